// GLSL twin of engine/src/math/basis/h_basis.cpp: Habel & Wimmer 2010 H-basis (H4 = first four of H6).
#ifndef HEMI_BASIS_H_GLSL
#define HEMI_BASIS_H_GLSL
void hemi_eval_h6(vec3 n, out float b[6])
{
    const float k0 = 0.398942280401433, k1 = 0.690988298942671, k2 = 1.545096808092680;
    b[0] = k0;
    b[1] = -k1 * n.y;
    b[2] = k1 * (2.0 * n.z - 1.0);
    b[3] = -k1 * n.x;
    b[4] = k2 * n.x * n.y;
    b[5] = 0.5 * k2 * (n.x * n.x - n.y * n.y);
}
void hemi_eval_h4(vec3 n, out float b[4])
{
    const float k0 = 0.398942280401433, k1 = 0.690988298942671;
    b[0] = k0;
    b[1] = -k1 * n.y;
    b[2] = k1 * (2.0 * n.z - 1.0);
    b[3] = -k1 * n.x;
}
// hemi-basis: id=3 name=h4 size=4
void hemi_basis_h4(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[4];
    hemi_eval_h4(n, t);
    for (int i = 0; i < 4; ++i)
        b[i] = t[i];
}

// hemi-basis: id=4 name=h6 size=6
void hemi_basis_h6(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[6];
    hemi_eval_h6(n, t);
    for (int i = 0; i < 6; ++i)
        b[i] = t[i];
}

#endif
