// What the material system's surface shader hands every technique (shaders/surface.frag fills it): the
// surface inputs and the coefficients, in the coefficients' frame.
#ifndef HEMI_SURFACE_INPUTS_GLSL
#define HEMI_SURFACE_INPUTS_GLSL
#include "hemi/basis/all.glsl"

const float kHemiPi = 3.14159265358979;

struct HemiSurface
{
    vec3 albedo;            // base colour factor x texture (1 in the lighting-only view)
    vec3 emissive;          // emissive factor x texture (0 in the lighting-only view)
    vec3 base_color_factor; // the material's factor alone
    vec3 n;                 // normal-map normal in the coefficients' frame (tangent or world)
    vec3 bump;              // the normal-map slot's texel as stored (an SSBump map's weights), linear
    int basis;              // HEMI_BASIS_* of the coefficients
    int k;                  // how many coefficients
    vec3 c[HEMI_BASIS_MAX_SIZE];
    vec4 sep4_weights[9];   // the separable basis's weights (math::sep4_weights())
};

#endif
