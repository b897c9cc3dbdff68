#version 450
// An engine's own fragment shader built against the installed GLSL library alone (hemi_GLSL_INCLUDE_DIR):
// every function of hemi/hemi.glsl called with the engine's own bindings.
#extension GL_GOOGLE_include_directive : require
#include "hemi/hemi.glsl"

layout(set = 3, binding = 0) uniform sampler2DArray lightmap;
layout(set = 3, binding = 1) uniform samplerBuffer prt;
layout(set = 3, binding = 2) uniform sampler2DArray parabolic;
layout(set = 3, binding = 3) uniform sampler2D fresnel;
layout(set = 3, binding = 4) uniform sampler2DArray brdf;
layout(set = 3, binding = 5, std140) uniform Sep4
{
    vec4 sep4_weights[9];
};

layout(location = 0) in vec3 in_normal;
layout(location = 1) in vec4 in_tangent;
layout(location = 2) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

void main()
{
    const HemiTangentFrame f = hemi_tangent_frame(in_normal, in_tangent);
    const vec3 n = hemi_normal_map_normal(vec3(0.5, 0.5, 1.0), 1.0);
    vec3 c[HEMI_BASIS_MAX_SIZE];
    hemi_lightmap_coefficients(lightmap, in_uv, 6, c);
    vec3 e = hemi_basis_irradiance(HEMI_BASIS_H6, 6, c, n, sep4_weights);
    hemi_vertex_coefficients(prt, 0, 9, c);
    vec4 packed[7];
    hemi_pack_coefficients(c, packed);
    hemi_unpack_coefficients(packed, 9, c);
    e += hemi_sh9_irradiance(c, hemi_from_tangent(f, n));
    e += hemi_rnm_irradiance(n, c[0], c[1], c[2]) + hemi_ssbump_irradiance(n, c[0], c[1], c[2]);
    e += vec3(hemi_ssbump_light(n, hemi_to_tangent(f, vec3(0, 0, 1)))) * hemi_ssbump_normal(n);
    const vec3 v = vec3(0, 0, 1), l = normalize(vec3(1, 0, 1));
    e += hemi_parabolic_lookup(parabolic, 32.0,
                               hemi_env_direction(vec3(1, 0, 0), vec3(0, 1, 0), vec3(0, 0, 1), n));
    e += hemi_fresnel_lookup(fresnel, 256.0, 0.5, dot(n, v)) *
         hemi_parabolic_lookup(parabolic, 32.0, hemi_reflect(n, v));
    e += hemi_torrance_sparrow_table(brdf, 64.0, n, l, v) + hemi_banks_light(brdf, 64.0, n, f.t, l, v).x;
    e += hemi_blinn_phong(n, l, v, 32.0);
    const mat3 m = mat3(2.0);
    out_color = vec4(e + hemi_normal_matrix(m) * n + hemi_transform_tangent(m, in_tangent).xyz, 1.0);
}
