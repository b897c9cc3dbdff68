// GLSL twin of engine/src/math/basis/sal.cpp: the first four shifted associated Legendre functions.
#ifndef HEMI_BASIS_SAL_GLSL
#define HEMI_BASIS_SAL_GLSL
void hemi_eval_sal4(vec3 n, out float b[4])
{
    const float k0 = 0.398942280401433, k1 = 0.690988298942671, k2 = 1.381976597885342;
    float z = max(n.z, 0.0);
    float s = sqrt(z / (1.0 + z));
    b[0] = k0;
    b[1] = -k2 * s * n.y;
    b[2] = k1 * (2.0 * n.z - 1.0);
    b[3] = -k2 * s * n.x;
}
// hemi-basis: id=5 name=sal4 size=4
void hemi_basis_sal4(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[4];
    hemi_eval_sal4(n, t);
    for (int i = 0; i < 4; ++i)
        b[i] = t[i];
}

#endif
