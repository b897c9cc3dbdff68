// Every hemispherical basis behind one entry point: hemi_eval_basis(HEMI_BASIS_*, n, sep4_weights, b) writes
// the basis's functions into b[0 .. size) and zeroes the rest; sep4_weights is read only by the separable
// basis (math::sep4_weights()). With a constant id the compiler keeps only one case.
#ifndef HEMI_BASIS_ALL_GLSL
#define HEMI_BASIS_ALL_GLSL
#include "hemi/shared/bases.h"
#include "hemi/basis/sh9.glsl"
#include "hemi/basis/hl2.glsl"
#include "hemi/basis/h_basis.glsl"
#include "hemi/basis/sal.glsl"
#include "hemi/basis/zernike.glsl"
#include "hemi/basis/sep4.glsl"

void hemi_eval_basis(int id, vec3 n, vec4 sep4_weights[9], out float b[HEMI_BASIS_MAX_SIZE])
{
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        b[i] = 0.0;
    if (id == HEMI_BASIS_SH9)
    {
        float t[9];
        hemi_eval_sh9(n, t);
        for (int i = 0; i < 9; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_SH4LS)
    {
        float t[9];
        hemi_eval_sh9(n, t);
        for (int i = 0; i < 4; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_HL2)
    {
        float t[3];
        hemi_eval_hl2(n, t);
        for (int i = 0; i < 3; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_H4)
    {
        float t[4];
        hemi_eval_h4(n, t);
        for (int i = 0; i < 4; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_H6)
    {
        float t[6];
        hemi_eval_h6(n, t);
        for (int i = 0; i < 6; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_SAL4)
    {
        float t[4];
        hemi_eval_sal4(n, t);
        for (int i = 0; i < 4; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_ZERNIKE3)
    {
        float t[3];
        hemi_eval_zernike3(n, t);
        for (int i = 0; i < 3; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_ZERNIKE6)
    {
        float t[6];
        hemi_eval_zernike6(n, t);
        for (int i = 0; i < 6; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_SEP4)
    {
        float t[4];
        hemi_eval_sep4(n, sep4_weights, t);
        for (int i = 0; i < 4; ++i) b[i] = t[i];
    }
    else if (id == HEMI_BASIS_VERTEX_IRRADIANCE)
    {
        b[0] = 1.0;
    }
}
#endif
