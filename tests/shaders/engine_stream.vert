#version 450
// An engine's own vertex shader reading a PRT model's coefficients as vertex streams (a test's, not
// hemi's): positions in stream 0, the four H4 coefficients of the vertex in stream 1 (PrtModel::
// coefficient_stream), read by the vertex input stage as the engine reads any other attribute. Its position
// comes from hemi's GLSL library, so its depth equals that of hemi's pipelines to the bit.
#extension GL_GOOGLE_include_directive : require
#include "hemi/hemi.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec4 in_c0;
layout(location = 2) in vec4 in_c1;
layout(location = 3) in vec4 in_c2;
layout(location = 4) in vec4 in_c3;

layout(push_constant) uniform EnginePush
{
    mat4 view_projection;
    mat4 model;
}
push;

layout(location = 0) out vec3 out_color;

void main()
{
    // The coefficients' sum: every one of them takes part, so a stale stream shows.
    out_color = in_c0.rgb + in_c1.rgb + in_c2.rgb + in_c3.rgb;
    vec3 world;
    gl_Position = hemi_clip_position(push.view_projection, push.model, in_position, world);
}
