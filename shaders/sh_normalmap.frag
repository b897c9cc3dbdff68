#version 450
// Normal-mapped mesh lit by SH9 irradiance: out = albedo * E(n) / pi, with n the normal-map normal in world
// space (tangent frame per glTF: B = cross(N, T) * w, Gram-Schmidt re-orthogonalised per pixel).
// Attachment 1 carries (u, v, 0, 1) where the mesh covers the pixel, for tests and tools.
#extension GL_GOOGLE_include_directive : require
#include "hemi/shared/sh_normalmap.h"
#include "hemi/basis/sh9.glsl"

layout(set = 0, binding = HEMI_SH_NORMALMAP_BINDING_UNIFORMS, std140) uniform Uniforms
{
    ShNormalMapUniforms u;
};
layout(set = 0, binding = HEMI_SH_NORMALMAP_BINDING_NORMAL_MAP) uniform sampler2D normal_map;

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec4 in_tangent;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_aux;

const float kPi = 3.14159265358979;

void main()
{
    vec3 nt = normalize(texture(normal_map, in_uv).xyz * 2.0 - 1.0);
    vec3 N = normalize(in_normal);
    vec3 T = normalize(in_tangent.xyz - N * dot(N, in_tangent.xyz));
    vec3 B = cross(N, T) * in_tangent.w;
    vec3 n = normalize(T * nt.x + B * nt.y + N * nt.z);
    vec3 E = hemi_eval_sh9_rgb(u.irradiance, n);
    out_color = vec4(u.albedo.rgb * E / kPi, 1.0);
    out_aux = vec4(in_uv, 0.0, 1.0);
}
