#version 450
// CPCA transfer, step 2: per vertex, c_v,k = (mean . l)_k + sum_j w_v,j (vector_j . l)_k with its cluster's
// projections from step 1. Writes the same RGBA32F coefficient texels as the dense pass (texel v*K + k), so
// the materials cannot tell the two apart.
//
// Layout (built by render::CpcaTransferPass): vertices are grouped by cluster into "slots", each cluster's
// run padded to whole blocks, and the pass makes one dispatch per cluster with that cluster's (V + 1) x K
// projections bound as a uniform block (a dynamic offset), so every read of them has a constant index:
// scalar, uniform loads, as the lighting is in the dense pass.
// Weights are element-interleaved like the dense matrices (blocks of 32 slots: weight j of 4 consecutive
// slots is one RGBA32F texel), and one invocation computes 4 slots with vec4 arithmetic. Per vertex and
// frame this reads V weights instead of the dense pass's K * L matrix elements.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "hemi/shared/transfer.h"

layout(constant_id = 0) const uint K = 9;
layout(constant_id = 1) const uint V = 24;

layout(local_size_x = HEMI_TRANSFER_WORKGROUP_SIZE) in;

layout(set = 0, binding = HEMI_CPCA_BINDING_PROJECTED, std140) uniform Projected
{
    vec4 p[HEMI_TRANSFER_MAX_K * (HEMI_CPCA_MAX_VECTORS + 1)]; // row j (0: the mean) of output k at j*K + k
};
layout(set = 0, binding = HEMI_CPCA_BINDING_WEIGHTS) uniform samplerBuffer weights;
layout(set = 0, binding = HEMI_CPCA_BINDING_SLOTS, std430) readonly buffer Slots
{
    uvec4 slot_vertex[];
};
layout(set = 0, binding = HEMI_CPCA_BINDING_COEFFICIENTS, rgba32f) uniform writeonly imageBuffer coefficients;

layout(push_constant) uniform Push
{
    CpcaPush pc;
};

void main()
{
    if (gl_GlobalInvocationID.x >= pc.count)
        return;
    const uint invocation = pc.first + gl_GlobalInvocationID.x;
    const uvec4 ids = slot_vertex[invocation];
    const uint block = invocation / HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    const uint lane = invocation % HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    const int base = int(block * V * HEMI_TRANSFER_INVOCATIONS_PER_BLOCK + lane);
    vec4 w[V];
    [[unroll]] for (uint j = 0; j < V; ++j) w[j] =
        texelFetch(weights, base + int(j * HEMI_TRANSFER_INVOCATIONS_PER_BLOCK));

    [[unroll]] for (uint k = 0; k < K; ++k)
    {
        const vec3 m = p[k].rgb;
        vec4 r = vec4(m.r), g = vec4(m.g), b = vec4(m.b);
        [[unroll]] for (uint j = 0; j < V; ++j)
        {
            const vec3 q = p[(j + 1) * K + k].rgb;
            r += w[j] * q.r;
            g += w[j] * q.g;
            b += w[j] * q.b;
        }
        [[unroll]] for (uint s = 0; s < HEMI_TRANSFER_VERTICES_PER_INVOCATION; ++s)
        {
            if (ids[s] != 0xffffffffu)
                imageStore(coefficients, int(ids[s] * K + k), vec4(r[s], g[s], b[s], 0.0));
        }
    }
}
