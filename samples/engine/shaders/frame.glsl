// The engine sample's own frame data and draw constants (not hemi's): set 0 is the engine's per-frame block
// (one per frame in flight), its shadow map and the level's probes (main.frag), the push constants its
// per-object block. Shared by its depth, main and post shaders.
#ifndef ENGINE_FRAME_GLSL
#define ENGINE_FRAME_GLSL
#include "hemi/shared/surface.h" // EnvironmentUniforms: what render::EnvironmentLighting::uniforms() gives

layout(set = 0, binding = 0, std140) uniform EngineFrame
{
    mat4 view_projection;
    mat4 sun_view_projection; // the sun's shadow map: orthographic over the level
    vec4 eye;                 // xyz; w: the distance where H6 gives way to H4
    vec4 sun_direction;  // xyz: towards the level's mixed sun; w: 1 when it is lit at run time (0: baked or
                         // off)
    vec4 sun_irradiance; // rgb: on a surface facing it; w: its shadowmask channel (0-3; -1: none)
    vec4 shadow;         // x: the shadow distance (from the eye); y: the fade band before it; z: 1 = the
                         // shadow map is drawn, 0 = static shadows alone (shadowmask, probes' occlusion)
    vec4 fog;            // rgb: fog colour; w: density per unit of distance (0: none)
    ivec4 mode; // x: lightmap basis (0: H6 near, H4 far; 1: H6; 2: H4); y: 1 = lighting only, 2 = the GGX
                // coat's light alone; z: 1 = the coat (specular)
    // World to the level's frame, where the level's light probes are (hemi_probe_irradiance over set 0's
    // texel buffer, which holds all the lookup needs).
    mat4 world_to_level;
    // The level's reflection probe (the glossy ball's; env below holds its maps' extents and the rotation
    // into the level's frame): its centre (w: 1) and box, in the level's frame.
    vec4 reflection_centre, reflection_min, reflection_max;
    EnvironmentUniforms env; // the glossy object's environment: the level's reflection probe
}
frame;

layout(push_constant) uniform EngineObject
{
    mat4 model;
    vec4 albedo;   // base colour factor
    ivec4 index;   // x: the PRT instance's first coefficient texel
    vec4 material; // x: GGX roughness (0: no coat), y: f0; z: a dynamic object's occlusion of the mixed sun
                   // from the level's probes (its static shadow beyond the shadow distance)
}
object;

#endif
