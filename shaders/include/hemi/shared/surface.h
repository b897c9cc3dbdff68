// The material system's surface shader interface, shared by C++ and GLSL (std140/std430-compatible):
// descriptor sets, bindings, the variant and specialization-constant values, uniform blocks and push
// constants. docs/materials.md explains the design.
//
// Sets: 0 = the frame (camera, options; one per view), 1 = the material (factors and textures; one per
// glTF material, shared by every object that uses it), 2 = the coefficient source (one per object
// instance: its transfer-pass output, its coefficient textures, or its SH probe).
#ifndef HEMI_SHARED_SURFACE_H
#define HEMI_SHARED_SURFACE_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
namespace hemi::shared
{
using mat4 = glm::mat4;
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
using uint = uint32_t;
#endif

#define HEMI_SET_FRAME 0
#define HEMI_SET_MATERIAL 1
#define HEMI_SET_SOURCE 2

#define HEMI_FRAME_BINDING_UNIFORMS 0
#define HEMI_FRAME_BINDING_INSTANCES 1
#define HEMI_MATERIAL_BINDING_UNIFORMS 0
#define HEMI_MATERIAL_BINDING_BASE_COLOR 1
#define HEMI_MATERIAL_BINDING_NORMAL 2
#define HEMI_MATERIAL_BINDING_EMISSIVE 3
#define HEMI_MATERIAL_BINDING_OCCLUSION 4
#define HEMI_SOURCE_BINDING_COEFFICIENTS 0
#define HEMI_SOURCE_BINDING_PAGE_TABLE 1 // texel source: the paged lightmap's page table
#define HEMI_SOURCE_BINDING_SHADOWMASK 2 // texel source: the mixed lights' shadowmask, in the pages' slots

// Coefficient sources (a shader variant each: they bind different descriptor types).
#define HEMI_SOURCE_VERTEX 0  // uniform texel buffer, texel offset + v*K + k (transfer / CPCA pass output)
#define HEMI_SOURCE_TEXEL 1   // 2D array texture, layer k, sampled at TEXCOORD_1 (lightmaps)
#define HEMI_SOURCE_UNIFORM 2 // K vec4 per object in a storage buffer (an SH probe; render::ProbeBuffer)
#define HEMI_SOURCE_ENVIRONMENT                                                                              \
    3 // parabolic environment maps, Fresnel and BRDF tables (Heidrich & Seidel 1999)

// Set 2 of the environment source (render::EnvironmentLighting).
#define HEMI_ENV_BINDING_UNIFORMS 0
#define HEMI_ENV_BINDING_MIRROR                                                                              \
    1 // sampler2DArray: the mirror map, layer 0 front (z >= 0), 1 back, its mip chain
#define HEMI_ENV_BINDING_GLOSSY 2  // sampler2DArray: the material's prefiltered glossy map
#define HEMI_ENV_BINDING_DIFFUSE 3 // sampler2DArray: the diffuse map (E / pi)
#define HEMI_ENV_BINDING_FRESNEL 4 // sampler2D: the Fresnel table, a row per index of refraction
#define HEMI_ENV_BINDING_BRDF 5    // sampler2DArray: the factored BRDF's tables (a layer each)

// Frames the coefficients are expressed in (specialization constant).
#define HEMI_FRAME_TANGENT 0 // the normal-map tangent frame: the map's normal evaluates the basis directly
#define HEMI_FRAME_WORLD 1   // world space: the map's normal is turned into world space first

// Techniques (specialization constant): HEMI_TECHNIQUE_<NAME>, generated from the declarations in
// shaders/include/hemi/techniques/*.glsl (one file each).
#include "hemi/shared/techniques_generated.h"

// Specialization constant ids.
#define HEMI_SPEC_BASIS 0
#define HEMI_SPEC_K 1
#define HEMI_SPEC_FRAME 2
#define HEMI_SPEC_TECHNIQUE 3
#define HEMI_SPEC_DOUBLE_SIDED 4
#define HEMI_SPEC_ALPHA 5           // HEMI_ALPHA_*
#define HEMI_SPEC_LIGHTMAP_FILTER 6 // HEMI_LIGHTMAP_FILTER_*

// Lightmap lookups (specialization constant HEMI_SPEC_LIGHTMAP_FILTER): the linear filter, or the cubic
// B-spline of hemi_lightmap_coefficients_bicubic (four linear fetches per packed layer).
#define HEMI_LIGHTMAP_FILTER_LINEAR 0
#define HEMI_LIGHTMAP_FILTER_BICUBIC 1

// Alpha modes (glTF alphaMode; specialization constant HEMI_SPEC_ALPHA).
#define HEMI_ALPHA_OPAQUE 0 // alpha ignored, output alpha 1
#define HEMI_ALPHA_MASK 1   // discarded where alpha < the material's alphaCutoff, output alpha 1
#define HEMI_ALPHA_BLEND 2  // output alpha = base colour alpha (the pipeline blends)

// Dynamic lights (added to the precomputed lighting by the techniques that take them: rnm, rnm_ao, ssbump).
#define HEMI_MAX_LIGHTS 4

struct FrameUniforms
{
    mat4 view_projection;
    vec4 options;         // x = 1: lighting only (albedo 1, no emissive); y = dynamic lights; z = specular
                          // exponent, w = specular strength of the dynamic lights
    vec4 sep4_weights[9]; // math::sep4_weights() rows, read only by the separable basis
    vec4 eye;             // xyz: the camera's position (world)
    vec4 light_position[HEMI_MAX_LIGHTS];   // w = 0: xyz towards a directional light; w = 1: a point light at
                                            // xyz
    vec4 light_irradiance[HEMI_MAX_LIGHTS]; // rgb: on a surface facing it (a point light: at distance 1, /
                                            // d^2); w: 1 + the shadowmask channel of a mixed light (0: none)
    vec4 light_spot[HEMI_MAX_LIGHTS];       // xyz: where a spot light points (unit; 0: not a spot); w: glTF's
                                            // range of a point or spot light (0: none)
    vec4 light_cone[HEMI_MAX_LIGHTS]; // a spot light's x = cos(outer cone), y = 1 / max(0.001, cos(inner)
                                      // - cos(outer)) (glTF's smooth cone); zw unused
    vec4 glossy;                      // the GGX coat: x = roughness (0: none), y = f0; zw unused
};

struct MaterialUniforms
{
    vec4 base_color_factor; // linear rgba
    vec4 emissive_factor;   // rgb linear; a = normal scale
    vec4 uv_transform[8]; // rows of the 2x3 KHR_texture_transform of base colour, normal, emissive, occlusion
    uvec4 texcoord;       // UV set (0 or 1) of base colour, normal, emissive, occlusion
    vec4 occlusion;       // x = glTF's occlusion strength; y = alphaCutoff (MASK); zw unused
};

// The environment source's uniforms (set 2, binding HEMI_ENV_BINDING_UNIFORMS).
#define HEMI_MAX_REFLECTION_PROBES 4 // blended by one environment material
struct EnvironmentUniforms
{
    vec4 extents;  // x, y, z: the mirror, glossy and diffuse maps' extents (math/paraboloid.h); w: unused
    vec4 material; // x = kd (diffuse weight), y = ks (specular weight), z = the Fresnel row's v coordinate,
                   // w = blend: 0 = F L_m + L_d, 1 = F L_m + (1 - F) L_d (a coating, section 4.4)
    vec4 tables;   // x = the BRDF tables' size, y = the Fresnel table's samples, z = the reflection probes
                   // blended (0: none, the environment is a sky), w unused
    vec4 world_to_env[3]; // rows of the rotation from world space into the environment's (x, y, z); w: the
                          // offset that places world points there (p_env = R p + w), for box projection
    // Reflection probes' box projection and blend (docs/probes.md), in the environment's frame: probe k's
    // centre (w: the fade of its influence, hemi_box_influence) and influence box; its maps are layers 2k and
    // 2k + 1 of the environment's images.
    vec4 probe_centre[HEMI_MAX_REFLECTION_PROBES];
    vec4 probe_box_min[HEMI_MAX_REFLECTION_PROBES];
    vec4 probe_box_max[HEMI_MAX_REFLECTION_PROBES];
};

// Per draw: the object's model matrix and where its coefficients start in the source's texel buffer. The
// same 96 bytes (std430) are an instance record of the frame's instance buffer (set 0, binding
// HEMI_FRAME_BINDING_INSTANCES; render::FrameSet::write_instances): a draw whose push has `instanced` = 1
// draws instanceCount instances, instance i with record firstInstance + i's model, coefficient_offset and
// lightmap_scale_offset, and its draw_id where the record's is not 0 (else the push's).
struct DrawPush
{
    mat4 model; // object to world (normals through its inverse transpose: any scale, mirrors)
    uint
        coefficient_offset; // texels (vertex source) or vec4s (probe source) of this draw's first coefficient
    uint draw_id;           // written to the aux attachment's blue channel (0 = background): picking, tests
    uint instanced;         // push constants only: 1 = read each instance's values from the instance buffer
    uint pad1;
    // Texel source: where this draw's lightmap lookup goes, TEXCOORD_1 * xy + zw, so that several objects
    // share one atlas, each in its own rectangle (default: (1, 1, 0, 0), the whole atlas).
#ifdef __cplusplus
    vec4 lightmap_scale_offset{1.0f, 1.0f, 0.0f, 0.0f};
#else
    vec4 lightmap_scale_offset;
#endif
};

#ifdef __cplusplus
static_assert(sizeof(FrameUniforms) == 64 + 16 + 9 * 16 + 16 + 4 * HEMI_MAX_LIGHTS * 16 + 16,
              "std140 layout");
static_assert(sizeof(MaterialUniforms) == 16 * 10 + 16 + 16, "std140 layout");
static_assert(sizeof(DrawPush) == 96, "push constants (within the 128 bytes every device has)");
static_assert(sizeof(EnvironmentUniforms) == 6 * 16 + 3 * HEMI_MAX_REFLECTION_PROBES * 16, "std140 layout");
} // namespace hemi::shared
#endif

#endif
