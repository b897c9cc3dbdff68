// Irradiance from a basis (Sloan 2006 PRT, classic PRT, Habel 2010 lightmaps, SH probes):
// E(n) = sum_k c_k b_k(n), colour = albedo * E / pi + emissive.
#ifndef HEMI_TECHNIQUE_IRRADIANCE_GLSL
#define HEMI_TECHNIQUE_IRRADIANCE_GLSL
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=0 name=irradiance
vec3 hemi_technique_irradiance(HemiSurface s)
{
    float b[HEMI_BASIS_MAX_SIZE];
    hemi_eval_basis(s.basis, s.n, s.sep4_weights, b);
    vec3 e = vec3(0.0);
    [[unroll]] for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k)
    {
        if (k < s.k)
            e += s.c[k] * b[k];
    }
    return s.albedo * e / kHemiPi + s.emissive;
}

#endif
