// GLSL twin of engine/src/math/basis/separable.cpp: u_m(n) = sum_j y_j(n) W[j][m], with W (9 x 4, from the
// SVD, see hemi/math/separable_basis.h) supplied by the caller as 9 vec4 rows. At run time Sloan's shader
// reads the same functions from a 64 x 64 texture indexed by n.xy (math::separable_texture).
#ifndef HEMI_BASIS_SEP4_GLSL
#define HEMI_BASIS_SEP4_GLSL
#include "hemi/basis/sh9.glsl"
void hemi_eval_sep4(vec3 n, vec4 weights[9], out float b[4])
{
    float y[9];
    hemi_eval_sh9(n, y);
    vec4 s = vec4(0.0);
    for (int j = 0; j < 9; ++j)
        s += y[j] * weights[j];
    b[0] = s.x;
    b[1] = s.y;
    b[2] = s.z;
    b[3] = s.w;
}
// hemi-basis: id=8 name=sep4 size=4
void hemi_basis_sep4(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[4];
    hemi_eval_sep4(n, sep4_weights, t);
    for (int i = 0; i < 4; ++i)
        b[i] = t[i];
}

#endif
