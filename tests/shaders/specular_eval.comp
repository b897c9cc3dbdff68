#version 450
// hemi's specular GLSL (shaders/include/hemi/lib/specular.glsl) at a list of records: per record the
// coefficients, n, v, a light direction l and (roughness, f0, basis id); out: hemi_basis_specular, hemi_ggx
// at l, hemi_ggx_albedo, hemi_basis_to_sh9's nine coefficients, and hemi_basis_dominant_sun's direction (w:
// its spread) and irradiance. A test shader (tests/shaders/).
#extension GL_GOOGLE_include_directive : require
#include "hemi/hemi.glsl"

layout(local_size_x = 64) in;
// The basis and its size as specialization constants, as the material system's surface shader has them (a
// basis picked at run time would compile every basis's branch into the pipeline).
layout(constant_id = 0) const int kBasis = 0;
layout(constant_id = 1) const int K = 9;

struct Record
{
    vec4 c[9];
    vec4 n, v, l;
    vec4 params; // roughness, f0
};
layout(set = 0, binding = 0, std430) readonly buffer Records
{
    Record records[];
};
layout(set = 0, binding = 1, std430) writeonly buffer Values
{
    vec4 values[];
}; // 14 per record
layout(set = 0, binding = 2, std430) readonly buffer Sep4
{
    vec4 sep4_weights[9]; // math::sep4_weights()
};
layout(push_constant) uniform Push
{
    uint count;
}
pc;

void main()
{
    const uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    const Record r = records[i];
    vec3 c[HEMI_BASIS_MAX_SIZE];
    for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k)
        c[k] = r.c[k].rgb;
    const int basis = kBasis;
    const vec3 f0 = vec3(r.params.y);
    const uint o = i * 14u;
    values[o] = vec4(hemi_basis_specular(basis, K, c, r.n.xyz, r.v.xyz, r.params.x, f0, sep4_weights), 0.0);
    values[o + 1u] = vec4(hemi_ggx(r.n.xyz, r.l.xyz, r.v.xyz, r.params.x, f0), 0.0);
    values[o + 2u] = vec4(hemi_ggx_albedo(dot(r.n.xyz, r.v.xyz), r.params.x), 0.0, 0.0);
    vec3 e[9];
    hemi_basis_to_sh9(basis, c, e);
    for (int j = 0; j < 9; ++j)
        values[o + 3u + uint(j)] = vec4(e[j], 0.0);
    vec3 rest[HEMI_BASIS_MAX_SIZE];
    const HemiSh9Sun sun = hemi_basis_dominant_sun(basis, K, c, rest);
    values[o + 12u] = vec4(sun.direction, sun.spread);
    values[o + 13u] = vec4(sun.irradiance, 0.0);
}
