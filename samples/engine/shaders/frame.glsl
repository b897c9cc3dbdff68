// The engine sample's own frame data and draw constants (not hemi's): set 0 is the engine's per-frame block
// (one per frame in flight) and its shadow map, the push constants its per-object block. Shared by its
// depth, main and post shaders.
#ifndef ENGINE_FRAME_GLSL
#define ENGINE_FRAME_GLSL
#include "hemi/shared/surface.h" // EnvironmentUniforms: what render::EnvironmentLighting::uniforms() gives

#define ENGINE_SPHERES 3

layout(set = 0, binding = 0, std140) uniform EngineFrame
{
    mat4 view_projection;
    mat4 light_view_projection;
    vec4 eye;             // xyz; w: the distance where H6 gives way to H4
    vec4 light_position;  // the spot light, xyz; w: 1 on, 0 off
    vec4 light_axis;      // xyz: where it points; w: cosine of its cone's half angle
    vec4 light_intensity; // rgb: irradiance on a surface facing it at distance 1
    vec4 fog;             // rgb: fog colour; w: density per unit of distance (0: none)
    ivec4 mode;           // x: lightmap basis (0: H6 near, H4 far; 1: H6; 2: H4); y: 1 = lighting only
    vec4 probe_sh[ENGINE_SPHERES * 9]; // each sphere's SH9 irradiance from the level's probes
    EnvironmentUniforms env;           // the glossy object's environment (turning)
}
frame;

layout(push_constant) uniform EngineObject
{
    mat4 model;
    vec4 albedo; // base colour factor
    ivec4 index; // x: the sphere (its probe_sh), or the PRT instance's first coefficient texel
}
object;

#endif
