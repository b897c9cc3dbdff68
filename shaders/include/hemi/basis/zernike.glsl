// GLSL twin of engine/src/math/basis/zernike.cpp: hemispherical Zernike polynomials (equal-area map).
#ifndef HEMI_BASIS_ZERNIKE_GLSL
#define HEMI_BASIS_ZERNIKE_GLSL
void hemi_eval_zernike6(vec3 n, out float b[6])
{
    float inv = 1.0 / (1.0 + max(n.z, 0.0));
    float r = sqrt(inv);
    b[0] = 0.398942280401433;
    b[1] = 0.797884560802865 * n.x * r;
    b[2] = 0.797884560802865 * n.y * r;
    b[3] = 0.690988298942671 * (1.0 - 2.0 * n.z);
    b[4] = 0.977205023805840 * (n.x * n.x - n.y * n.y) * inv;
    b[5] = 0.977205023805840 * 2.0 * n.x * n.y * inv;
}
void hemi_eval_zernike3(vec3 n, out float b[3])
{
    float r = sqrt(1.0 / (1.0 + max(n.z, 0.0)));
    b[0] = 0.398942280401433;
    b[1] = 0.797884560802865 * n.x * r;
    b[2] = 0.797884560802865 * n.y * r;
}
// hemi-basis: id=6 name=zernike3 size=3
void hemi_basis_zernike3(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[3];
    hemi_eval_zernike3(n, t);
    for (int i = 0; i < 3; ++i)
        b[i] = t[i];
}

// hemi-basis: id=7 name=zernike6 size=6
void hemi_basis_zernike6(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[6];
    hemi_eval_zernike6(n, t);
    for (int i = 0; i < 6; ++i)
        b[i] = t[i];
}

#endif
