// Uniform block of the SH normal-mapping raster pass, shared by C++ and GLSL (std140 layout).
#ifndef HEMI_SHARED_SH_NORMALMAP_H
#define HEMI_SHARED_SH_NORMALMAP_H

#ifdef __cplusplus
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
namespace hemi::shared
{
using mat4 = glm::mat4;
using vec4 = glm::vec4;
#endif

struct ShNormalMapUniforms
{
    mat4 view_projection;
    mat4 model;       // rotation, uniform scale and translation (normals use its upper 3x3)
    vec4 albedo;      // rgb, a unused
    vec4 irradiance[9]; // SH9 irradiance coefficients A_l L_lm (rgb) in world space
};

#define HEMI_SH_NORMALMAP_BINDING_UNIFORMS 0
#define HEMI_SH_NORMALMAP_BINDING_NORMAL_MAP 1

#ifdef __cplusplus
static_assert(sizeof(ShNormalMapUniforms) == 64 + 64 + 16 + 9 * 16, "std140 layout");
} // namespace hemi::shared
#endif

#endif
