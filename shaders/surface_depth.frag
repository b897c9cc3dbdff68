#version 450
// The material system's fragment stage of depth and shadow passes, for alpha-tested materials only (opaque
// ones have no fragment stage there): the base colour's alpha against the material's alphaCutoff, the same
// test as surface.frag's, and nothing written but depth.
#extension GL_GOOGLE_include_directive : require
#include "hemi/shared/surface.h"

layout(set = HEMI_SET_MATERIAL, binding = HEMI_MATERIAL_BINDING_UNIFORMS, std140) uniform Material
{
    MaterialUniforms material;
};
layout(set = HEMI_SET_MATERIAL, binding = HEMI_MATERIAL_BINDING_BASE_COLOR) uniform sampler2D base_color;

// The vertex stage's whole interface (surface.vert), so that every output it writes is consumed.
layout(location = 0) in vec4 in_packed[7];
layout(location = 7) in vec2 in_uv0;
layout(location = 8) in vec2 in_uv1;
layout(location = 9) in vec3 in_normal;
layout(location = 10) in vec4 in_tangent;
layout(location = 11) in vec3 in_world;
layout(location = 12) flat in uvec2 in_ids;
layout(location = 13) flat in vec4 in_lightmap_scale_offset;

void main()
{
    vec3 uv = vec3(material.texcoord.x == 1u ? in_uv1 : in_uv0, 1.0);
    uv = vec3(dot(material.uv_transform[0].xyz, uv), dot(material.uv_transform[1].xyz, uv), 1.0);
    if (material.base_color_factor.a * texture(base_color, uv.xy).a < material.occlusion.y)
        discard;
}
