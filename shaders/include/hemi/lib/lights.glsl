// hemi's GLSL library: the dynamic-light terms hemi's techniques add to precomputed lighting, for engines
// that want the same response (their own lights usually replace these). Directions unit, pointing away from
// the surface. docs/glsl.md.
#ifndef HEMI_LIB_LIGHTS_GLSL
#define HEMI_LIB_LIGHTS_GLSL

// Normalised Blinn-Phong, (m + 8) / (8 pi) (n.h)^m (n.l): times the light's irradiance (facing it) and a
// specular strength. 0 when the light is behind or the half vector does not exist (l = -v).
float hemi_blinn_phong(vec3 n, vec3 l, vec3 v, float exponent)
{
    const float nl = max(dot(n, l), 0.0);
    const vec3 lv = l + v;
    if (nl == 0.0 || dot(lv, lv) < 1e-12)
        return 0.0;
    return nl * pow(max(dot(n, normalize(lv)), 1e-6), exponent) * (exponent + 8.0) / (8.0 * 3.14159265358979);
}

#endif
