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

// glTF's recommended falloffs (KHR_lights_punctual), as hemi-bake bakes a light: a point or spot light's
// range window at distance d (range 0: none), clamp(1 - (d / range)^4, 0, 1), times its 1 / d^2; a spot
// light's smooth cone at cos_angle = dot(where it points, -l): saturate((cos_angle - cos_outer) * scale)^2
// with scale = 1 / max(0.001, cos_inner - cos_outer).
float hemi_range_window(float d, float range)
{
    if (range <= 0.0)
        return 1.0;
    const float x = d / range;
    return clamp(1.0 - x * x * x * x, 0.0, 1.0);
}
float hemi_spot_cone(float cos_angle, float cos_outer, float scale)
{
    const float a = clamp((cos_angle - cos_outer) * scale, 0.0, 1.0);
    return a * a;
}

// A mixed light's static shadow (hemi-bake lightmap --sun-mode mixed, a glTF light's hemi_bake_mode): its
// channel of the lightmap's shadowmask (hemi_lightmap_shadowmask), 1 for channel -1 (a light the lightmap
// does not shadow). Its direct light at run time is the light's unshadowed irradiance times this.
float hemi_shadowmask_channel(vec4 shadowmask, int channel)
{
    return channel < 0 ? 1.0 : shadowmask[clamp(channel, 0, 3)];
}

// Blending with the engine's own shadow map near the camera (Unity's and Godot's shadowmask modes): within
// the shadow map's reach the dynamic objects' shadows come from it, the static level's from both (whichever
// is darker, so a static shadow never fades where the map is coarse); beyond it the shadowmask alone.
// `fade` is 1 inside the shadow distance and falls to 0 at its end.
float hemi_mixed_shadow(float shadowmask, float shadow_map, float fade)
{
    return mix(shadowmask, min(shadowmask, shadow_map), clamp(fade, 0.0, 1.0));
}

#endif
