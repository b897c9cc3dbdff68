// hemi's GLSL library: radiosity normal mapping and self-shadowed bump maps (Green 2007). The lightmap
// baker's "rnm" output holds three colours L_i, the irradiance towards each of Valve's tangent-space
// directions B_i (kHemiRnmBasis); a normal map blends them (Listing 1), an SSBump texel's weights w_i do
// (Listing 2). Plain functions; no descriptors. docs/glsl.md.
#ifndef HEMI_LIB_RNM_GLSL
#define HEMI_LIB_RNM_GLSL
#include "hemi/shared/rnm.h"

const vec3 kHemiRnmBasis[3] = vec3[3](vec3(HEMI_RNM_SQRT_2_3, 0.0, HEMI_RNM_INV_SQRT_3),
                                      vec3(-HEMI_RNM_INV_SQRT_6, HEMI_RNM_INV_SQRT_2, HEMI_RNM_INV_SQRT_3),
                                      vec3(-HEMI_RNM_INV_SQRT_6, -HEMI_RNM_INV_SQRT_2, HEMI_RNM_INV_SQRT_3));

// Listing 1's weights at a tangent-space normal: D_i = saturate(n . B_i)^2 / sum_j saturate(n . B_j)^2 (0 for
// a normal that faces away from all three).
vec3 hemi_rnm_weights(vec3 n)
{
    vec3 dp =
        clamp(vec3(dot(n, kHemiRnmBasis[0]), dot(n, kHemiRnmBasis[1]), dot(n, kHemiRnmBasis[2])), 0.0, 1.0);
    dp *= dp;
    const float sum = dp.x + dp.y + dp.z;
    return sum > 0.0 ? dp / sum : vec3(0.0);
}

// Listing 1: the lightmap's three colours blended at the normal-map normal n (tangent space).
vec3 hemi_rnm_irradiance(vec3 n, vec3 l0, vec3 l1, vec3 l2)
{
    const vec3 d = hemi_rnm_weights(n);
    return d.x * l0 + d.y * l1 + d.z * l2;
}

// Listing 2: an SSBump texel's weights w (as stored, linear) times the three colours.
vec3 hemi_ssbump_irradiance(vec3 w, vec3 l0, vec3 l1, vec3 l2)
{
    return w.x * l0 + w.y * l1 + w.z * l2;
}

// A dynamic light on an SSBump texel (Green 2007, section 3): the light's tangent-space direction l projected
// onto the three directions, saturate(B_i . l), dotted with the weights, times sqrt 3 so that a flat texel
// (1/3 each) under a light straight above receives the light's full irradiance. Multiply by its irradiance.
float hemi_ssbump_light(vec3 w, vec3 l)
{
    const vec3 projected =
        clamp(vec3(dot(kHemiRnmBasis[0], l), dot(kHemiRnmBasis[1], l), dot(kHemiRnmBasis[2], l)), 0.0, 1.0);
    return HEMI_RNM_SQRT_3 * dot(w, projected);
}

// The normal an SSBump texel stands for, normalize(sum_i w_i B_i) (+z for zero weights): for specular terms.
vec3 hemi_ssbump_normal(vec3 w)
{
    const vec3 r = w.x * kHemiRnmBasis[0] + w.y * kHemiRnmBasis[1] + w.z * kHemiRnmBasis[2];
    return dot(r, r) > 0.0 ? normalize(r) : vec3(0.0, 0.0, 1.0);
}

#endif
