#version 450
// Evaluates one hemispherical basis (specialization constant 0 = HEMI_BASIS_*) at a list of unit normals:
// out[i * HEMI_BASIS_MAX_SIZE + k] = b_k(n_i). A test shader (tests/shaders/): it holds every GLSL twin equal
// to its C++ basis.
#extension GL_GOOGLE_include_directive : require
#include "hemi/basis/all.glsl"

layout(constant_id = 0) const int kBasis = 0;
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Normals
{
    vec4 normals[];
};
layout(set = 0, binding = 1, std430) writeonly buffer Values
{
    float values[];
};
layout(set = 0, binding = 2, std140) uniform Separable
{
    vec4 sep4_weights[9];
};
layout(push_constant) uniform Push
{
    uint count;
}
pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    float b[HEMI_BASIS_MAX_SIZE];
    hemi_eval_basis(kBasis, normals[i].xyz, sep4_weights, b);
    for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k)
        values[i * HEMI_BASIS_MAX_SIZE + k] = b[k];
}
