// SH9 (bands 0-2) at a unit direction: the GLSL twin of hemi::math::sh9_eval.
#ifndef HEMI_BASIS_SH9_GLSL
#define HEMI_BASIS_SH9_GLSL
#include "hemi/shared/sh_constants.h"

void hemi_eval_sh9(vec3 n, out float b[9])
{
    b[0] = float(HEMI_SH_Y00);
    b[1] = -float(HEMI_SH_Y1) * n.y;
    b[2] = float(HEMI_SH_Y1) * n.z;
    b[3] = -float(HEMI_SH_Y1) * n.x;
    b[4] = float(HEMI_SH_Y2) * n.x * n.y;
    b[5] = -float(HEMI_SH_Y2) * n.y * n.z;
    b[6] = float(HEMI_SH_Y20) * (3.0 * n.z * n.z - 1.0);
    b[7] = -float(HEMI_SH_Y2) * n.x * n.z;
    b[8] = float(HEMI_SH_Y22) * (n.x * n.x - n.y * n.y);
}

// Sum of coefficient * basis: with irradiance coefficients (A_l L_lm) this is E(n).
vec3 hemi_eval_sh9_rgb(vec4 coefficients[9], vec3 n)
{
    float b[9];
    hemi_eval_sh9(n, b);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < 9; ++i)
        sum += coefficients[i].rgb * b[i];
    return sum;
}
// hemi-basis: id=0 name=sh9 size=9
void hemi_basis_sh9(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[9];
    hemi_eval_sh9(n, t);
    for (int i = 0; i < 9; ++i)
        b[i] = t[i];
}

// Linear SH least-squares fitted on the hemisphere (Habel & Wimmer 2010 Sec. 4.1): the first 4 SH functions.
// hemi-basis: id=1 name=sh4ls size=4
void hemi_basis_sh4ls(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[9];
    hemi_eval_sh9(n, t);
    for (int i = 0; i < 4; ++i)
        b[i] = t[i];
}

#endif
