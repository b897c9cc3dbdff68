#version 450
// engine_stream.vert's colour into hemi's offscreen target (colour and aux, as hemi's materials write them).
layout(location = 0) in vec3 in_color;
layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_aux;

void main()
{
    out_color = vec4(in_color, 1.0);
    out_aux = vec4(0.0, 0.0, 0.0, 1.0);
}
