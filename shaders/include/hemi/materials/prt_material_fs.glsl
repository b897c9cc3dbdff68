// The PRT material's fragment stage, included by prt_material.frag (colour + aux outputs, for hemi's
// OffscreenTarget) and prt_material_color.frag (colour only, for an engine's render pass with one colour
// attachment), with HEMI_PRT_MATERIAL_AUX set to 1 or 0.
#include "hemi/shared/prt_material.h"
#include "hemi/basis/all.glsl"

layout(constant_id = 0) const int kBasis = 0;
layout(constant_id = 1) const int K = 9;

layout(set = 0, binding = HEMI_PRT_MATERIAL_BINDING_UNIFORMS, std140) uniform Uniforms
{
    PrtMaterialUniforms u;
};
layout(set = 0, binding = HEMI_PRT_MATERIAL_BINDING_NORMAL_MAP) uniform sampler2D normal_map;
layout(set = 0, binding = HEMI_PRT_MATERIAL_BINDING_BASE_COLOR) uniform sampler2D base_color; // sRGB format

layout(location = 0) in vec4 in_packed[HEMI_PRT_MATERIAL_PACKED_VEC4];
layout(location = HEMI_PRT_MATERIAL_PACKED_VEC4) in vec2 in_uv;

layout(location = 0) out vec4 out_color;
#if HEMI_PRT_MATERIAL_AUX
layout(location = 1) out vec4 out_aux;
#endif

const float kPi = 3.14159265358979;

void main()
{
    vec3 n = normalize(texture(normal_map, in_uv).xyz * 2.0 - 1.0);
    float b[HEMI_BASIS_MAX_SIZE];
    hemi_eval_basis(kBasis, n, u.sep4_weights, b);
    vec3 e = vec3(0.0);
    [[unroll]] for (int k = 0; k < K; ++k)
    {
        int i = k * 3;
        vec3 c = vec3(in_packed[i / 4][i % 4], in_packed[(i + 1) / 4][(i + 1) % 4], in_packed[(i + 2) / 4][(i + 2) % 4]);
        e += c * b[k];
    }
    vec3 albedo = u.albedo.rgb * mix(vec3(1.0), texture(base_color, in_uv).rgb, u.albedo.a);
    out_color = vec4(albedo * e / kPi, 1.0);
#if HEMI_PRT_MATERIAL_AUX
    out_aux = vec4(in_uv, 0.0, 1.0);
#endif
}
