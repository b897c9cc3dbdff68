// Irradiance from a basis (Sloan 2006 PRT, classic PRT, Habel 2010 lightmaps, SH probes):
// E(n) = sum_k c_k b_k(n), colour = albedo * E / pi + emissive.
#ifndef HEMI_TECHNIQUE_IRRADIANCE_GLSL
#define HEMI_TECHNIQUE_IRRADIANCE_GLSL
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=0 name=irradiance
vec3 hemi_technique_irradiance(HemiSurface s)
{
    return s.albedo * hemi_basis_irradiance(s.basis, s.k, s.c, s.n, s.sep4_weights) / kHemiPi + s.emissive;
}

#endif
