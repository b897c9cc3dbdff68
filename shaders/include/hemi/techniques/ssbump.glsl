// Self-shadowed radiosity normal mapping (Green 2007, Listing 2): the material's normal-map slot holds an
// SSBump map (hemi-bake ssbump, normalised convention: the weights w_i of Valve's directions with their
// directional occlusion), the lightmap's "rnm" output the three colours L_i (in c[0..2]).
// colour = albedo * sum_i w_i L_i / pi + emissive. A flat texel (1/3 each) gives what the rnm technique gives
// with a flat normal map.
#ifndef HEMI_TECHNIQUE_SSBUMP_GLSL
#define HEMI_TECHNIQUE_SSBUMP_GLSL
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=3 name=ssbump
vec3 hemi_technique_ssbump(HemiSurface s)
{
    const vec3 e = s.bump.x * s.c[0] + s.bump.y * s.c[1] + s.bump.z * s.c[2];
    return s.albedo * e / kHemiPi + s.emissive;
}

#endif
