#version 450
// CPCA transfer, step 2: per vertex, c_v,k = (mean . l)_k + sum_j w_v,j (vector_j . l)_k with the cluster's
// projections from step 1. Writes the same RGBA32F coefficient texels as the dense pass (texel v*K + k), so
// the materials cannot tell the two apart.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "hemi/shared/transfer.h"

layout(constant_id = 0) const uint K = 9;
layout(constant_id = 1) const uint V = 24;

layout(local_size_x = HEMI_TRANSFER_WORKGROUP_SIZE) in;

layout(set = 0, binding = HEMI_CPCA_BINDING_PROJECTED, std430) readonly buffer Projected { vec4 projected[]; };
layout(set = 0, binding = HEMI_CPCA_BINDING_WEIGHTS, std430) readonly buffer Weights { float weights[]; };
layout(set = 0, binding = HEMI_CPCA_BINDING_CLUSTERS, std430) readonly buffer Clusters { uint cluster_of[]; };
layout(set = 0, binding = HEMI_CPCA_BINDING_COEFFICIENTS, rgba32f) uniform writeonly imageBuffer coefficients;

layout(push_constant) uniform Push
{
    CpcaPush pc;
};

void main()
{
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.count)
        return;
    uint base = cluster_of[v] * (V + 1) * K;
    float w[V];
    [[unroll]] for (uint j = 0; j < V; ++j)
        w[j] = weights[v * V + j];
    [[unroll]] for (uint k = 0; k < K; ++k)
    {
        vec3 c = projected[base + k].rgb;
        [[unroll]] for (uint j = 0; j < V; ++j)
            c += w[j] * projected[base + (j + 1) * K + k].rgb;
        imageStore(coefficients, int(v * K + k), vec4(c, 0.0));
    }
}
