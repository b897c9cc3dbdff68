// Heidrich & Seidel 1999, section 3.1: the Torrance-Sparrow model from its two factor tables (hemi-bake brdf,
// layers 0 = F D, 1 = G / (pi cos beta) of the environment source's BRDF tables), per pixel at the normal-map
// normal, for the dynamic lights; a Lambertian term kd albedo / pi; and the environment's diffuse map for the
// light from everywhere else: colour = sum_i E_i (kd albedo (n.l_i) / pi + ks FD G) + kd albedo D(n) +
// emissive. World frame (the environment is in world space).
#ifndef HEMI_TECHNIQUE_FACTORED_GLSL
#define HEMI_TECHNIQUE_FACTORED_GLSL
#include "hemi/brdf/factored.glsl"
#include "hemi/surface/environment.glsl"
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=5 name=factored
vec3 hemi_technique_factored(HemiSurface s)
{
    vec3 sum = hemi_env_kd() * s.albedo * hemi_env_diffuse(s.position, s.n);
#if HEMI_SOURCE == HEMI_SOURCE_ENVIRONMENT
    for (int i = 0; i < s.lights; ++i)
    {
        const float nl = max(dot(s.n, s.l[i]), 0.0);
        const float spec =
            hemi_torrance_sparrow_table(HEMI_ENV_BRDF_TABLES, hemi_env_table_size(), s.n, s.l[i], s.v);
        sum += s.e[i] * (hemi_env_kd() * s.albedo * nl / kHemiPi + hemi_env_ks() * spec);
    }
#endif
    return sum + s.emissive;
}

#endif
