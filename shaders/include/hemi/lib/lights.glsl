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
