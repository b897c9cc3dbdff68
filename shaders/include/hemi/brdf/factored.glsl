// Heidrich & Seidel 1999's reflection models in GLSL: the GLSL twins of hemi/math/brdf.h (same conventions,
// same normalisation: every model is f_r cos(alpha), directions point away from the surface), evaluated
// analytically, and the lookups of their factored tables as hemi-bake brdf writes them (one table per layer
// of a sampler2DArray or a sampler2D; sample i of an axis at coordinate i / (size - 1)).
#ifndef HEMI_BRDF_FACTORED_GLSL
#define HEMI_BRDF_FACTORED_GLSL

const float kHemiBrdfPi = 3.14159265358979;

// erf by Abramowitz & Stegun 7.1.26 (absolute error < 1.5e-7): GLSL has none.
float hemi_erf(float x)
{
    const float t = 1.0 / (1.0 + 0.3275911 * abs(x));
    const float p =
        t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return sign(x) * (1.0 - p * exp(-x * x));
}

// Exact unpolarised Fresnel reflectance of a dielectric of relative index ior > 1 (math::fresnel_dielectric).
float hemi_fresnel_dielectric(float c, float ior)
{
    c = clamp(c, 0.0, 1.0);
    const float g = sqrt(ior * ior - 1.0 + c * c);
    const float a = (g - c) / (g + c);
    const float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

// Beckmann's distribution normalised so that Eq. 1 is the microfacet BRDF (integral of D cos = pi / 4).
float hemi_beckmann_d(float c, float m)
{
    if (c <= 0.0)
        return 0.0;
    const float c2 = c * c;
    const float t2 = (1.0 - c2) / c2;
    if (t2 > 80.0 * m * m)
        return 0.0;
    return exp(-t2 / (m * m)) / (4.0 * m * m * c2 * c2);
}

// Smith's G1(c) / c for Gaussian slopes of RMS m (finite at c = 0: 2 sqrt(pi) / m).
float hemi_smith_g1_over_cos(float c, float m)
{
    c = clamp(c, 0.0, 1.0);
    const float s = sqrt(max(0.0, 1.0 - c * c));
    if (s < 1e-6)
        return 1.0;
    const float a = c / (m * s);
    const float sqrt_pi = 1.7724538509;
    return 2.0 * sqrt_pi / (m * s) / (a * sqrt_pi * (1.0 + hemi_erf(a)) + exp(-a * a));
}

// Torrance-Sparrow with Beckmann facets, Eq. 1, f_r cos(alpha), evaluated directly; n, l, v unit.
float hemi_torrance_sparrow_cos(vec3 n, vec3 l, vec3 v, float m, float ior)
{
    const float ca = dot(n, l), cb = dot(n, v);
    if (ca <= 0.0 || cb <= 0.0)
        return 0.0;
    const vec3 h = normalize(l + v);
    const float g = ca * hemi_smith_g1_over_cos(ca, m) * hemi_smith_g1_over_cos(cb, m) * cb;
    return hemi_fresnel_dielectric(dot(l, h), ior) * g * hemi_beckmann_d(dot(n, h), m) / (kHemiBrdfPi * cb);
}

// Banks (Eq. 4) in Stalling's form, f_r cos(alpha) with t the fibre's tangent.
float hemi_banks_cos(vec3 n, vec3 t, vec3 l, vec3 v, float kd, float ks, float e)
{
    const float ca = dot(n, l);
    if (ca <= 0.0 || dot(n, v) <= 0.0)
        return 0.0;
    const float a = dot(t, l), b = dot(t, v);
    const float sa = sqrt(max(0.0, 1.0 - a * a)), sb = sqrt(max(0.0, 1.0 - b * b));
    const float c = sa * sb - a * b;
    return ca * (kd * sa + ks * (c > 0.0 ? pow(c, e) : 0.0));
}

// Phong's lobe of Eq. 8, normalised ((e + 1) / 2 pi) max(0, r_v.l)^e (the glossy maps' normalisation).
float hemi_phong_cos(vec3 n, vec3 l, vec3 v, float e)
{
    const float nv = dot(n, v);
    if (dot(n, l) <= 0.0 || nv <= 0.0)
        return 0.0;
    const float c = dot(2.0 * nv * n - v, l);
    return (e + 1.0) / (2.0 * kHemiBrdfPi) * (c > 0.0 ? pow(c, e) : 0.0);
}

// Table coordinates: an axis value s in [0, 1] of a table of `size` samples, and the axis mappings.
float hemi_table_coord(float s, float size)
{
    return (clamp(s, 0.0, 1.0) * (size - 1.0) + 0.5) / size;
}
float hemi_axis_sqrt(float c)
{
    return sqrt(max(0.0, 1.0 - c));
}
float hemi_axis_angle(float c)
{
    return acos(clamp(c, -1.0, 1.0)) / kHemiBrdfPi;
}

// Torrance-Sparrow from its two tables: layer 0 = FD (cos_theta, sqrt(1 - cos_delta)), layer 1 = G
// (cos_alpha, cos_beta), channel r; f_r cos(alpha) = FD * G.
float hemi_torrance_sparrow_table(sampler2DArray tables, float size, vec3 n, vec3 l, vec3 v)
{
    const float ca = dot(n, l), cb = dot(n, v);
    if (ca <= 0.0 || cb <= 0.0)
        return 0.0;
    const vec3 h = normalize(l + v);
    // textureLod: tables have one level, and these lookups sit in non-uniform control flow.
    const float fd = textureLod(tables,
                                vec3(hemi_table_coord(dot(l, h), size),
                                     hemi_table_coord(hemi_axis_sqrt(dot(n, h)), size), 0.0),
                                0.0)
                         .r;
    const float g =
        textureLod(tables, vec3(hemi_table_coord(ca, size), hemi_table_coord(cb, size), 1.0), 0.0).r;
    return fd * g;
}

// Banks from its table (r = diffuse, g = specular, axes acos(t.l) / pi, acos(t.v) / pi).
float hemi_banks_table(sampler2D table, float size, vec3 n, vec3 t, vec3 l, vec3 v, float kd, float ks)
{
    const float ca = dot(n, l);
    if (ca <= 0.0 || dot(n, v) <= 0.0)
        return 0.0;
    const vec2 ds = textureLod(table,
                               vec2(hemi_table_coord(hemi_axis_angle(dot(t, l)), size),
                                    hemi_table_coord(hemi_axis_angle(dot(t, v)), size)),
                               0.0)
                        .rg;
    return ca * (kd * ds.x + ks * ds.y);
}

// Phong from its table (r = specular, axes n.l, sqrt(1 - r_v.l)).
float hemi_phong_table(sampler2D table, float size, vec3 n, vec3 l, vec3 v)
{
    const float nv = dot(n, v);
    if (dot(n, l) <= 0.0 || nv <= 0.0)
        return 0.0;
    const float y = dot(2.0 * nv * n - v, l);
    if (y <= 0.0)
        return 0.0;
    return textureLod(table,
                      vec2(hemi_table_coord(dot(n, l), size), hemi_table_coord(hemi_axis_sqrt(y), size)), 0.0)
        .r;
}

#endif
