#version 450
// Looks light probes up at a list of points with the GLSL library's hemi_probe_irradiance
// (hemi/lib/probes.glsl): out[i * 11 + j] = SH9 coefficient j (j < 9), out[i * 11 + 9] the occlusion; and
// out[i * 11 + 10] hemi_box_projected_direction (hemi/lib/environment.glsl) from the point along the
// direction from (1.3, 0.8, 0.4) to it, in the box [-0.5, -0.5, -0.5] to [3.5, 2.5, 1.5] captured at (1.5, 1,
// 0.5), with in .w hemi_box_influence of the box [0, 0, 0] to [3, 2, 1] with a fade of 0.3. A test shader
// (tests/shaders/).
#extension GL_GOOGLE_include_directive : require
#include "hemi/lib/environment.glsl"
#include "hemi/lib/probes.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform samplerBuffer probes;
layout(set = 0, binding = 1, std430) readonly buffer Points
{
    vec4 points[];
};
layout(set = 0, binding = 2, std430) writeonly buffer Values
{
    vec4 values[];
};
layout(push_constant) uniform Push
{
    uint count; // the number of points
}
pc;

void main()
{
    const uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    vec3 sh[HEMI_BASIS_MAX_SIZE];
    vec4 occlusion;
    hemi_probe_irradiance(probes, points[i].xyz, sh, occlusion);
    for (int j = 0; j < 9; ++j)
        values[i * 11 + j] = vec4(sh[j], 0.0);
    values[i * 11 + 9] = occlusion;
    const vec3 p = points[i].xyz, r = normalize(p - vec3(1.3, 0.8, 0.4));
    values[i * 11 + 10] =
        vec4(hemi_box_projected_direction(p, r, vec3(-0.5), vec3(3.5, 2.5, 1.5), vec3(1.5, 1.0, 0.5)),
             hemi_box_influence(p, vec3(0.0), vec3(3.0, 2.0, 1.0), 0.3));
}
