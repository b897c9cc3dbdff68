#version 450
// The material system's vertex stage, for every technique: positions to clip space, the frame and both UV
// sets to the fragment stage and, for per-vertex coefficient sources (HEMI_SOURCE == HEMI_SOURCE_VERTEX),
// the vertex's K RGB coefficients (texel coefficient_offset + v*K + k of the source's buffer), packed.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define HEMI_UNROLL [[unroll]]
#include "hemi/hemi.glsl"
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
// Instanced draws' per-instance values (DrawPush::instanced).
layout(set = HEMI_SET_FRAME, binding = HEMI_FRAME_BINDING_INSTANCES, std430) readonly buffer Instances
{
    DrawPush instances[];
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
// This draw's (or instance's) coefficient offset and draw id, and its lightmap rectangle.
layout(location = 12) flat out uvec2 out_ids;
layout(location = 13) flat out vec4 out_lightmap_scale_offset;

void main()
{
    mat4 model = draw.model;
    uint coefficient_offset = draw.coefficient_offset, draw_id = draw.draw_id;
    vec4 lightmap_scale_offset = draw.lightmap_scale_offset;
    if (draw.instanced != 0u)
    {
        model = instances[gl_InstanceIndex].model;
        coefficient_offset = instances[gl_InstanceIndex].coefficient_offset;
        lightmap_scale_offset = instances[gl_InstanceIndex].lightmap_scale_offset;
        if (instances[gl_InstanceIndex].draw_id != 0u)
            draw_id = instances[gl_InstanceIndex].draw_id;
    }
    out_ids = uvec2(coefficient_offset, draw_id);
    out_lightmap_scale_offset = lightmap_scale_offset;
    vec3 c[HEMI_BASIS_MAX_SIZE];
#if HEMI_SOURCE == HEMI_SOURCE_VERTEX
    hemi_vertex_coefficients(coefficients, int(coefficient_offset) + gl_VertexIndex * K, K, c);
#else
    HEMI_UNROLL for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k) c[k] = vec3(0.0);
#endif
    hemi_pack_coefficients(c, out_packed);
    out_uv0 = in_uv0;
    out_uv1 = in_uv1;
    // Normals through the inverse transpose (non-uniform scale, mirrors), tangents with the surface.
    const mat3 m = mat3(model);
    out_normal = hemi_normal_matrix(m) * in_normal;
    out_tangent = hemi_transform_tangent(m, in_tangent);
    // Every pass of a key runs this same code (a colour pass tests EQUAL against a depth prepass), and so
    // does an engine's vertex shader that calls it: hemi_clip_position's products are precise. (`invariant
    // gl_Position` would say the same, but Mesa warns about the decoration glslang puts on gl_PerVertex's
    // member.)
    gl_Position = hemi_clip_position(frame.view_projection, model, in_position, out_world);
}
