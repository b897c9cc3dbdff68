#version 450
// An engine's own fragment shader (a test's, not hemi's surface shader): its own descriptor sets (set 0 the
// view, set 1 the object, bindings of its own choosing) and its own composition of hemi's GLSL library for
// each technique. ENGINE_SOURCE as in engine_surface.vert. ENGINE_TECHNIQUE (a specialization constant): 0 =
// irradiance from a basis, 1 = radiosity normal mapping, 2 = SSBump, 3 = Torrance-Sparrow from its factored
// tables, 4 = Banks from its table, 5 = mirror reflection with Fresnel, 6 = glossy reflection.
#extension GL_GOOGLE_include_directive : require
#include "hemi/hemi.glsl"
#include "hemi/shared/surface.h" // EnvironmentUniforms: the values render::EnvironmentLighting::uniforms() gives

layout(constant_id = 0) const int kTechnique = 0;
layout(constant_id = 1) const int kBasis = 0;
layout(constant_id = 2) const int K = 9;

layout(set = 0, binding = 0, std140) uniform EngineView
{
    mat4 view_projection;
    vec4 eye;
    vec4 light_direction;
    vec4 light_irradiance;
    vec4 sep4_weights[9];
}
view;
layout(set = 1, binding = 3) uniform sampler2D albedo_map;
layout(set = 1, binding = 5) uniform sampler2D normal_map;
#if ENGINE_SOURCE == 1
layout(set = 1, binding = 7) uniform sampler2DArray lightmap;
layout(set = 1, binding = 13) uniform usampler2D lightmap_pages;
#elif ENGINE_SOURCE == 2
layout(set = 1, binding = 7, std140) uniform EngineProbe
{
    vec4 sh[9];
}
probe;
#elif ENGINE_SOURCE == 3
layout(set = 1, binding = 7, std140) uniform EngineEnvironment
{
    EnvironmentUniforms env;
};
layout(set = 1, binding = 8) uniform sampler2DArray mirror_map;
layout(set = 1, binding = 9) uniform sampler2DArray glossy_map;
layout(set = 1, binding = 10) uniform sampler2DArray diffuse_map;
layout(set = 1, binding = 11) uniform sampler2D fresnel_table;
layout(set = 1, binding = 12) uniform sampler2DArray brdf_tables;
#endif

layout(location = 0) in vec4 in_coefficients[7];
layout(location = 7) in vec2 in_uv0;
layout(location = 8) in vec2 in_uv1;
layout(location = 9) in vec3 in_normal;
layout(location = 10) in vec4 in_tangent;
layout(location = 11) in vec3 in_world;

layout(location = 0) out vec4 out_color;

const float kPi = 3.14159265358979;

void main()
{
    const vec3 albedo = texture(albedo_map, in_uv0).rgb;
    const vec3 bump = texture(normal_map, in_uv0).xyz;
    const HemiTangentFrame frame = hemi_tangent_frame(in_normal, in_tangent);
    const vec3 nt = hemi_normal_map_normal(bump, 1.0);
    const vec3 l = view.light_direction.xyz;
    const vec3 e = view.light_irradiance.rgb;
    vec3 color = vec3(0.0);
#if ENGINE_SOURCE == 0 || ENGINE_SOURCE == 1
    // Tangent-frame coefficients: a PRT vertex's, a lightmap texel's.
    vec3 c[HEMI_BASIS_MAX_SIZE];
#if ENGINE_SOURCE == 0
    hemi_unpack_coefficients(in_coefficients, K, c);
#else
    hemi_lightmap_coefficients(lightmap, lightmap_pages, in_uv1, K, c);
#endif
    const vec3 lt = hemi_to_tangent(frame, l);
    if (kTechnique == 0)
        color = albedo *
                (hemi_basis_irradiance(kBasis, K, c, nt, view.sep4_weights) + e * max(dot(nt, lt), 0.0)) /
                kPi;
    else if (kTechnique == 1)
        color = albedo * (hemi_rnm_irradiance(nt, c[0], c[1], c[2]) + e * max(dot(nt, lt), 0.0)) / kPi;
    else if (kTechnique == 2)
        color =
            albedo * (hemi_ssbump_irradiance(bump, c[0], c[1], c[2]) + e * hemi_ssbump_light(bump, lt)) / kPi;
#elif ENGINE_SOURCE == 2
    // A world-space SH9 probe.
    vec3 c[HEMI_BASIS_MAX_SIZE];
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        c[i] = i < 9 ? probe.sh[i].rgb : vec3(0.0);
    const vec3 n = normalize(hemi_from_tangent(frame, nt));
    color = albedo * (hemi_sh9_irradiance(c, n) + e * max(dot(n, l), 0.0)) / kPi;
#elif ENGINE_SOURCE == 3
    // Heidrich & Seidel, world frame.
    const vec3 n = normalize(hemi_from_tangent(frame, nt));
    const vec3 v = normalize(view.eye.xyz - in_world);
    const vec3 r0 = env.world_to_env[0].xyz, r1 = env.world_to_env[1].xyz, r2 = env.world_to_env[2].xyz;
    const float kd = env.material.x, ks = env.material.y;
    const vec3 diffuse = hemi_parabolic_lookup(diffuse_map, env.extents.z, hemi_env_direction(r0, r1, r2, n));
    const vec3 lambert = e * max(dot(n, l), 0.0) / kPi;
    if (kTechnique == 3)
        color = kd * albedo * (diffuse + lambert) +
                e * ks * hemi_torrance_sparrow_table(brdf_tables, env.tables.x, n, l, v);
    else if (kTechnique == 4)
    {
        const vec2 ds = hemi_banks_light(brdf_tables, env.tables.x, n, frame.t, l, v);
        color = kd * albedo * diffuse + e * (kd * albedo * ds.x + ks * ds.y);
    }
    else if (kTechnique == 5)
    {
        const vec3 r = hemi_reflect(n, v);
        const float f = hemi_fresnel_lookup(fresnel_table, env.tables.y, env.material.z, max(dot(n, v), 0.0));
        color = f * hemi_parabolic_lookup(mirror_map, env.extents.x, hemi_env_direction(r0, r1, r2, r)) +
                kd * albedo * (diffuse + lambert);
    }
    else if (kTechnique == 6)
    {
        const vec3 r = hemi_reflect(n, v);
        color = ks * hemi_parabolic_lookup(glossy_map, env.extents.y, hemi_env_direction(r0, r1, r2, r)) +
                kd * albedo * (diffuse + lambert);
    }
#endif
    out_color = vec4(color, 1.0);
}
