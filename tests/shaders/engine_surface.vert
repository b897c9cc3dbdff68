#version 450
// An engine's own vertex shader (a test's, not hemi's): its own vertex streams (positions alone in stream 0;
// normal, tangent and both UV sets in stream 1), its own sets and push constants, and hemi's GLSL library for
// the normal matrix and, for PRT objects, the per-vertex coefficients. ENGINE_SOURCE: 0 = a PRT object's
// per-vertex coefficients, 1 = a lightmap, 2 = an SH9 probe, 3 = an environment.
#extension GL_GOOGLE_include_directive : require
#include "hemi/hemi.glsl"

layout(constant_id = 2) const int K = 9;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv0;
layout(location = 4) in vec2 in_uv1;

layout(set = 0, binding = 0, std140) uniform EngineView
{
    mat4 view_projection;
    vec4 eye;
    vec4 light_direction; // towards the light, world
    vec4 light_irradiance;
    vec4 sep4_weights[9];
}
view;
#if ENGINE_SOURCE == 0
layout(set = 1, binding = 7) uniform samplerBuffer prt_coefficients;
#endif
layout(push_constant) uniform EnginePush
{
    mat4 model;
    int coefficient_offset;
}
object;

layout(location = 0) out vec4 out_coefficients[7];
layout(location = 7) out vec2 out_uv0;
layout(location = 8) out vec2 out_uv1;
layout(location = 9) out vec3 out_normal;
layout(location = 10) out vec4 out_tangent;
layout(location = 11) out vec3 out_world;

void main()
{
    vec3 c[HEMI_BASIS_MAX_SIZE];
#if ENGINE_SOURCE == 0
    hemi_vertex_coefficients(prt_coefficients, object.coefficient_offset + gl_VertexIndex * K, K, c);
#else
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        c[i] = vec3(0.0);
#endif
    hemi_pack_coefficients(c, out_coefficients);
    const mat3 m = mat3(object.model);
    out_normal = hemi_normal_matrix(m) * in_normal;
    out_tangent = hemi_transform_tangent(m, in_tangent);
    out_uv0 = in_uv0;
    out_uv1 = in_uv1;
    const vec4 world = object.model * vec4(in_position, 1.0);
    out_world = world.xyz;
    gl_Position = view.view_projection * world;
}
