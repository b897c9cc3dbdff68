// What the material system's surface shader hands every technique (shaders/surface.frag fills it): the
// surface inputs and the coefficients, in the coefficients' frame.
#ifndef HEMI_SURFACE_INPUTS_GLSL
#define HEMI_SURFACE_INPUTS_GLSL
#include "hemi/hemi.glsl"
#include "hemi/shared/surface.h"

const float kHemiPi = 3.14159265358979;

struct HemiSurface
{
    vec3 albedo;            // base colour factor x texture (1 in the lighting-only view)
    vec3 emissive;          // emissive factor x texture (0 in the lighting-only view)
    vec3 base_color_factor; // the material's factor alone
    vec3 n;                 // normal-map normal in the coefficients' frame (tangent or world)
    vec3 t;                 // the surface tangent (glTF's, the normal map's u) in the same frame
    vec3 bump;              // the normal-map slot's texel as stored (an SSBump map's weights), linear
    float occlusion;        // glTF's occlusion (1: none), for the techniques that apply it
    int basis;              // HEMI_BASIS_* of the coefficients
    int k;                  // how many coefficients
    vec3 c[HEMI_BASIS_MAX_SIZE];
    vec4 sep4_weights[9]; // the separable basis's weights (math::sep4_weights())
    // Dynamic lights in the coefficients' frame (tangent or world), at this pixel.
    int lights;
    vec3 l[HEMI_MAX_LIGHTS]; // unit, towards the light
    vec3 e[HEMI_MAX_LIGHTS]; // irradiance on a surface facing it (a point light's falloff applied)
    vec3 v;                  // unit, towards the eye
    float specular_exponent, specular_strength;
    float roughness; // the GGX coat's (0: none; then the Blinn-Phong term above)
    vec3 f0;
    bool world;    // the coefficients' frame is world space (an SH9 probe), not a tangent frame
    vec3 position; // the surface point in world space (a reflection probe's box projection)
};

// The dynamic lights' irradiance at normal n: sum_i E_i max(0, n . l_i).
vec3 hemi_dynamic_irradiance(HemiSurface s, vec3 n)
{
    vec3 sum = vec3(0.0);
    for (int i = 0; i < s.lights; ++i)
        sum += s.e[i] * max(dot(n, s.l[i]), 0.0);
    return sum;
}

// The dynamic lights' specular at normal n: with the GGX coat, its exact GGX, E f_r (n.l); else normalised
// Blinn-Phong, (m + 8) / (8 pi) (n.h)^m (n.l) E times the strength; summed.
vec3 hemi_dynamic_specular(HemiSurface s, vec3 n)
{
    vec3 sum = vec3(0.0);
    if (s.roughness > 0.0)
    {
        for (int i = 0; i < s.lights; ++i)
            sum += s.e[i] * hemi_ggx(n, s.l[i], s.v, s.roughness, s.f0);
        return sum;
    }
    if (s.specular_strength == 0.0)
        return sum;
    for (int i = 0; i < s.lights; ++i)
        sum += s.e[i] * hemi_blinn_phong(n, s.l[i], s.v, s.specular_exponent);
    return sum * s.specular_strength;
}

// The GGX coat's specular from the coefficients at normal n (0 without a coat): hemi_basis_specular, or for
// world-space SH9 (a probe) hemi_sh9_specular over the sphere.
vec3 hemi_coefficient_specular(HemiSurface s, vec3 n)
{
    if (!(s.roughness > 0.0))
        return vec3(0.0);
    if (s.world && s.basis == HEMI_BASIS_SH9)
    {
        vec3 e[9];
        for (int j = 0; j < 9; ++j)
            e[j] = s.c[j];
        return hemi_sh9_specular(e, n, s.v, s.roughness, s.f0, false);
    }
    return hemi_basis_specular(s.basis, s.k, s.c, n, s.v, s.roughness, s.f0, s.sep4_weights);
}

#endif
