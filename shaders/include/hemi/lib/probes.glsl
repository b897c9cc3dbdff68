// hemi's GLSL library: light probes that do not leak through walls (io/light_probes.h; Majercik et al. 2019).
// The SH9 irradiance at a point from a lightmap asset's probe grid, each of the 8 probes of the point's cell
// weighted by its trilinear weight times its visibility: Chebyshev's bound on the chance that nothing lies
// between the probe and the point, from the probe's octahedral depth map (mean distance and deviation). The
// same math as io::LightProbes::at() (docs/probes.md).
//
// The engine keeps the probes in one RGBA32F texel buffer in io::probe_texels()' layout and passes the
// grid's numbers (HemiProbeGrid, from io::LightProbes). Per object (its centre) or per pixel (a surface
// point lifted off its surface along the normal by a few centimetres, so that the probes behind the surface
// do not see it as occluded by the surface itself).
#ifndef HEMI_LIB_PROBES_GLSL
#define HEMI_LIB_PROBES_GLSL
#include "hemi/lib/coefficients.glsl"

// io::LightProbes' count, lo, hi and depth_resolution (0: no depth maps, trilinear alone).
struct HemiProbeGrid
{
    ivec3 count;
    vec3 lo;
    vec3 hi;
    int depth_resolution;
};

#define HEMI_PROBE_MIN_VISIBILITY 1e-4 // io::LightProbes::kMinVisibility

// io::octahedral_encode: a direction to [0, 1]^2.
vec2 hemi_octahedral_encode(vec3 d)
{
    vec2 p = d.xy / (abs(d.x) + abs(d.y) + abs(d.z));
    if (d.z < 0.0)
        p = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
    return p * 0.5 + 0.5;
}

// The texels of one probe: io::probe_texel_stride.
int hemi_probe_stride(int depth_resolution)
{
    return 8 + (depth_resolution * depth_resolution + 1) / 2;
}

vec3 hemi_probe_position(HemiProbeGrid g, ivec3 ijk)
{
    const vec3 steps = max(vec3(g.count) - 1.0, vec3(1.0));
    return g.lo + (g.hi - g.lo) * vec3(ijk) / steps;
}

// Texel (x, y) of the depth map that starts at texel `first`: (mean, deviation); outside the square, its
// mirror image across the edge it crossed (the octahedral map's folds), a corner the opposite corner.
vec2 hemi_probe_depth_texel(samplerBuffer probes, int first, int r, int x, int y)
{
    if (y < 0 || y >= r)
    {
        y = y < 0 ? 0 : r - 1;
        x = r - 1 - x;
    }
    if (x < 0 || x >= r)
    {
        x = x < 0 ? 0 : r - 1;
        y = r - 1 - y;
    }
    const int t = y * r + x;
    const vec4 pair = texelFetch(probes, first + t / 2);
    return (t & 1) == 0 ? pair.xy : pair.zw;
}

// io::LightProbes::depth_at: bilinear over the map, continuous over the sphere.
vec2 hemi_probe_depth(samplerBuffer probes, int first, int r, vec3 direction)
{
    const vec2 t = hemi_octahedral_encode(direction) * float(r) - 0.5;
    const vec2 f = floor(t);
    const ivec2 i = ivec2(f);
    const vec2 a = t - f;
    return mix(mix(hemi_probe_depth_texel(probes, first, r, i.x, i.y),
                   hemi_probe_depth_texel(probes, first, r, i.x + 1, i.y), a.x),
               mix(hemi_probe_depth_texel(probes, first, r, i.x, i.y + 1),
                   hemi_probe_depth_texel(probes, first, r, i.x + 1, i.y + 1), a.x),
               a.y);
}

// io::LightProbes::visibility: how much of point p the probe whose texels start at `base` sees.
float hemi_probe_visibility(samplerBuffer probes, HemiProbeGrid g, int base, vec3 probe_position, vec3 p)
{
    if (g.depth_resolution == 0)
        return 1.0;
    const vec3 d = p - probe_position;
    const float r = length(d);
    if (!(r > 0.0) || isinf(r))
        return 1.0;
    const vec2 m = hemi_probe_depth(probes, base + 8, g.depth_resolution, d / r);
    if (r <= m.x)
        return 1.0;
    const float variance = m.y * m.y, beyond = r - m.x;
    const float chebyshev = variance / (variance + beyond * beyond);
    return max(chebyshev * chebyshev * chebyshev, HEMI_PROBE_MIN_VISIBILITY);
}

// The SH9 irradiance at p (the grid's frame; E(n) = hemi_sh9_irradiance(sh, n)) and the mixed lights'
// occlusion there (io::LightProbes::occlusion_at; all 1 without mixed lights). Where none of the cell's 8
// probes is valid, zero light and occlusion 1 (io::LightProbes::at() falls back to the nearest valid probe
// of the whole grid instead, which a shader cannot afford: place or bake probes so that none of a reachable
// cell's are all inside geometry).
void hemi_probe_irradiance(samplerBuffer probes, HemiProbeGrid g, vec3 p, out vec3 sh[HEMI_BASIS_MAX_SIZE],
                           out vec4 occlusion)
{
    HEMI_UNROLL for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i) sh[i] = vec3(0.0);
    occlusion = vec4(0.0);
    const vec3 extent = g.hi - g.lo;
    const vec3 last = vec3(g.count - 1);
    vec3 f = vec3(0.0);
    for (int a = 0; a < 3; ++a)
        if (g.count[a] > 1 && extent[a] > 0.0)
        {
            const float t = (p[a] - g.lo[a]) / extent[a] * last[a];
            f[a] = isnan(t) ? 0.0 : clamp(t, 0.0, last[a]); // NaN: the first cell, never outside the buffer
        }
    const ivec3 i0 = clamp(ivec3(f), ivec3(0), g.count - 1), i1 = min(i0 + 1, g.count - 1);
    const vec3 t = f - vec3(i0);
    const int stride = hemi_probe_stride(g.depth_resolution);
    float total = 0.0;
    vec4 packed_sum[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed_sum[i] = vec4(0.0);
    for (int corner = 0; corner < 8; ++corner)
    {
        const bvec3 up = bvec3((corner & 1) != 0, (corner & 2) != 0, (corner & 4) != 0);
        const ivec3 ijk = ivec3(up.x ? i1.x : i0.x, up.y ? i1.y : i0.y, up.z ? i1.z : i0.z);
        const vec3 w3 = mix(1.0 - t, t, vec3(up));
        float w = w3.x * w3.y * w3.z;
        const int base = (ijk.x + g.count.x * (ijk.y + g.count.y * ijk.z)) * stride;
        const vec4 last_texel = texelFetch(probes, base + 6); // .w: valid
        if (last_texel.w == 0.0 || w <= 0.0)
            continue;
        w *= hemi_probe_visibility(probes, g, base, hemi_probe_position(g, ijk), p);
        total += w;
        HEMI_UNROLL for (int i = 0; i < 6; ++i) packed_sum[i] += w * texelFetch(probes, base + i);
        packed_sum[6] += w * last_texel;
        occlusion += w * texelFetch(probes, base + 7);
    }
    if (!(total > 0.0))
    {
        occlusion = vec4(1.0);
        return;
    }
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed_sum[i] /= total;
    hemi_unpack_coefficients(packed_sum, 9, sh);
    occlusion = clamp(occlusion / total, 0.0, 1.0);
}

#endif
