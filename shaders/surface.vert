#version 450
// The material system's vertex stage, for every technique: positions to clip space, the frame and both UV
// sets to the fragment stage and, for per-vertex coefficient sources (HEMI_SOURCE == HEMI_SOURCE_VERTEX),
// the vertex's K RGB coefficients (texel coefficient_offset + v*K + k of the source's buffer), packed.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "hemi/shared/bases.h"
#include "hemi/shared/surface.h"

layout(constant_id = HEMI_SPEC_K) const int K = 9;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv0;
layout(location = 4) in vec2 in_uv1;

layout(set = HEMI_SET_FRAME, binding = HEMI_FRAME_BINDING_UNIFORMS, std140) uniform Frame
{
    FrameUniforms frame;
};
layout(push_constant) uniform Push
{
    DrawPush draw;
};
#if HEMI_SOURCE == HEMI_SOURCE_VERTEX
layout(set = HEMI_SET_SOURCE, binding = HEMI_SOURCE_BINDING_COEFFICIENTS) uniform samplerBuffer coefficients;
#endif

// 9 RGB coefficients = 27 floats travel as 7 vec4.
layout(location = 0) out vec4 out_packed[7];
layout(location = 7) out vec2 out_uv0;
layout(location = 8) out vec2 out_uv1;
layout(location = 9) out vec3 out_normal;
layout(location = 10) out vec4 out_tangent;
layout(location = 11) out vec3 out_world;

void main()
{
    float f[28];
    [[unroll]] for (int i = 0; i < 28; ++i) f[i] = 0.0;
#if HEMI_SOURCE == HEMI_SOURCE_VERTEX
    [[unroll]] for (int k = 0; k < K; ++k)
    {
        vec3 c = texelFetch(coefficients, int(draw.coefficient_offset) + gl_VertexIndex * K + k).rgb;
        f[k * 3 + 0] = c.r;
        f[k * 3 + 1] = c.g;
        f[k * 3 + 2] = c.b;
    }
#endif
    [[unroll]] for (int i = 0; i < 7; ++i) out_packed[i] =
        vec4(f[i * 4], f[i * 4 + 1], f[i * 4 + 2], f[i * 4 + 3]);
    out_uv0 = in_uv0;
    out_uv1 = in_uv1;
    mat3 m = mat3(draw.model);
    out_normal = m * in_normal;
    out_tangent = vec4(m * in_tangent.xyz, in_tangent.w);
    const vec4 world = draw.model * vec4(in_position, 1.0);
    out_world = world.xyz;
    gl_Position = frame.view_projection * world;
}
