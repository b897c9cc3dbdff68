#version 450
// The engine's depth-only vertex shader for its own objects (the spheres and the glossy ball), in the depth
// prepass and the shadow map; hemi's own pipelines draw the level and the PRT torus in the same passes.
// ENGINE_SHADOW: 1 = from the sun. Positions are computed exactly as main.vert does (precise).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 in_position;

void main()
{
    precise vec4 world = object.model * vec4(in_position, 1.0);
#if ENGINE_SHADOW
    precise vec4 clip = frame.sun_view_projection * world;
#else
    precise vec4 clip = frame.view_projection * world;
#endif
    gl_Position = clip;
}
