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
#include "hemi/surface/surface_inputs.glsl"
#include "hemi/techniques/rnm.glsl"

// hemi-technique: id=3 name=ssbump
vec3 hemi_technique_ssbump(HemiSurface s)
{
    vec3 e = s.bump.x * s.c[0] + s.bump.y * s.c[1] + s.bump.z * s.c[2];
    for (int i = 0; i < s.lights; ++i)
    {
        const vec3 projected = clamp(
            vec3(dot(kHemiRnmBasis[0], s.l[i]), dot(kHemiRnmBasis[1], s.l[i]), dot(kHemiRnmBasis[2], s.l[i])),
            0.0, 1.0);
        e += s.e[i] * (HEMI_RNM_SQRT_3 * dot(s.bump, projected));
    }
    const vec3 reconstructed =
        s.bump.x * kHemiRnmBasis[0] + s.bump.y * kHemiRnmBasis[1] + s.bump.z * kHemiRnmBasis[2];
    const vec3 n = dot(reconstructed, reconstructed) > 0.0 ? normalize(reconstructed) : vec3(0.0, 0.0, 1.0);
    return s.albedo * e / kHemiPi + hemi_dynamic_specular(s, n) + s.emissive;
}

#endif
