// Heidrich & Seidel 1999, section 3.2: Banks' anisotropic model (Eq. 4, in Stalling's form) from its table
// (hemi-bake brdf --model banks: layer 0, r = diffuse, g = specular against acos(t.l) / pi, acos(t.v) / pi),
// per pixel with the tangent t made perpendicular to the normal-map normal, for the dynamic lights; plus the
// environment's diffuse map: colour = sum_i E_i (n.l_i) (kd albedo diffuse + ks specular) + kd albedo D(n) +
// emissive.
#ifndef HEMI_TECHNIQUE_BANKS_GLSL
#define HEMI_TECHNIQUE_BANKS_GLSL
#include "hemi/brdf/factored.glsl"
#include "hemi/surface/environment.glsl"
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=6 name=banks
vec3 hemi_technique_banks(HemiSurface s)
{
    vec3 sum = hemi_env_kd() * s.albedo * hemi_env_diffuse(s.position, s.n);
#if HEMI_SOURCE == HEMI_SOURCE_ENVIRONMENT
    for (int i = 0; i < s.lights; ++i)
    {
        const vec2 ds = hemi_banks_light(HEMI_ENV_BRDF_TABLES, hemi_env_table_size(), s.n, s.t, s.l[i], s.v);
        sum += s.e[i] * (hemi_env_kd() * s.albedo * ds.x + hemi_env_ks() * ds.y);
    }
#endif
    return sum + s.emissive;
}

#endif
