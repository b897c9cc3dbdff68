#version 450
// The engine's own main-pass fragment shader: the baked lighting from hemi's GLSL library, plus what is the
// engine's alone (the level's mixed sun lit at run time with its shadow map, a GGX coat, fog) into an HDR
// target that the post pass exposes and tonemaps.
// ENGINE_SOURCE: 1 = the lightmapped level (technique: 0 = H6 near / H4 far, 1 = SSBump), 2 = a PRT object's
// per-vertex coefficients, 3 = a probe-lit sphere (SH9 from the level's probes, per pixel), 4 = Heidrich &
// Seidel's glossy object (prefiltered parabolic maps).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "hemi/hemi.glsl"

layout(constant_id = 0) const int kTechnique = 0;
layout(constant_id = 1) const int K = 4;
layout(constant_id = 2) const int kBasis = 0;

layout(set = 0, binding = 1) uniform sampler2DShadow shadow_map;
layout(set = 0, binding = 2) uniform samplerBuffer level_probes; // io::probe_texels of the level's probes
#if ENGINE_SOURCE == 1 || ENGINE_SOURCE == 2
layout(set = 1, binding = 0) uniform sampler2D base_color; // sRGB
layout(set = 1, binding = 1) uniform sampler2D normal_map; // or an SSBump map (technique 1)
#endif
#if ENGINE_SOURCE == 1
// hemi's paged lightmaps: each output's pages and page table (render::TexelCoefficients).
layout(set = 1, binding = 2) uniform sampler2DArray h6_maps;
layout(set = 1, binding = 3) uniform sampler2DArray h4_maps;
layout(set = 1, binding = 5) uniform sampler2DArray rnm_maps;
layout(set = 1, binding = 8) uniform usampler2D h6_table;
layout(set = 1, binding = 9) uniform usampler2D h4_table;
layout(set = 1, binding = 10) uniform usampler2D rnm_table;
layout(set = 1, binding = 11) uniform sampler2DArray shadowmask; // the mixed lights' (h4's slots and table)
#elif ENGINE_SOURCE == 4
layout(set = 1, binding = 6) uniform sampler2DArray glossy_map;
layout(set = 1, binding = 7) uniform sampler2DArray diffuse_map;
#endif

layout(location = 0) in vec4 in_coefficients[7];
layout(location = 7) in vec2 in_uv0;
layout(location = 8) in vec2 in_uv1;
layout(location = 9) in vec3 in_normal;
layout(location = 10) in vec4 in_tangent;
layout(location = 11) in vec3 in_world;

layout(location = 0) out vec4 out_color;

const float kPi = 3.14159265358979;

// The sun's shadow map at `world`: 3 x 3 PCF; 1 outside the map.
float sun_shadow_map(vec3 world)
{
    const vec4 p = frame.sun_view_projection * vec4(world, 1.0);
    const vec3 ndc = p.xyz / p.w;
    if (!all(lessThan(abs(ndc.xy), vec2(1.0))) || ndc.z >= 1.0)
        return 1.0;
    const vec2 uv = ndc.xy * 0.5 + 0.5, texel = 1.0 / vec2(textureSize(shadow_map, 0));
    float lit = 0.0;
    for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x)
            lit += texture(shadow_map, vec3(uv + vec2(x, y) * texel, ndc.z));
    return lit / 9.0;
}

// The mixed sun's irradiance at `world` on a surface facing it (0 when the level's sun is baked or off). Its
// static shadow (`baked`: the level's shadowmask channel, or a dynamic object's occlusion from the probes)
// meets the shadow map within the shadow distance as the darker of the two (hemi_mixed_shadow); beyond it
// the static shadow alone. The map holds what faces the sun (hemi's shadow pipelines cull back faces, and the
// level's walls and ceiling are one-sided, facing in): the static shadow keeps a dynamic object inside the
// room dark where the ceiling hides the sun.
vec3 sun_light(vec3 world, float baked)
{
    if (frame.sun_direction.w == 0.0)
        return vec3(0.0);
    float fade = 0.0;
    if (frame.shadow.z != 0.0)
        fade =
            1.0 - smoothstep(frame.shadow.x - frame.shadow.y, frame.shadow.x, distance(frame.eye.xyz, world));
    const float map = fade > 0.0 ? sun_shadow_map(world) : 1.0;
    return frame.sun_irradiance.rgb * hemi_mixed_shadow(baked, map, fade);
}

void main()
{
    const vec3 l = frame.sun_direction.xyz, v = normalize(frame.eye.xyz - in_world);
    const float roughness = frame.mode.z != 0 ? object.material.x : 0.0;
    const vec3 f0 = vec3(object.material.y);
#if ENGINE_SOURCE == 1
    // The level: the sun's static shadow is its channel of the shadowmask.
    const float baked = hemi_shadowmask_channel(hemi_lightmap_shadowmask(shadowmask, h4_table, in_uv1),
                                                int(frame.sun_irradiance.w));
    const vec3 light = sun_light(in_world, baked);
#elif ENGINE_SOURCE == 3
    // A probe-lit object, per pixel: the level's probes at the surface point lifted 5 cm off it (in the
    // level's frame), blended over the probes that see it; their occlusion of the sun is its static shadow.
    const vec3 n = normalize(in_normal);
    vec3 probe_sh[HEMI_BASIS_MAX_SIZE];
    vec4 probe_occlusion;
    hemi_probe_irradiance(level_probes, (frame.world_to_level * vec4(in_world + 0.05 * n, 1.0)).xyz, probe_sh,
                          probe_occlusion);
    const int channel = int(frame.sun_irradiance.w);
    const vec3 light = sun_light(in_world, channel >= 0 ? probe_occlusion[channel] : 1.0);
#else
    const vec3 light = sun_light(in_world, object.material.z);
#endif
    vec4 sep4[9]; // no basis here uses SEP4's weights
    for (int i = 0; i < 9; ++i)
        sep4[i] = vec4(0.0);
    vec3 color = vec3(0.0), specular = vec3(0.0);
#if ENGINE_SOURCE == 1 || ENGINE_SOURCE == 2
    vec3 albedo = object.albedo.rgb * texture(base_color, in_uv0).rgb;
    if (frame.mode.y != 0)
        albedo = vec3(1.0);
    const vec3 bump = texture(normal_map, in_uv0).xyz;
    const HemiTangentFrame tf = hemi_tangent_frame(in_normal, in_tangent);
    const vec3 lt = hemi_to_tangent(tf, l), vt = hemi_to_tangent(tf, v);
    vec3 c[HEMI_BASIS_MAX_SIZE];
#if ENGINE_SOURCE == 1
    if (kTechnique == 1)
    {
        // SSBump (Green 2007, Listing 2): the map's three weights over Valve's basis, light included.
        hemi_lightmap_coefficients(rnm_maps, rnm_table, in_uv1, 3, c);
        const vec3 e = hemi_ssbump_irradiance(bump, c[0], c[1], c[2]) + light * hemi_ssbump_light(bump, lt);
        color = albedo * e / kPi;
    }
    else
    {
        // Habel & Wimmer's shader level of detail: H6 near the eye, H4 beyond.
        const vec3 nt = hemi_normal_map_normal(bump, 1.0);
        const bool near =
            frame.mode.x == 1 || (frame.mode.x == 0 && distance(frame.eye.xyz, in_world) < frame.eye.w);
        // Under a GGX coat (the polished floor), the specular the directional lightmap holds (its dominant
        // light's highlight and the rest's reflection: hemi_basis_specular) and the mixed sun's, exact.
        vec3 e;
        if (near)
        {
            hemi_lightmap_coefficients(h6_maps, h6_table, in_uv1, 6, c);
            e = hemi_basis_irradiance(HEMI_BASIS_H6, 6, c, nt, sep4);
            if (roughness > 0.0)
                specular = hemi_basis_specular(HEMI_BASIS_H6, 6, c, nt, vt, roughness, f0, sep4);
        }
        else
        {
            hemi_lightmap_coefficients(h4_maps, h4_table, in_uv1, 4, c);
            e = hemi_basis_irradiance(HEMI_BASIS_H4, 4, c, nt, sep4);
            if (roughness > 0.0)
                specular = hemi_basis_specular(HEMI_BASIS_H4, 4, c, nt, vt, roughness, f0, sep4);
        }
        if (roughness > 0.0)
            specular += light * hemi_ggx(nt, lt, vt, roughness, f0);
        color = albedo * (e + light * max(dot(nt, lt), 0.0)) / kPi + specular;
    }
#else
    // PRT: this frame's coefficients at the vertices (hemi's transfer pass), in the tangent frame.
    hemi_unpack_coefficients(in_coefficients, K, c);
    const vec3 nt = hemi_normal_map_normal(bump, 1.0);
    color = albedo * (hemi_basis_irradiance(kBasis, K, c, nt, sep4) + light * max(dot(nt, lt), 0.0)) / kPi;
#endif
#elif ENGINE_SOURCE == 3
    // The probes' SH9 is in the level's frame: the normal goes there.
    const vec3 albedo = frame.mode.y != 0 ? vec3(1.0) : object.albedo.rgb;
    const vec3 level_normal = normalize(mat3(frame.world_to_level) * n);
    color = albedo * (hemi_sh9_irradiance(probe_sh, level_normal) + light * max(dot(n, l), 0.0)) / kPi;
#elif ENGINE_SOURCE == 4
    // Heidrich & Seidel: a Phong-prefiltered glossy reflection and the diffuse map of the same environment,
    // here the level's reflection probe.
    const vec3 n = normalize(in_normal);
    const vec3 r = hemi_reflect(n, v);
    const vec3 r0 = frame.env.world_to_env[0].xyz, r1 = frame.env.world_to_env[1].xyz,
               r2 = frame.env.world_to_env[2].xyz;
    const float kd = frame.env.material.x, ks = frame.env.material.y;
    const vec3 albedo = frame.mode.y != 0 ? vec3(1.0) : object.albedo.rgb;
    const vec3 diffuse =
        hemi_parabolic_lookup(diffuse_map, frame.env.extents.z, hemi_env_direction(r0, r1, r2, n));
    // The level's reflection probe, box-projected from the shaded point (its maps are in the level's frame).
    vec3 reflected = hemi_env_direction(r0, r1, r2, r);
    if (frame.reflection_centre.w != 0.0)
        reflected = hemi_box_projected_direction((frame.world_to_level * vec4(in_world, 1.0)).xyz, reflected,
                                                 frame.reflection_min.xyz, frame.reflection_max.xyz,
                                                 frame.reflection_centre.xyz);
    const vec3 glossy = hemi_parabolic_lookup(glossy_map, frame.env.extents.y, reflected);
    color = ks * glossy + kd * albedo * (diffuse + light * max(dot(n, l), 0.0) / kPi);
#endif
    // The coat's light alone (--specular-only).
    if (frame.mode.y == 2)
        color = specular;
    // Exponential fog over the distance from the eye.
    else if (frame.fog.w > 0.0)
        color = mix(frame.fog.rgb, color, exp(-frame.fog.w * distance(frame.eye.xyz, in_world)));
    out_color = vec4(color, 1.0);
}
