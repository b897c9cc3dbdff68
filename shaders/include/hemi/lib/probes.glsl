// hemi's GLSL library: light probes that do not leak through walls (io/light_probes.h; Majercik et al. 2019).
// The SH9 irradiance at a point from a lightmap asset's probes, a grid's or scattered ones: each probe around
// the point (a grid's 8 probes of the point's cell by their trilinear weights; scattered probes whose reach
// holds the point by their bumps (1 - d^2 / reach^2)^8) weighted by its visibility: Chebyshev's bound on the
// chance that nothing lies between the probe and the point, from the probe's octahedral depth map (mean
// distance and deviation). The same math as io::LightProbes::at() (docs/probes.md).
//
// The engine keeps the probes in one RGBA32F texel buffer in io::probe_texels()' layout, which describes
// itself: the shader needs nothing else. Per object (its centre) or per pixel (a surface point lifted off
// its surface along the normal by a few centimetres, so that the probes behind the surface do not see it as
// occluded by the surface itself).
#ifndef HEMI_LIB_PROBES_GLSL
#define HEMI_LIB_PROBES_GLSL
#include "hemi/lib/coefficients.glsl"

#define HEMI_PROBE_MIN_VISIBILITY 1e-4 // io::LightProbes::kMinVisibility
#define HEMI_PROBE_HEADER 4            // io::kProbeTexelHeader

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
    return 9 + (depth_resolution * depth_resolution + 1) / 2;
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

// io::LightProbes::visibility: how much of point p the probe whose texels start at `base` sees (r: the
// depth maps' side, 0 for none).
float hemi_probe_visibility(samplerBuffer probes, int r, int base, vec3 p)
{
    if (r == 0)
        return 1.0;
    const vec3 d = p - texelFetch(probes, base + 8).xyz;
    const float distance = length(d);
    if (!(distance > 0.0) || isinf(distance))
        return 1.0;
    const vec2 m = hemi_probe_depth(probes, base + 9, r, d / distance);
    if (distance <= m.x)
        return 1.0;
    const float variance = m.y * m.y, beyond = distance - m.x;
    const float chebyshev = variance / (variance + beyond * beyond);
    return max(chebyshev * chebyshev, HEMI_PROBE_MIN_VISIBILITY);
}

// The running sums of one lookup.
struct HemiProbeSum
{
    vec4 packed[7];
    vec4 occlusion;
    float total;
};

// Adds probe `probe` with weight w (before its visibility) at p, when it is valid and w > 0.
void hemi_probe_add(samplerBuffer probes, int r, int stride, int probe, float w, vec3 p, inout HemiProbeSum s)
{
    const int base = HEMI_PROBE_HEADER + probe * stride;
    const vec4 last_texel = texelFetch(probes, base + 6); // .w: valid
    if (last_texel.w == 0.0 || !(w > 0.0))
        return;
    w *= hemi_probe_visibility(probes, r, base, p);
    s.total += w;
    HEMI_UNROLL for (int i = 0; i < 6; ++i) s.packed[i] += w * texelFetch(probes, base + i);
    s.packed[6] += w * last_texel;
    s.occlusion += w * texelFetch(probes, base + 7);
}

// The SH9 irradiance at p (the probes' frame, the level's; E(n) = hemi_sh9_irradiance(sh, n)) and the mixed
// lights' occlusion there (io::LightProbes::occlusion_at; all 1 without mixed lights). Where no valid probe
// reaches p (all 8 of a grid cell's inside geometry, or beyond every scattered probe's reach), zero light and
// occlusion 1 (io::LightProbes::at() falls back to the nearest valid probe instead, which a shader cannot
// afford: place probes so that every reachable point has a valid one around it, as hemi-bake's placement
// does).
void hemi_probe_irradiance(samplerBuffer probes, vec3 p, out vec3 sh[HEMI_BASIS_MAX_SIZE], out vec4 occlusion)
{
    HEMI_UNROLL for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i) sh[i] = vec3(0.0);
    const vec4 header = texelFetch(probes, 0);
    const int r = int(header.y), stride = int(header.w);
    HemiProbeSum s;
    HEMI_UNROLL for (int i = 0; i < 7; ++i) s.packed[i] = vec4(0.0);
    s.occlusion = vec4(0.0);
    s.total = 0.0;
    const vec4 t1 = texelFetch(probes, 1), t2 = texelFetch(probes, 2), t3 = texelFetch(probes, 3);
    if (header.x == 0.0)
    {
        // A grid: the 8 probes of p's cell.
        const ivec3 count = ivec3(t1.xyz);
        const vec3 lo = t2.xyz, extent = t3.xyz - t2.xyz, last = vec3(count - 1);
        vec3 f = vec3(0.0);
        for (int a = 0; a < 3; ++a)
            if (count[a] > 1 && extent[a] > 0.0)
            {
                const float t = (p[a] - lo[a]) / extent[a] * last[a];
                f[a] =
                    isnan(t) ? 0.0 : clamp(t, 0.0, last[a]); // NaN: the first cell, never outside the buffer
            }
        const ivec3 i0 = clamp(ivec3(f), ivec3(0), count - 1), i1 = min(i0 + 1, count - 1);
        const vec3 t = f - vec3(i0);
        for (int corner = 0; corner < 8; ++corner)
        {
            const bvec3 up = bvec3((corner & 1) != 0, (corner & 2) != 0, (corner & 4) != 0);
            const ivec3 ijk = ivec3(up.x ? i1.x : i0.x, up.y ? i1.y : i0.y, up.z ? i1.z : i0.z);
            const vec3 w3 = mix(1.0 - t, t, vec3(up));
            hemi_probe_add(probes, r, stride, ijk.x + count.x * (ijk.y + count.y * ijk.z), w3.x * w3.y * w3.z,
                           p, s);
        }
    }
    else
    {
        // Scattered probes: those the index lists for p's cell, each by its bump.
        const ivec3 cells = ivec3(t1.xyz);
        const vec3 c = (p - t2.xyz) / t3.xyz;
        if (all(greaterThanEqual(c, vec3(0.0))) && all(lessThan(c, vec3(cells))))
        {
            const ivec3 ci = min(ivec3(c), cells - 1);
            const int cell = ci.x + cells.x * (ci.y + cells.y * ci.z), first = int(t1.w), list = int(t2.w);
            const int begin = int(texelFetch(probes, first + cell / 4)[cell & 3]);
            const int end = int(texelFetch(probes, first + (cell + 1) / 4)[(cell + 1) & 3]);
            for (int k = begin; k < end; ++k)
            {
                const int probe = int(texelFetch(probes, list + k / 4)[k & 3]);
                const vec4 q = texelFetch(probes, HEMI_PROBE_HEADER + probe * stride + 8);
                const vec3 d = p - q.xyz;
                const float b = 1.0 - dot(d, d) / (q.w * q.w), b2 = b * b, b4 = b2 * b2;
                hemi_probe_add(probes, r, stride, probe, b > 0.0 ? b4 * b4 : 0.0, p, s);
            }
        }
    }
    if (!(s.total > 0.0))
    {
        occlusion = vec4(1.0);
        return;
    }
    HEMI_UNROLL for (int i = 0; i < 7; ++i) s.packed[i] /= s.total;
    hemi_unpack_coefficients(s.packed, 9, sh);
    occlusion = clamp(s.occlusion / s.total, 0.0, 1.0);
}

#endif
