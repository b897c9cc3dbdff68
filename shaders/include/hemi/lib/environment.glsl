// hemi's GLSL library: Heidrich & Seidel 1999's environment terms over the textures hemi-bake envmap and
// hemi-bake brdf make (render::EnvironmentLighting uploads them and hands out their views, or the engine
// uploads the asset's maps itself; docs/glsl.md):
//   - parabolic maps (math/paraboloid.h): a 2-layer 2D array, layer 0 the front half (z >= 0), a direction d
//     at (x, y) = d.xy / (1 + |d.z|), texture coordinate ((x / m + 1) / 2, (1 - y / m) / 2) for the map's
//     extent m; the mirror map (with its solid-angle mipmaps), prefiltered glossy maps, the diffuse map (E /
//     pi);
//   - the Fresnel table: a row per index of refraction, samples at cos = i / (N - 1);
//   - the factored BRDF's tables (hemi/brdf/factored.glsl): Torrance-Sparrow's FD and G layers, Banks' table.
// Directions are in the environment's frame: rotate world directions first (hemi_env_direction).
#ifndef HEMI_LIB_ENVIRONMENT_GLSL
#define HEMI_LIB_ENVIRONMENT_GLSL
#include "hemi/brdf/factored.glsl"

// A world direction in the environment's frame, given the rows of the world-to-environment rotation.
vec3 hemi_env_direction(vec3 row0, vec3 row1, vec3 row2, vec3 world)
{
    return vec3(dot(row0, world), dot(row1, world), dot(row2, world));
}

// Where unit direction d sits in a parabolic map of extent m: (u, v, layer). The two halves agree on the
// circle (d.z = 0), so u, v and their screen derivatives (the mip level) are continuous across the seam.
vec3 hemi_parabolic_coord(vec3 d, float m)
{
    const vec2 xy = d.xy / (1.0 + abs(d.z));
    return vec3(0.5 * (xy.x / m + 1.0), 0.5 * (1.0 - xy.y / m), d.z >= 0.0 ? 0.0 : 1.0);
}

// A parabolic map (mirror, glossy or diffuse) in direction d (environment frame, unit), filtered by the
// engine's sampler (trilinear for the mirror map's mips).
vec3 hemi_parabolic_lookup(sampler2DArray map, float extent, vec3 d)
{
    return texture(map, hemi_parabolic_coord(d, extent)).rgb;
}

// A box-projected reflection probe (Lagarde & Zanuttini 2012; math::box_projected_direction): the direction
// to look the probe captured at `centre` up in, for a reflection from `p` along unit `r`, with the influence
// box [box_min, box_max] holding p: towards where the ray leaves the box. All in the probe's frame.
vec3 hemi_box_projected_direction(vec3 p, vec3 r, vec3 box_min, vec3 box_max, vec3 centre)
{
    float t = 3.4e38;
    for (int a = 0; a < 3; ++a)
        if (r[a] != 0.0)
            t = min(t, ((r[a] > 0.0 ? box_max[a] : box_min[a]) - p[a]) / r[a]);
    return normalize(p + max(t, 0.0) * r - centre);
}

// How much a reflection probe with influence box [box_min, box_max] counts at p (math::box_influence): 1
// deeper than `fade` inside every face, falling linearly to 0 at the faces, 0 outside. Blend the probes that
// overlap p by these weights, divided by their sum.
float hemi_box_influence(vec3 p, vec3 box_min, vec3 box_max, float fade)
{
    const vec3 inside = min(p - box_min, box_max - p);
    const float depth = min(inside.x, min(inside.y, inside.z));
    if (!(fade > 0.0))
        return depth >= 0.0 ? 1.0 : 0.0;
    return clamp(depth / fade, 0.0, 1.0);
}

// The mirror reflection of v (towards the eye) about n: 2 (n.v) n - v.
vec3 hemi_reflect(vec3 n, vec3 v)
{
    return 2.0 * dot(n, v) * n - v;
}

// F(cos theta) from a Fresnel table of `samples` samples per row, at the row's v coordinate `row_v` ((row +
// 0.5) / rows).
float hemi_fresnel_lookup(sampler2D table, float samples, float row_v, float c)
{
    return texture(table, vec2((clamp(c, 0.0, 1.0) * (samples - 1.0) + 0.5) / samples, row_v)).r;
}

// Banks' model for one light from its table (layer 0 of `tables`: r = diffuse, g = specular against
// acos(t.l) / pi, acos(t.v) / pi), with the fibre tangent t made perpendicular to n: vec2(diffuse, specular)
// times n.l, for the caller's kd albedo and ks. 0 for a light or eye behind the surface.
vec2 hemi_banks_light(sampler2DArray tables, float size, vec3 n, vec3 t, vec3 l, vec3 v)
{
    const float nl = dot(n, l);
    if (nl <= 0.0 || dot(n, v) <= 0.0)
        return vec2(0.0);
    t = t - n * dot(n, t);
    t = dot(t, t) > 1e-12
            ? normalize(t)
            : (abs(n.x) < 0.9 ? normalize(cross(n, vec3(1, 0, 0))) : normalize(cross(n, vec3(0, 1, 0))));
    // textureLod: the table has one level, and lights sit in non-uniform control flow.
    const vec2 ds = textureLod(tables,
                               vec3(hemi_table_coord(hemi_axis_angle(dot(t, l)), size),
                                    hemi_table_coord(hemi_axis_angle(dot(t, v)), size), 0.0),
                               0.0)
                        .rg;
    return nl * ds;
}

#endif
