#version 450
// The engine's post pass: exposure, then a filmic tonemap (Narkowicz's fit of ACES) or, with it off, the
// plain clamp hemi-render's PNGs use; sRGB encoding by the swapchain's format, or here when it is UNORM.
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(push_constant) uniform Post
{
    float exposure;
    int tonemap; // 0: clamp
    int encode;  // 1: encode sRGB here (a UNORM swapchain)
}
post;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

vec3 aces(vec3 x)
{
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 srgb(vec3 c)
{
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main()
{
    vec3 c = texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb * post.exposure;
    c = post.tonemap != 0 ? aces(c) : clamp(c, 0.0, 1.0);
    out_color = vec4(post.encode != 0 ? srgb(c) : c, 1.0);
}
