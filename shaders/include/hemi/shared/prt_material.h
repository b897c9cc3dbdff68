// Uniform block and bindings of the PRT material (per-vertex basis coefficients from the transfer pass,
// basis evaluated per pixel at the tangent-space normal-map normal), shared by C++ and GLSL (std140).
#ifndef HEMI_SHARED_PRT_MATERIAL_H
#define HEMI_SHARED_PRT_MATERIAL_H

#ifdef __cplusplus
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
namespace hemi::shared
{
using mat4 = glm::mat4;
using vec4 = glm::vec4;
#endif

struct PrtMaterialUniforms
{
    mat4 view_projection;
    mat4 model;
    vec4 albedo;          // rgb multiplies the base colour texture; a = 1 uses the texture, 0 ignores it
    vec4 sep4_weights[9]; // math::sep4_weights() rows, read only by the separable basis
};

#define HEMI_PRT_MATERIAL_BINDING_UNIFORMS 0
#define HEMI_PRT_MATERIAL_BINDING_NORMAL_MAP 1
#define HEMI_PRT_MATERIAL_BINDING_COEFFICIENTS 2
#define HEMI_PRT_MATERIAL_BINDING_BASE_COLOR 3
// 9 RGB coefficients = 27 floats travel from the vertex to the fragment stage as 7 vec4.
#define HEMI_PRT_MATERIAL_PACKED_VEC4 7

#ifdef __cplusplus
static_assert(sizeof(PrtMaterialUniforms) == 64 + 64 + 16 + 9 * 16, "std140 layout");
} // namespace hemi::shared
#endif

#endif
