#version 450
// Heidrich & Seidel's models in GLSL (shaders/include/hemi/brdf/factored.glsl) at a list of (l, v) pairs with
// n = +z and t = +x: per pair, Torrance-Sparrow evaluated directly and from its two tables, Banks directly
// and from its table, Phong directly and from its table. A test shader (tests/shaders/).
#extension GL_GOOGLE_include_directive : require
#include "hemi/brdf/factored.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Pairs
{
    vec4 dirs[];
}; // l, v, l, v, ...
layout(set = 0, binding = 1, std430) writeonly buffer Values
{
    float values[];
}; // 6 per pair
layout(set = 0, binding = 2) uniform sampler2DArray ts_tables;
layout(set = 0, binding = 3) uniform sampler2D banks_table;
layout(set = 0, binding = 4) uniform sampler2D phong_table;
layout(push_constant) uniform Push
{
    uint count;
    float roughness;
    float ior;
    float exponent;
    float size;
}
pc;

void main()
{
    const uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    const vec3 n = vec3(0.0, 0.0, 1.0), t = vec3(1.0, 0.0, 0.0);
    const vec3 l = dirs[2 * i].xyz, v = dirs[2 * i + 1].xyz;
    values[i * 6 + 0] = hemi_torrance_sparrow_cos(n, l, v, pc.roughness, pc.ior);
    values[i * 6 + 1] = hemi_torrance_sparrow_table(ts_tables, pc.size, n, l, v);
    values[i * 6 + 2] = hemi_banks_cos(n, t, l, v, 1.0, 1.0, pc.exponent);
    values[i * 6 + 3] = hemi_banks_table(banks_table, pc.size, n, t, l, v, 1.0, 1.0);
    values[i * 6 + 4] = hemi_phong_cos(n, l, v, pc.exponent);
    values[i * 6 + 5] = hemi_phong_table(phong_table, pc.size, n, l, v);
}
