#pragma once
// Descriptor set 2 of the environment source (CoefficientSourceKind::Environment): what Heidrich & Seidel's
// materials read (the factored, banks, env_mirror and env_glossy techniques,
// shaders/include/hemi/techniques/). It holds one environment asset's maps (hemi-bake envmap: the mirror map
// with its solid-angle mipmaps as baked, one glossy map, the diffuse map, the Fresnel tables), a factored
// BRDF's tables (hemi-bake brdf) and the material's weights, so one set serves one (environment, material)
// pair; objects with the same pair share it.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/math/brdf.h>
#include <hemi/render/material/material_system.h>

#include <glm/mat3x3.hpp>

#include <span>

namespace hemi::render
{

struct EnvironmentMaterial
{
    float kd = 1.0f;      // diffuse weight (times the base colour): the diffuse map, Lambert for lights
    float ks = 1.0f;      // specular weight: the BRDF tables' term, the glossy map
    uint32_t glossy = 0;  // which of the asset's glossy maps (exponents) env_glossy reads
    uint32_t fresnel = 0; // which of the asset's Fresnel tables (indices of refraction) env_mirror reads
    bool coating = false; // env_mirror: F L_m + (1 - F) L_d (a coated diffuse surface) for F L_m + L_d
    glm::mat3 world_to_env{1.0f}; // rotation from world space into the environment's (z up: identity)
};

class EnvironmentLighting
{
  public:
    // `brdf` holds the factored BRDF's tables, one layer each, all of one size: Torrance-Sparrow's FD and G
    // (channel 0 each), or Banks' one table (channels diffuse, specular); empty binds zero tables (for the
    // env_* techniques). Maps are RGBA32F where the device filters it linearly, else RGBA16F (radiance
    // clamped to 65504). Throws std::invalid_argument for an inconsistent asset (io::envmap_problem), a
    // glossy or Fresnel index the asset does not have, tables of different sizes or neither
    // Torrance-Sparrow's nor Banks', weights that are not finite, or a world_to_env that is not a rotation.
    EnvironmentLighting(const MaterialSystem& system, const io::EnvmapAsset& environment,
                        std::span<const math::BrdfTable> brdf, const EnvironmentMaterial& material,
                        gpu::UploadBatch& upload);
    VkDescriptorSet set() const { return set_.get(); }
    // Outside a render pass: new weights, blend or rotation (the glossy and Fresnel indices are fixed).
    void record_update(VkCommandBuffer cmd, const EnvironmentMaterial& material) const;
    VkFormat map_format() const { return map_format_; }

    // For an engine's own shaders (hemi/lib/environment.glsl, docs/glsl.md): the uploaded maps and tables
    // (2D_ARRAY views but the Fresnel table's 2D one, SHADER_READ_ONLY_OPTIMAL once the upload is recorded),
    // the trilinear sampler hemi reads them with, and the values its uniform block holds for `material`
    // (extents, weights, the Fresnel row's coordinate, table sizes, the rotation's rows).
    const gpu::Image& mirror_map() const { return mirror_; }
    const gpu::Image& glossy_map() const { return glossy_; }
    const gpu::Image& diffuse_map() const { return diffuse_; }
    const gpu::Image& fresnel_table() const { return fresnel_; }
    const gpu::Image& brdf_tables() const { return brdf_; }
    VkSampler sampler() const { return sampler_; }
    shared::EnvironmentUniforms uniforms(const EnvironmentMaterial& material) const;

  private:
    gpu::Image mirror_, glossy_, diffuse_, fresnel_, brdf_;
    gpu::Sampler sampler_;
    gpu::Buffer uniforms_;
    gpu::DescriptorSet set_;
    VkFormat map_format_ = VK_FORMAT_UNDEFINED;
    float extents_[3] = {1, 1, 1};
    uint32_t fresnel_rows_ = 1, fresnel_samples_ = 2, fresnel_row_ = 0, table_size_ = 2;
};

} // namespace hemi::render
