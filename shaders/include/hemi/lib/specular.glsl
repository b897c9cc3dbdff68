// hemi's GLSL library: specular light from precomputed lighting, for the GGX microfacet BRDF an engine's PBR
// material has (roughness as glTF's, alpha = roughness^2; f0 the reflectance at normal incidence). The
// BRDF's twin is hemi::math::ggx_eval_cos (math/ggx.h); docs/specular.md derives the estimator and measures
// its error against path-traced truth (hemi-bake reference --roughness).
//
// A directional lightmap's coefficients hold the irradiance over the normals of a texel's hemisphere, not
// the radiance a glossy lobe needs. hemi_basis_specular recovers a lighting that explains them: the SH9
// irradiance they most likely came from (hemi_basis_to_sh9, a per-basis linear estimator generated from
// math::sh9_from_basis), split into one sun (its direction from the linear band, where a uniform sky has
// been taken out; refined in the basis's own space by Gauss-Newton) and the rest. The sun's specular is GGX,
// its lobe widened by the light's spread; the rest's is its irradiance at the reflected direction, E(r) / pi,
// as the radiance of a smooth environment, times the split sum's directional albedo. One sun comes back
// exactly from every basis. Mixed lights are not in the coefficients: light them as dynamic lights with
// hemi_ggx (exact).
#ifndef HEMI_LIB_SPECULAR_GLSL
#define HEMI_LIB_SPECULAR_GLSL
#include "hemi/basis/sh9.glsl"
#include "hemi/lib/irradiance.glsl"
#include "hemi/lib/specular_generated.glsl"
#include "hemi/shared/bases.h"
#include "hemi/shared/sh_constants.h"

// Roughness is clamped to [0.03, 1] (alpha >= 9e-4 keeps D finite in float), as math::kGgxMinRoughness.
float hemi_ggx_alpha(float roughness)
{
    const float r = clamp(roughness, 0.03, 1.0);
    return r * r;
}

// GGX at alpha^2 = a2 (hemi_ggx's, or a lobe widened for a light of some size: hemi_basis_specular).
vec3 hemi_ggx_a2(vec3 n, vec3 l, vec3 v, float a2, vec3 f0)
{
    const float nl = dot(n, l), nv = dot(n, v);
    const vec3 lv = l + v;
    if (nl <= 0.0 || nv <= 0.0 || dot(lv, lv) < 1e-12)
        return vec3(0.0);
    const vec3 h = normalize(lv);
    const float nh = clamp(dot(n, h), 0.0, 1.0);
    // nh^2 (a2 - 1) + 1 as nh^2 a2 + |n x h|^2: no cancellation near the peak of a smooth lobe in float.
    const vec3 nxh = cross(n, h);
    const float t = nh * nh * a2 + dot(nxh, nxh);
    const float d = a2 / (3.14159265358979 * t * t);
    const float vis = 0.5 / (nl * sqrt(nv * nv * (1.0 - a2) + a2) + nv * sqrt(nl * nl * (1.0 - a2) + a2));
    const float fc = pow(1.0 - clamp(dot(v, h), 0.0, 1.0), 5.0);
    return (f0 + (vec3(1.0) - f0) * fc) * (d * vis * nl);
}

// f_r (n.l) of GGX with Smith's height-correlated masking-shadowing and Schlick's Fresnel: times a light's
// irradiance on a surface facing it, its reflected radiance. 0 where l or v is below n.
vec3 hemi_ggx(vec3 n, vec3 l, vec3 v, float roughness, vec3 f0)
{
    const float a = hemi_ggx_alpha(roughness);
    return hemi_ggx_a2(n, l, v, a * a, f0);
}

// The split sum's directional albedo: the GGX lobe's integral over a white environment at n.v = cos_v, as
// f0 * x + y: a polynomial fitted to math::ggx_albedo's quadrature (hemi_ggx_albedo_fit, generated; within
// 0.03 of it, docs/specular.md). n.v below 0.05 is taken as 0.05.
vec2 hemi_ggx_albedo(float cos_v, float roughness)
{
    return clamp(hemi_ggx_albedo_fit(sqrt(clamp(cos_v, 0.05, 1.0)), clamp(roughness, 0.03, 1.0)), 0.0, 1.0);
}

// A unit sun's SH9 irradiance coefficients at direction d: A_l y_lm(d).
void hemi_sh9_sun(vec3 d, out float y[9])
{
    hemi_eval_sh9(d, y);
    y[0] *= float(HEMI_SH_A0);
    for (int j = 1; j < 4; ++j)
        y[j] *= float(HEMI_SH_A1);
    for (int j = 4; j < 9; ++j)
        y[j] *= float(HEMI_SH_A2);
}

// Its derivative as d moves along t: d/ds of A_l y_lm(d + s t).
void hemi_sh9_sun_derivative(vec3 d, vec3 t, out float y[9])
{
    const float y1 = float(HEMI_SH_A1 * HEMI_SH_Y1), y2 = float(HEMI_SH_A2 * HEMI_SH_Y2);
    y[0] = 0.0;
    y[1] = -y1 * t.y;
    y[2] = y1 * t.z;
    y[3] = -y1 * t.x;
    y[4] = y2 * (t.x * d.y + d.x * t.y);
    y[5] = -y2 * (t.y * d.z + d.y * t.z);
    y[6] = float(HEMI_SH_A2 * HEMI_SH_Y20) * 6.0 * d.z * t.z;
    y[7] = -y2 * (t.x * d.z + d.x * t.z);
    y[8] = float(HEMI_SH_A2 * HEMI_SH_Y22) * 2.0 * (d.x * t.x - d.y * t.y);
}

// The one sun that best explains SH9 irradiance e: its direction (unit; in the upper hemisphere of the
// frame when `hemisphere`) and its irradiance on a surface facing it; `rest` = e minus that sun. The lighting
// is modelled as a sun plus a uniform sky (over the upper hemisphere of the coefficients' frame when
// `hemisphere`, a lightmap's or a tangent-frame PRT vertex's; over the sphere otherwise, a world-space
// probe): the direction comes from the linear band (luminance) once the sky's share is taken out, and both
// intensities from a least-squares fit of the nine coefficients, twice. One sun alone is recovered exactly.
struct HemiSh9Sun
{
    vec3 direction;
    vec3 irradiance;
    // How far the light spreads about `direction`: the alpha^2 to add to a GGX lobe lit by it (0: a sun).
    // From the linear band's length over the constant's (of all the light: a sun with a sky reads as a wider
    // lobe, which on real levels errs on the safe side), which is sqrt(3) for a sun and sqrt(3) g1 for a von
    // Mises-Fisher lobe of sharpness kappa (g1 = coth kappa - 1 / kappa, inverted as Banerjee et al. 2005
    // do); the lobe's angular variance 1 / kappa is a quarter of that in half vectors, where GGX's alpha^2 is
    // about twice the slopes' variance: 1 / (2 kappa).
    float spread;
};

// The linear band's length over the constant's, in units of a sun's (sqrt(3) in radiance: 1 for a sun, less
// for a wider light), of SH9 irradiance e (luminance).
float hemi_sh9_directionality(vec3 e[9])
{
    const vec3 w = vec3(0.2126, 0.7152, 0.0722);
    const float l0 = dot(e[0], w) / float(HEMI_SH_A0);
    const vec3 l1 = vec3(dot(e[3], w), dot(e[1], w), dot(e[2], w)) / float(HEMI_SH_A1);
    return l0 > 0.0 ? length(l1) / (sqrt(3.0) * l0) : 0.0;
}

// HemiSh9Sun::spread for a directionality g (1: a sun). Sharpness above 1e5 (a lobe under 0.2 degrees,
// beyond what float coefficients resolve) counts as a sun: no spread, so that one sun stays exact.
float hemi_sun_spread(float g)
{
    g = clamp(g, 0.0, 1.0 - 1e-6);
    const float kappa = g * (3.0 - g * g) / (1.0 - g * g);
    return max(0.5 / max(kappa, 1e-6) - 0.5e-5, 0.0);
}
HemiSh9Sun hemi_sh9_dominant_sun(vec3 e[9], bool hemisphere, out vec3 rest[9])
{
    const vec3 w = vec3(0.2126, 0.7152, 0.0722);
    // The sky's coefficients for irradiance 1 (radiance 1 / pi): 2 pi y00, 2 pi / 3 y1 over the hemisphere;
    // 1 / y00 over the sphere.
    float h[9];
    for (int j = 0; j < 9; ++j)
        h[j] = 0.0;
    h[0] = hemisphere ? 2.0 * 3.14159265358979 * float(HEMI_SH_Y00) : 1.0 / float(HEMI_SH_Y00);
    h[2] = hemisphere ? 2.0 * 3.14159265358979 / 3.0 * float(HEMI_SH_Y1) : 0.0;
    HemiSh9Sun sun;
    sun.direction = vec3(0.0, 0.0, 1.0);
    sun.irradiance = vec3(0.0);
    sun.spread = 0.0;
    vec3 sky = vec3(0.0);
    float y[9];
    for (int pass = 0; pass < 2; ++pass)
    {
        // Band 1 of e minus the sky: y1,-1 = -Y1 y, y1,0 = Y1 z, y1,1 = -Y1 x.
        const vec3 b1 =
            vec3(-dot(e[3] - sky * h[3], w), -dot(e[1] - sky * h[1], w), dot(e[2] - sky * h[2], w));
        vec3 d = b1;
        if (hemisphere)
            d.z = max(d.z, 0.0);
        d = dot(d, d) > 1e-20 ? normalize(d) : vec3(0.0, 0.0, 1.0);
        hemi_sh9_sun(d, y);
        float yy = 0.0, yh = 0.0, hh = 0.0;
        vec3 ye = vec3(0.0), he = vec3(0.0);
        for (int j = 0; j < 9; ++j)
        {
            yy += y[j] * y[j];
            yh += y[j] * h[j];
            hh += h[j] * h[j];
            ye += y[j] * e[j];
            he += h[j] * e[j];
        }
        const float det = yy * hh - yh * yh;
        vec3 c = (ye * hh - he * yh) / det;
        vec3 s = (he * yy - ye * yh) / det;
        // A negative sun (or sky) is a misfit, not a light: the other alone then.
        const bvec3 no_sun = lessThan(c, vec3(0.0)), no_sky = lessThan(s, vec3(0.0));
        s = mix(s, he / hh, no_sun);
        c = mix(c, vec3(0.0), no_sun);
        c = mix(c, ye / yy, no_sky);
        s = mix(s, vec3(0.0), no_sky);
        c = max(c, vec3(0.0));
        s = max(s, vec3(0.0));
        sun.direction = d;
        sun.irradiance = c;
        sky = s;
    }
    for (int j = 0; j < 9; ++j)
        rest[j] = e[j] - sun.irradiance * y[j];
    sun.spread = hemi_sun_spread(hemi_sh9_directionality(e));
    return sun;
}

// Specular radiance (GGX) towards v from SH9 irradiance e, at the unit normal n (n, v and e in one frame;
// `hemisphere` as for hemi_sh9_dominant_sun).
vec3 hemi_sh9_specular(vec3 e[9], vec3 n, vec3 v, float roughness, vec3 f0, bool hemisphere)
{
    const float nv = dot(n, v);
    if (nv <= 0.0)
        return vec3(0.0);
    vec3 rest[9];
    const HemiSh9Sun sun = hemi_sh9_dominant_sun(e, hemisphere, rest);
    const float a = hemi_ggx_alpha(roughness);
    vec3 spec = sun.irradiance * hemi_ggx_a2(n, sun.direction, v, min(a * a + sun.spread, 1.0), f0);
    // The rest at the reflected direction (not below the frame's horizon, which a lightmap does not see).
    vec3 r = reflect(-v, n);
    if (hemisphere)
        r.z = max(r.z, 0.0);
    r = dot(r, r) > 1e-12 ? normalize(r) : n;
    float b[9];
    hemi_eval_sh9(r, b);
    vec3 er = vec3(0.0);
    for (int j = 0; j < 9; ++j)
        er += rest[j] * b[j];
    const vec2 ab = hemi_ggx_albedo(nv, roughness);
    return spec + max(er, vec3(0.0)) / 3.14159265358979 * (f0 * ab.x + ab.y);
}

// The one sun (and uniform sky, with four coefficients or more) that best explains a basis's K coefficients
// in the basis's own space: c ~ C P y(d) + S P h, P the bake's projection (hemi_basis_from_sh9), y(d) a
// unit sun's SH9 irradiance, h a uniform sky's. It starts from hemi_sh9_dominant_sun of the SH9 estimate
// (hemi_basis_to_sh9) and refines direction and strengths by Gauss-Newton on the luminance (six steps),
// then fits C and S per channel at that direction. A sun alone is recovered wherever the basis can tell its
// direction. `rest` = c minus the sun's coefficients.
HemiSh9Sun hemi_basis_dominant_sun(int basis, int k, vec3 c[HEMI_BASIS_MAX_SIZE],
                                   out vec3 rest[HEMI_BASIS_MAX_SIZE])
{
    vec3 e[9], e_rest[9];
    hemi_basis_to_sh9(basis, c, e);
    HemiSh9Sun sun = hemi_sh9_dominant_sun(e, true, e_rest);
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        rest[i] = basis == HEMI_BASIS_SH9 ? e_rest[i] : c[i];
    if (basis == HEMI_BASIS_SH9)
        return sun;
    const vec3 w = vec3(0.2126, 0.7152, 0.0722);
    float h[9], rs[HEMI_BASIS_MAX_SIZE], y[9], r[HEMI_BASIS_MAX_SIZE], cl[HEMI_BASIS_MAX_SIZE];
    for (int j = 0; j < 9; ++j)
        h[j] = 0.0;
    h[0] = 2.0 * 3.14159265358979 * float(HEMI_SH_Y00);
    h[2] = 2.0 * 3.14159265358979 / 3.0 * float(HEMI_SH_Y1);
    hemi_basis_from_sh9(basis, h, rs);
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        cl[i] = i < k ? dot(c[i], w) : 0.0;
    const bool sky = k >= 4; // three coefficients hold a sun's direction and strength, nothing more
    vec3 d = sun.direction;
    float cs = 0.0, ss = 0.0;
    for (int step = 0; step < 6; ++step)
    {
        const vec3 a = abs(d.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
        const vec3 t1 = normalize(a - d * dot(d, a)), t2 = cross(d, t1);
        float dy1[9], dy2[9], j1[HEMI_BASIS_MAX_SIZE], j2[HEMI_BASIS_MAX_SIZE];
        hemi_sh9_sun(d, y);
        hemi_sh9_sun_derivative(d, t1, dy1);
        hemi_sh9_sun_derivative(d, t2, dy2);
        hemi_basis_from_sh9(basis, y, r);
        hemi_basis_from_sh9(basis, dy1, j1);
        hemi_basis_from_sh9(basis, dy2, j2);
        if (step == 0)
        {
            // The strengths at the start: the linear fit.
            float rr = 0.0, rh = 0.0, hh = 0.0, re = 0.0, he = 0.0;
            for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
            {
                rr += r[i] * r[i];
                rh += r[i] * rs[i];
                hh += rs[i] * rs[i];
                re += r[i] * cl[i];
                he += rs[i] * cl[i];
            }
            cs = re / rr;
            if (sky)
            {
                const float det = rr * hh - rh * rh;
                ss = max((he * rr - re * rh) / det, 0.0);
                cs = (re - ss * rh) / rr;
            }
        }
        if (!(cs > 0.0))
            break;
        // Gauss-Newton on (d, C, S) together: the residual's Jacobian has the columns C j1, C j2, r and the
        // sky's coefficients (a unit column, unused, without a sky).
        mat4 m = mat4(0.0);
        vec4 g = vec4(0.0);
        for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        {
            const vec4 jac = vec4(cs * j1[i], cs * j2[i], r[i], sky ? rs[i] : 0.0);
            m += outerProduct(jac, jac);
            g += jac * (cl[i] - cs * r[i] - ss * rs[i]);
        }
        const float ridge = 1e-6 * (m[0][0] + m[1][1] + m[2][2] + m[3][3]);
        m += mat4(ridge);
        if (!sky)
            m[3][3] = 1.0;
        const vec4 delta = inverse(m) * g;
        const vec2 turn =
            delta.xy * min(1.0, 0.5 / max(length(delta.xy), 1e-20)); // at most ~29 degrees a step
        d = normalize(d + turn.x * t1 + turn.y * t2);
        d.z = max(d.z, 0.0);
        d = normalize(d);
        cs += delta.z;
        ss = sky ? max(ss + delta.w, 0.0) : 0.0;
    }
    // The colour at the final direction: sun and sky per channel, as hemi_sh9_dominant_sun fits them.
    hemi_sh9_sun(d, y);
    hemi_basis_from_sh9(basis, y, r);
    float rr = 0.0, rh = 0.0, hh = 0.0;
    vec3 re = vec3(0.0), he = vec3(0.0);
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
    {
        rr += r[i] * r[i];
        rh += r[i] * rs[i];
        hh += rs[i] * rs[i];
        re += r[i] * (i < k ? c[i] : vec3(0.0));
        he += rs[i] * (i < k ? c[i] : vec3(0.0));
    }
    vec3 colour = re / rr;
    if (sky)
    {
        const float det = rr * hh - rh * rh;
        const vec3 sky_colour = (he * rr - re * rh) / det;
        colour = mix((re * hh - he * rh) / det, re / rr, lessThan(sky_colour, vec3(0.0)));
    }
    sun.direction = d;
    sun.irradiance = max(colour, vec3(0.0));
    // The spread: the SH9 estimate's directionality over what the same estimate gives for the fitted sun
    // alone (the basis blurs even a sun): 1, and no spread, for a sun.
    {
        vec3 one[HEMI_BASIS_MAX_SIZE], alone[9];
        for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
            one[i] = vec3(r[i]);
        hemi_basis_to_sh9(basis, one, alone);
        sun.spread = hemi_sun_spread(hemi_sh9_directionality(e) / max(hemi_sh9_directionality(alone), 1e-6));
    }
    for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
        rest[i] = i < k ? c[i] - sun.irradiance * r[i] : vec3(0.0);
    return sun;
}

// Specular radiance (GGX) towards v from the K coefficients of one of hemi's bases (`basis` a HEMI_BASIS_*
// id and `sep4_weights` as for hemi_basis_irradiance; the coefficients' frame a tangent frame: a lightmap
// texel, a PRT vertex), at the normal-map normal n: the dominant sun's exact GGX, and the rest's irradiance
// at the reflected direction (not below the frame's horizon) over pi times the split sum's albedo. Classic
// PRT's vertex irradiance (one coefficient, no direction) is taken as a uniform sky.
vec3 hemi_basis_specular(int basis, int k, vec3 c[HEMI_BASIS_MAX_SIZE], vec3 n, vec3 v, float roughness,
                         vec3 f0, vec4 sep4_weights[9])
{
    const float nv = dot(n, v);
    if (nv <= 0.0)
        return vec3(0.0);
    const vec2 ab = hemi_ggx_albedo(nv, roughness);
    if (basis == HEMI_BASIS_VERTEX_IRRADIANCE)
        return max(c[0], vec3(0.0)) / 3.14159265358979 * (f0 * ab.x + ab.y);
    vec3 rest[HEMI_BASIS_MAX_SIZE];
    const HemiSh9Sun sun = hemi_basis_dominant_sun(basis, k, c, rest);
    vec3 r = reflect(-v, n);
    r.z = max(r.z, 0.0);
    r = dot(r, r) > 1e-12 ? normalize(r) : n;
    const vec3 er = hemi_basis_irradiance(basis, k, rest, r, sep4_weights);
    const float a = hemi_ggx_alpha(roughness);
    return sun.irradiance * hemi_ggx_a2(n, sun.direction, v, min(a * a + sun.spread, 1.0), f0) +
           max(er, vec3(0.0)) / 3.14159265358979 * (f0 * ab.x + ab.y);
}

#endif
