#version 450
// The engine's main-pass vertex shader: hemi's vertex layout (GpuMesh::layout(), so hemi's meshes bind as
// they are), the engine's own sets and push constants, and hemi's GLSL library for the normal matrix and a
// PRT object's per-vertex coefficients (ENGINE_SOURCE 2).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "hemi/hemi.glsl"

layout(constant_id = 1) const int K = 4;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv0;
layout(location = 4) in vec2 in_uv1;

#if ENGINE_SOURCE == 2
layout(set = 1, binding = 4) uniform samplerBuffer prt_coefficients;
#endif

layout(location = 0) out vec4 out_coefficients[7];
layout(location = 7) out vec2 out_uv0;
layout(location = 8) out vec2 out_uv1;
layout(location = 9) out vec3 out_normal;
layout(location = 10) out vec4 out_tangent;
layout(location = 11) out vec3 out_world;

void main()
{
    vec3 c[HEMI_BASIS_MAX_SIZE];
#if ENGINE_SOURCE == 2
    hemi_vertex_coefficients(prt_coefficients, object.index.x + gl_VertexIndex * K, K, c);
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
    precise vec4 world = object.model * vec4(in_position, 1.0);
    precise vec4 clip = frame.view_projection * world;
    out_world = world.xyz;
    gl_Position = clip;
}
