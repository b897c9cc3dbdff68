#version 450
// Looks a lightmap up at a list of UVs with the GLSL library's functions (hemi/lib/coefficients.glsl):
// specialization constant 0 picks the lookup (0: paged linear, 1: paged bicubic, 2: plain linear, 3: plain
// bicubic), 1 the coefficient count K. out[i * K + k] = coefficient k at uvs[i]. A test shader
// (tests/shaders/).
#extension GL_GOOGLE_include_directive : require
#include "hemi/lib/coefficients.glsl"

layout(constant_id = 0) const int kLookup = 0;
layout(constant_id = 1) const int K = 1;
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform sampler2DArray pages;
layout(set = 0, binding = 1) uniform usampler2D page_table;
layout(set = 0, binding = 2) uniform sampler2DArray plain;
layout(set = 0, binding = 3, std430) readonly buffer Uvs
{
    vec2 uvs[];
};
layout(set = 0, binding = 4, std430) writeonly buffer Values
{
    vec4 values[];
};
layout(push_constant) uniform Push
{
    uint count;
}
pc;

void main()
{
    const uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    vec3 c[HEMI_BASIS_MAX_SIZE];
    if (kLookup == 0)
        hemi_lightmap_coefficients(pages, page_table, uvs[i], K, c);
    else if (kLookup == 1)
        hemi_lightmap_coefficients_bicubic(pages, page_table, uvs[i], K, c);
    else if (kLookup == 2)
        hemi_lightmap_coefficients(plain, uvs[i], K, c);
    else
        hemi_lightmap_coefficients_bicubic(plain, uvs[i], K, c);
    for (int k = 0; k < K; ++k)
        values[i * K + k] = vec4(c[k], 0.0);
}
