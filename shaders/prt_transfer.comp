#version 450
// The per-frame PRT transfer multiply (Sloan 2006, Sec. 2/3): c_v = T_v * l for every vertex, where T_v is
// the K x L transfer matrix of vertex v and l the RGB lighting vector in SH (L coefficients).
//
// Why the layout is what it is: the pass reads every matrix once per frame and is bandwidth-bound on a GPU.
// Matrices are element-interleaved in blocks of 32 vertices (see hemi/shared/transfer.h), so
//  - on a GPU, the lanes of a subgroup read consecutive 16-byte texels: every load is fully coalesced;
//  - on lavapipe (llvmpipe), where a storage-buffer load with a per-lane address becomes a scalar loop
//    over the lanes, a uniform-texel-buffer fetch takes the vectorised gather path, and each fetch brings
//    4 useful floats (the same element of 4 vertices) that feed 12 FMAs with no lane shuffling;
//  - one texel buffer view addresses 2^27 texels on common hardware (2 GiB of RGBA32F), far beyond the
//    128 MiB storage-buffer range limit of lavapipe; larger sets are split into segments by the host.
// K and L are specialization constants and the loops are unrolled, so the lighting is read with constant
// indices (scalar, uniform loads) and the accumulators of one output row (3 x vec4) stay in registers.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "hemi/shared/transfer.h"

layout(constant_id = 0) const uint K = 9;
layout(constant_id = 1) const uint L = 25;

layout(local_size_x = HEMI_TRANSFER_WORKGROUP_SIZE) in;

layout(set = 0, binding = HEMI_TRANSFER_BINDING_MATRICES) uniform samplerBuffer matrices;
layout(set = 0, binding = HEMI_TRANSFER_BINDING_LIGHTING, std140) uniform Lighting
{
    vec4 light[HEMI_TRANSFER_MAX_L]; // rgb = coefficient j of the lighting, a unused
};
// Output: coefficient k of vertex v is texel v*K + k (rgb, a = 0), ready for a vertex shader's texelFetch.
layout(set = 0, binding = HEMI_TRANSFER_BINDING_COEFFICIENTS,
       rgba32f) uniform writeonly imageBuffer coefficients;

layout(push_constant) uniform Push
{
    TransferPush pc;
};

void main()
{
    uint invocation = gl_GlobalInvocationID.x;
    uint first = invocation * HEMI_TRANSFER_VERTICES_PER_INVOCATION;
    if (first >= pc.vertex_count)
        return;
    uint block = invocation / HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    uint lane = invocation % HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    int base = int(block * K * L * HEMI_TRANSFER_INVOCATIONS_PER_BLOCK + lane);
    uint valid = min(pc.vertex_count - first, uint(HEMI_TRANSFER_VERTICES_PER_INVOCATION));

    [[unroll]] for (uint k = 0; k < K; ++k)
    {
        vec4 r = vec4(0.0), g = vec4(0.0), b = vec4(0.0);
        [[unroll]] for (uint j = 0; j < L; ++j)
        {
            vec4 m = texelFetch(matrices, base + int((k * L + j) * HEMI_TRANSFER_INVOCATIONS_PER_BLOCK));
            vec3 lj = light[j].rgb;
            r += m * lj.r;
            g += m * lj.g;
            b += m * lj.b;
        }
        int out_base = int(first * K + k);
        [[unroll]] for (uint q = 0; q < HEMI_TRANSFER_VERTICES_PER_INVOCATION; ++q)
        {
            if (q < valid)
                imageStore(coefficients, out_base + int(q * K), vec4(r[q], g[q], b[q], 0.0));
        }
    }
}
