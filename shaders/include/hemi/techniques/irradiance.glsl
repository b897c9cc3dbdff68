// Irradiance from a basis (Sloan 2006 PRT, classic PRT, Habel 2010 lightmaps, SH probes):
// E(n) = sum_k c_k b_k(n), colour = albedo * (E + sum_k E_k max(0, n . l_k)) / pi + specular + emissive,
// with the frame's dynamic lights k at the normal-map normal (a lightmap's mixed lights times their
// shadowmask channel) and their specular (Blinn-Phong, or exact GGX under the frame's GGX coat; the ggx
// technique adds the coefficients' own specular).
#ifndef HEMI_TECHNIQUE_IRRADIANCE_GLSL
#define HEMI_TECHNIQUE_IRRADIANCE_GLSL
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=0 name=irradiance
vec3 hemi_technique_irradiance(HemiSurface s)
{
    return s.albedo *
               (hemi_basis_irradiance(s.basis, s.k, s.c, s.n, s.sep4_weights) +
                hemi_dynamic_irradiance(s, s.n)) /
               kHemiPi +
           hemi_dynamic_specular(s, s.n) + s.emissive;
}

#endif
