// hemi's GLSL library: irradiance from K coefficients of one of hemi's bases (math::bases(): SH9, SH4LS, HL2,
// H4, H6, SAL4, Zernike, SEP4; or classic PRT's vertex irradiance) at a unit normal in the coefficients'
// frame: E(n) = sum_k c_k b_k(n). The same function for a lightmap texel (Habel & Wimmer 2010), a PRT
// vertex (Sloan 2006, tangent frame) and a world-space SH9 probe. docs/glsl.md.
#ifndef HEMI_LIB_IRRADIANCE_GLSL
#define HEMI_LIB_IRRADIANCE_GLSL
#include "hemi/basis/all.glsl"
#include "hemi/lib/coefficients.glsl"

// `basis` is a HEMI_BASIS_* id (hemi/shared/bases_generated.h; a constant or a specialization constant lets
// the compiler keep one basis). `sep4_weights` are math::sep4_weights()' 9 rows, read by HEMI_BASIS_SEP4
// only (any value otherwise).
vec3 hemi_basis_irradiance(int basis, int k, vec3 c[HEMI_BASIS_MAX_SIZE], vec3 n, vec4 sep4_weights[9])
{
    float b[HEMI_BASIS_MAX_SIZE];
    hemi_eval_basis(basis, n, sep4_weights, b);
    vec3 e = vec3(0.0);
    HEMI_UNROLL for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
    {
        if (i < k)
            e += c[i] * b[i];
    }
    return e;
}

// SH9 irradiance (A_l L_lm, world space) at a unit normal: the probe form, no separable weights needed.
vec3 hemi_sh9_irradiance(vec3 c[HEMI_BASIS_MAX_SIZE], vec3 n)
{
    float b[9];
    hemi_eval_sh9(n, b);
    vec3 e = vec3(0.0);
    for (int i = 0; i < 9; ++i)
        e += c[i] * b[i];
    return e;
}

#endif
