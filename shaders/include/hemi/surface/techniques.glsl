// The techniques of the material system, one function each, called by surface.frag's one main(). A
// technique receives the surface inputs and the coefficients and returns linear radiance.
#ifndef HEMI_SURFACE_TECHNIQUES_GLSL
#define HEMI_SURFACE_TECHNIQUES_GLSL
#include "hemi/basis/all.glsl"

const float kHemiPi = 3.14159265358979;

// Irradiance from a basis (Sloan 2006 PRT, classic PRT, Habel 2010 lightmaps, SH probes):
// E(n) = sum_k c_k b_k(n), colour = albedo * E / pi + emissive.
vec3 hemi_technique_irradiance(int basis, int k_count, vec3 n, vec3 c[HEMI_BASIS_MAX_SIZE], vec4 sep4_weights[9],
                               vec3 albedo, vec3 emissive)
{
    float b[HEMI_BASIS_MAX_SIZE];
    hemi_eval_basis(basis, n, sep4_weights, b);
    vec3 e = vec3(0.0);
    [[unroll]] for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k)
    {
        if (k < k_count)
            e += c[k] * b[k];
    }
    return albedo * e / kHemiPi + emissive;
}

#endif
