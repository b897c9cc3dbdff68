#version 450
// Normal-mapped mesh lit by SH9 irradiance: vertex stage (world-space frame to the fragment stage).
#extension GL_GOOGLE_include_directive : require
#include "hemi/shared/sh_normalmap.h"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;

layout(set = 0, binding = HEMI_SH_NORMALMAP_BINDING_UNIFORMS, std140) uniform Uniforms
{
    ShNormalMapUniforms u;
};

layout(location = 0) out vec3 out_normal;
layout(location = 1) out vec4 out_tangent;
layout(location = 2) out vec2 out_uv;

void main()
{
    mat3 m = mat3(u.model);
    out_normal = m * in_normal;
    out_tangent = vec4(m * in_tangent.xyz, in_tangent.w);
    out_uv = in_uv;
    gl_Position = u.view_projection * (u.model * vec4(in_position, 1.0));
}
