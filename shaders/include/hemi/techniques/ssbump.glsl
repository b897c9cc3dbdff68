// Self-shadowed radiosity normal mapping (Green 2007, Listing 2): the material's normal-map slot holds an
// SSBump map (hemi-bake ssbump, normalised convention: the weights w_i of Valve's directions with their
// directional occlusion), the lightmap's "rnm" output the three colours L_i (in c[0..2]).
// colour = albedo * sum_i w_i L_i / pi + emissive. A flat texel (1/3 each) gives what the rnm technique gives
// with a flat normal map. Dynamic lights (Green 2007, section 3): each light's direction l projected onto
// the three directions, saturate(B_i . l), dotted with the texel's weights, times sqrt 3 so that a flat
// texel under a light straight above gets its full irradiance E (as n . l would give):
// albedo * E * sqrt(3) sum_i w_i saturate(B_i . l) / pi, and the specular term at the reconstructed
// normal normalize(sum_i w_i B_i).
#ifndef HEMI_TECHNIQUE_SSBUMP_GLSL
#define HEMI_TECHNIQUE_SSBUMP_GLSL
#include "hemi/lib/rnm.glsl"
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=3 name=ssbump
vec3 hemi_technique_ssbump(HemiSurface s)
{
    vec3 e = hemi_ssbump_irradiance(s.bump, s.c[0], s.c[1], s.c[2]);
    for (int i = 0; i < s.lights; ++i)
        e += s.e[i] * hemi_ssbump_light(s.bump, s.l[i]);
    return s.albedo * e / kHemiPi + hemi_dynamic_specular(s, hemi_ssbump_normal(s.bump)) + s.emissive;
}

#endif
