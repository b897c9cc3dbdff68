// Radiosity normal mapping (Green 2007, Listing 1: Source's original bump mapping): three lightmap colours
// L_i, the irradiance towards each of Valve's directions B_i (the lightmap baker's "rnm" output, in c[0..2]),
// blended by the normal-map normal's weights D_i = saturate(n . B_i)^2 / sum_j saturate(n . B_j)^2.
// colour = albedo * (sum_i D_i L_i + sum_k E_k max(0, n . l_k)) / pi + specular + emissive, with the dynamic
// lights k at the normal-map normal n (tangent space) and their Blinn-Phong term at n.
#ifndef HEMI_TECHNIQUE_RNM_GLSL
#define HEMI_TECHNIQUE_RNM_GLSL
#include "hemi/lib/rnm.glsl"
#include "hemi/surface/surface_inputs.glsl"

// E: the lightmap's colours blended at the normal-map normal, plus the dynamic lights there.
vec3 hemi_rnm_surface_irradiance(HemiSurface s)
{
    // Dynamic lights at the normal-map normal.
    return hemi_rnm_irradiance(s.n, s.c[0], s.c[1], s.c[2]) + hemi_dynamic_irradiance(s, s.n);
}

// hemi-technique: id=2 name=rnm
vec3 hemi_technique_rnm(HemiSurface s)
{
    return s.albedo * hemi_rnm_surface_irradiance(s) / kHemiPi + hemi_dynamic_specular(s, s.n) + s.emissive;
}

#endif
