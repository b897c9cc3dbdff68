#version 450
// PRT material, vertex stage: fetches the vertex's K RGB basis coefficients written by the transfer pass
// (texel v*K + k) and hands them, packed, to the fragment stage, which evaluates the basis per pixel.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "hemi/shared/prt_material.h"

layout(constant_id = 0) const int kBasis = 0;
layout(constant_id = 1) const int K = 9;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;

layout(set = 0, binding = HEMI_PRT_MATERIAL_BINDING_UNIFORMS, std140) uniform Uniforms
{
    PrtMaterialUniforms u;
};
layout(set = 0, binding = HEMI_PRT_MATERIAL_BINDING_COEFFICIENTS) uniform samplerBuffer coefficients;

layout(location = 0) out vec4 out_packed[HEMI_PRT_MATERIAL_PACKED_VEC4];
layout(location = HEMI_PRT_MATERIAL_PACKED_VEC4) out vec2 out_uv;

void main()
{
    float f[HEMI_PRT_MATERIAL_PACKED_VEC4 * 4];
    [[unroll]] for (int i = 0; i < HEMI_PRT_MATERIAL_PACKED_VEC4 * 4; ++i)
        f[i] = 0.0;
    [[unroll]] for (int k = 0; k < K; ++k)
    {
        vec3 c = texelFetch(coefficients, gl_VertexIndex * K + k).rgb;
        f[k * 3 + 0] = c.r;
        f[k * 3 + 1] = c.g;
        f[k * 3 + 2] = c.b;
    }
    [[unroll]] for (int i = 0; i < HEMI_PRT_MATERIAL_PACKED_VEC4; ++i)
        out_packed[i] = vec4(f[i * 4], f[i * 4 + 1], f[i * 4 + 2], f[i * 4 + 3]);
    out_uv = in_uv;
    gl_Position = u.view_projection * (u.model * vec4(in_position, 1.0));
}
