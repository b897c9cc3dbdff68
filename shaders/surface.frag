#version 450
// The material system's one fragment main, for every technique: fetch the surface inputs (normal-map
// normal, base colour, emissive, each through its UV set and KHR_texture_transform), fetch the coefficients
// from their source (HEMI_SOURCE variant), put the normal in the coefficients' frame, call the technique
// (hemi_shade, generated from shaders/include/hemi/techniques/). What a technique ignores, the compiler
// drops. Everything but its descriptors and the technique switch is hemi's GLSL library (hemi/hemi.glsl),
// which engines' own shaders call the same way. HEMI_AUX = 1 adds colour attachment 1 = (u, v, draw id, 1)
// where the mesh covers the pixel (hemi's OffscreenTarget; tests and tools read it).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define HEMI_UNROLL [[unroll]]
#include "hemi/shared/surface.h"
#include "hemi/surface/techniques.glsl"

layout(constant_id = HEMI_SPEC_BASIS) const int kBasis = 0;
layout(constant_id = HEMI_SPEC_K) const int K = 9;
layout(constant_id = HEMI_SPEC_FRAME) const int kFrame = HEMI_FRAME_TANGENT;
layout(constant_id = HEMI_SPEC_TECHNIQUE) const int kTechnique = HEMI_TECHNIQUE_IRRADIANCE;
layout(constant_id = HEMI_SPEC_DOUBLE_SIDED) const int kDoubleSided = 0;
layout(constant_id = HEMI_SPEC_ALPHA) const int kAlpha = HEMI_ALPHA_OPAQUE;
layout(constant_id = HEMI_SPEC_LIGHTMAP_FILTER) const int kLightmapFilter = HEMI_LIGHTMAP_FILTER_LINEAR;

layout(set = HEMI_SET_FRAME, binding = HEMI_FRAME_BINDING_UNIFORMS, std140) uniform Frame
{
    FrameUniforms frame;
};
layout(set = HEMI_SET_MATERIAL, binding = HEMI_MATERIAL_BINDING_UNIFORMS, std140) uniform Material
{
    MaterialUniforms material;
};
layout(set = HEMI_SET_MATERIAL,
       binding = HEMI_MATERIAL_BINDING_BASE_COLOR) uniform sampler2D base_color; // sRGB
layout(set = HEMI_SET_MATERIAL, binding = HEMI_MATERIAL_BINDING_NORMAL) uniform sampler2D normal_map;
layout(set = HEMI_SET_MATERIAL,
       binding = HEMI_MATERIAL_BINDING_EMISSIVE) uniform sampler2D emissive_map; // sRGB
layout(set = HEMI_SET_MATERIAL,
       binding = HEMI_MATERIAL_BINDING_OCCLUSION) uniform sampler2D occlusion_map; // linear r
#if HEMI_SOURCE == HEMI_SOURCE_TEXEL
layout(set = HEMI_SET_SOURCE,
       binding = HEMI_SOURCE_BINDING_COEFFICIENTS) uniform sampler2DArray coefficient_maps;
layout(set = HEMI_SET_SOURCE, binding = HEMI_SOURCE_BINDING_PAGE_TABLE) uniform usampler2D page_table;
layout(set = HEMI_SET_SOURCE, binding = HEMI_SOURCE_BINDING_SHADOWMASK) uniform sampler2DArray shadowmask;
#elif HEMI_SOURCE == HEMI_SOURCE_UNIFORM
// Every probe of every frame in flight (render::ProbeBuffer); this draw's from vec4 in_ids.x.
layout(set = HEMI_SET_SOURCE, binding = HEMI_SOURCE_BINDING_COEFFICIENTS, std430) readonly buffer Probes
{
    vec4 probes[];
};
#endif

layout(location = 0) in vec4 in_packed[7];
layout(location = 7) in vec2 in_uv0;
layout(location = 8) in vec2 in_uv1;
layout(location = 9) in vec3 in_normal;
layout(location = 10) in vec4 in_tangent;
layout(location = 11) in vec3 in_world;
layout(location = 12) flat in uvec2 in_ids; // coefficient offset, draw id (the draw's or its instance's)
layout(location = 13) flat in vec4 in_lightmap_scale_offset;

layout(location = 0) out vec4 out_color;
#if HEMI_AUX
layout(location = 1) out vec4 out_aux;
#endif

vec2 material_uv(uint set, int transform)
{
    vec3 uv = vec3(set == 1u ? in_uv1 : in_uv0, 1.0);
    return vec2(dot(material.uv_transform[transform * 2].xyz, uv),
                dot(material.uv_transform[transform * 2 + 1].xyz, uv));
}

void main()
{
    vec4 albedo = material.base_color_factor * texture(base_color, material_uv(material.texcoord.x, 0));
    const float alpha = albedo.a;
    if (kAlpha == HEMI_ALPHA_MASK && alpha < material.occlusion.y)
        discard;
    // Most materials emit nothing: skip the fetch (a branch uniform across the draw).
    vec3 emissive = vec3(0.0);
    if (any(notEqual(material.emissive_factor.rgb, vec3(0.0))))
        emissive =
            material.emissive_factor.rgb * texture(emissive_map, material_uv(material.texcoord.z, 2)).rgb;
    const vec3 bump = texture(normal_map, material_uv(material.texcoord.y, 1)).xyz;
    const vec3 nt = hemi_normal_map_normal(bump, material.emissive_factor.a);
    if (frame.options.x != 0.0)
    {
        albedo = vec4(1.0);
        emissive = vec3(0.0);
    }

    vec3 c[HEMI_BASIS_MAX_SIZE];
    // The mixed lights' static shadows: a lightmap's shadowmask, a probe's occlusion; read only when a frame
    // light is a mixed one (a branch uniform across the draw).
    vec4 mask = vec4(1.0);
    bool mixed = false;
    for (int i = 0; i < min(int(frame.options.y), HEMI_MAX_LIGHTS); ++i)
        mixed = mixed || frame.light_irradiance[i].w > 0.0;
#if HEMI_SOURCE == HEMI_SOURCE_VERTEX
    hemi_unpack_coefficients(in_packed, K, c);
#elif HEMI_SOURCE == HEMI_SOURCE_TEXEL
    const vec2 lightmap_uv = in_uv1 * in_lightmap_scale_offset.xy + in_lightmap_scale_offset.zw;
    if (kLightmapFilter == HEMI_LIGHTMAP_FILTER_BICUBIC)
        hemi_lightmap_coefficients_bicubic(coefficient_maps, page_table, lightmap_uv, K, c);
    else
        hemi_lightmap_coefficients(coefficient_maps, page_table, lightmap_uv, K, c);
    if (mixed)
        mask = hemi_lightmap_shadowmask(shadowmask, page_table, lightmap_uv);
#else
    HEMI_UNROLL for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k)
    {
        c[k] = vec3(0.0);
#if HEMI_SOURCE == HEMI_SOURCE_UNIFORM
        if (k < K)
            c[k] = probes[in_ids.x + uint(k)].rgb;
#endif
    }
#if HEMI_SOURCE == HEMI_SOURCE_UNIFORM
    // A probe's occlusion of the mixed lights' channels: the fourth components of its first four vec4s.
    if (mixed)
        mask = vec4(probes[in_ids.x].w, probes[in_ids.x + 1u].w, probes[in_ids.x + 2u].w,
                    probes[in_ids.x + 3u].w);
#endif
#endif

    // glTF frame (hemi_tangent_frame): a double-sided surface seen from behind is lit as the other side (its
    // normal flipped).
    vec3 N = in_normal;
    if (kDoubleSided != 0 && !gl_FrontFacing)
        N = -N;
    const HemiTangentFrame tf = hemi_tangent_frame(N, in_tangent);
    const vec3 n = kFrame == HEMI_FRAME_WORLD ? normalize(hemi_from_tangent(tf, nt)) : nt;
    // World vectors in the coefficients' frame.
    const mat3 to_frame = kFrame == HEMI_FRAME_WORLD ? mat3(1.0) : transpose(mat3(tf.t, tf.b, tf.n));

    HemiSurface s;
    s.position = in_world;
    s.albedo = albedo.rgb;
    s.emissive = emissive;
    s.base_color_factor = material.base_color_factor.rgb;
    s.n = n;
    s.t = kFrame == HEMI_FRAME_WORLD ? tf.t : vec3(1.0, 0.0, 0.0);
    s.bump = bump;
    s.basis = kBasis;
    s.k = K;
    s.c = c;
    s.sep4_weights = frame.sep4_weights;
    // glTF: occlusion = 1 + strength (r - 1); the compiler drops the fetch from techniques that ignore it.
    s.occlusion =
        1.0 + material.occlusion.x * (texture(occlusion_map, material_uv(material.texcoord.w, 3)).r - 1.0);
    s.lights = min(int(frame.options.y), HEMI_MAX_LIGHTS);
    // Only the frame's lights (a bound uniform across the draw): a technique reads l[i], e[i] for i < lights.
    for (int i = 0; i < s.lights; ++i)
    {
        const vec4 p = frame.light_position[i];
        const vec3 to = p.w == 0.0 ? p.xyz : p.xyz - in_world;
        const float d2 = max(dot(to, to), 1e-12);
        s.l[i] = to_frame * (to * inversesqrt(d2));
        // glTF's falloffs of a point or spot light (a range window, a spot's cone), and a mixed light's
        // shadow.
        const vec4 spot = frame.light_spot[i];
        float falloff = p.w == 0.0 ? 1.0 : hemi_range_window(sqrt(d2), spot.w) / d2;
        if (p.w != 0.0 && dot(spot.xyz, spot.xyz) > 0.0)
            falloff *= hemi_spot_cone(dot(spot.xyz, -to * inversesqrt(d2)), frame.light_cone[i].x,
                                      frame.light_cone[i].y);
        s.e[i] = frame.light_irradiance[i].rgb * falloff *
                 hemi_shadowmask_channel(mask, int(frame.light_irradiance[i].w) - 1);
    }
    s.v = to_frame * normalize(frame.eye.xyz - in_world);
    s.specular_exponent = frame.options.z;
    s.specular_strength = frame.options.w;
    s.roughness = frame.glossy.x;
    s.f0 = vec3(frame.glossy.y);
    s.world = kFrame == HEMI_FRAME_WORLD;
    out_color = vec4(hemi_shade(kTechnique, s), kAlpha == HEMI_ALPHA_BLEND ? alpha : 1.0);
#if HEMI_AUX
    out_aux = vec4(in_uv0, float(in_ids.y), 1.0);
#endif
}
