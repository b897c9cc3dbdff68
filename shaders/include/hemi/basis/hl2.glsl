// GLSL twin of engine/src/math/basis/hl2.cpp: Half-Life 2 basis, orthonormal on the hemisphere.
#ifndef HEMI_BASIS_HL2_GLSL
#define HEMI_BASIS_HL2_GLSL
void hemi_eval_hl2(vec3 n, out float b[3])
{
    const float k = 0.690988298942671;
    const float a = 0.408248290463863, s2 = 0.707106781186548, c = 0.577350269189626;
    b[0] = k * (-a * n.x - s2 * n.y + c * n.z);
    b[1] = k * (-a * n.x + s2 * n.y + c * n.z);
    b[2] = k * (0.816496580927726 * n.x + c * n.z);
}
// hemi-basis: id=2 name=hl2 size=3
void hemi_basis_hl2(vec3 n, vec4 sep4_weights[9], inout float b[HEMI_BASIS_MAX_SIZE])
{
    float t[3];
    hemi_eval_hl2(n, t);
    for (int i = 0; i < 3; ++i)
        b[i] = t[i];
}

#endif
