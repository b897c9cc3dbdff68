// The material's textures lit by the frame's dynamic lights alone, no precomputed lighting:
// colour = albedo * sum_k E_k max(0, n . l_k) / pi + emissive, at the normal-map normal. It fetches what
// every technique fetches (base colour, normal map, emissive where the factor is not zero) and nothing else,
// so hemi-bench measures each technique's own cost (basis evaluation, coefficient fetches and interpolation)
// against it; also what a surface lit only by an engine's dynamic lights looks like.
#ifndef HEMI_TECHNIQUE_LAMBERT_GLSL
#define HEMI_TECHNIQUE_LAMBERT_GLSL
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=9 name=lambert
vec3 hemi_technique_lambert(HemiSurface s)
{
    return s.albedo * hemi_dynamic_irradiance(s, s.n) / kHemiPi + s.emissive;
}

#endif
