#pragma once
// Descriptor set 2 of the environment source (CoefficientSourceKind::Environment): what Heidrich & Seidel's
// materials read (the factored, banks, env_mirror and env_glossy techniques,
// shaders/include/hemi/techniques/). It holds one environment asset's maps (hemi-bake envmap: the mirror map
// with its solid-angle mipmaps as baked, one glossy map, the diffuse map, the Fresnel tables), a factored
// BRDF's tables (hemi-bake brdf) and the material's weights, so one set serves one (environment, material)
// pair; objects with the same pair share it. The environment's maps are an EnvironmentMaps, uploaded once
// and shared by every material lit by that environment.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/math/brdf.h>
#include <hemi/render/material/material_system.h>

#include <glm/mat3x3.hpp>

#include <memory>
#include <span>
#include <vector>

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
    // Reflection probes (docs/probes.md): with box_projection, the environment's maps are reflection probes'
    // (EnvironmentMaps::probe_count() of them, one `probes` entry each, in the environment's frame, which a
    // world point p reaches as world_to_env p + world_to_env_offset). env_mirror and env_glossy look each
    // probe up towards where the reflected ray leaves its influence box, seen from its centre (parallax
    // correction), and blend the probes whose box holds the point by math::box_influence(p, box, fade) over
    // their sum, the diffuse map too; a point in no box takes probe 0. Off: the environment is infinitely far
    // (a sky).
    struct Probe
    {
        glm::vec3 centre{0.0f}, box_min{0.0f}, box_max{0.0f};
        float fade = 0.0f; // how deep inside its box a probe counts fully (box_influence); 0: a hard edge
    };
    bool box_projection = false;
    glm::vec3 world_to_env_offset{0.0f};
    std::vector<Probe> probes;
};

// How an environment's parabolic maps are stored on the GPU. Radiance is never negative, and the maps are
// sampled with the GPU's trilinear filter, so each choice is a filterable format:
// - Float: RGBA32F, 16 bytes a texel, exact (where the device filters RGBA32F linearly, else as Half);
// - Half: RGBA16F, 8 bytes, within 2^-11 of each value (relative) up to 65504;
// - SharedExponent: E5B9G9R9, 4 bytes, each channel within 2^-9 of the texel's largest channel, up to
//   65408 (a hue whose channels differ by 100x keeps 1% of its smallest);
// - Auto (the default): Half where every value of the asset fits it, else Float (an unclamped sun).
// Measured on a mirror sphere (tests/render/factored_material_test.cpp, docs/factored.md): against Float,
// Half changes a rendered pixel by at most 0.043% of its largest channel, SharedExponent by 0.19%.
enum class MapPrecision
{
    Auto,
    Float,
    Half,
    SharedExponent,
};

// One environment asset's maps on the GPU (every map and table of the asset: the mirror chain, each glossy
// map, the diffuse map, the Fresnel tables) and the trilinear sampler hemi reads them with, stored as
// `precision` says. Throws std::invalid_argument for an inconsistent asset (io::envmap_problem) and, for
// Half or SharedExponent asked for explicitly, for radiance beyond the format's range (naming the value).
class EnvironmentMaps
{
  public:
    EnvironmentMaps(const gpu::Device& device, const io::EnvmapAsset& environment, gpu::UploadBatch& upload,
                    MapPrecision precision = MapPrecision::Auto);
    // Several reflection probes' maps in one set of images, probe k's halves in layers 2k and 2k + 1 (for a
    // material that blends them: EnvironmentMaterial::probes). The probes must be alike, as one hemi-bake
    // lightmap job bakes them (the same sizes, mip levels, extents and glossy exponents); the Fresnel
    // tables are the first one's. Throws std::invalid_argument for none, more than
    // HEMI_MAX_REFLECTION_PROBES, an inconsistent asset or probes that differ (naming which and how).
    EnvironmentMaps(const gpu::Device& device, std::span<const io::EnvmapAsset> probes,
                    gpu::UploadBatch& upload, MapPrecision precision = MapPrecision::Auto);
    uint32_t probe_count() const { return probe_count_; }

    const gpu::Image& mirror_map() const { return mirror_; }
    // Glossy map `i` (std::out_of_range past glossy_count()); the diffuse map when the asset has none.
    const gpu::Image& glossy_map(uint32_t i) const;
    const gpu::Image& diffuse_map() const { return diffuse_; }
    const gpu::Image& fresnel_table() const { return fresnel_; }
    VkSampler sampler() const { return sampler_; }
    // RGBA32F, RGBA16F or E5B9G9R9 (MapPrecision).
    VkFormat map_format() const { return map_format_; }
    // Bytes of every map's texels on the GPU (all levels), for an engine's budget.
    VkDeviceSize map_bytes() const { return map_bytes_; }
    uint32_t glossy_count() const { return uint32_t(glossy_.size()); }
    uint32_t fresnel_count() const { return fresnel_count_; } // the asset's tables (indices of refraction)
    uint32_t fresnel_rows() const { return fresnel_rows_; }   // of the table image: 1 without any
    uint32_t fresnel_samples() const { return fresnel_samples_; }
    // The maps' extents (the paraboloid's coordinate range), as the uniform block holds them.
    float mirror_extent() const { return mirror_extent_; }
    float glossy_extent(uint32_t i) const;
    float diffuse_extent() const { return diffuse_extent_; }

  private:
    gpu::Image mirror_, diffuse_, fresnel_;
    std::vector<gpu::Image> glossy_;
    std::vector<float> glossy_extents_;
    gpu::Sampler sampler_;
    VkFormat map_format_ = VK_FORMAT_UNDEFINED;
    VkDeviceSize map_bytes_ = 0;
    float mirror_extent_ = 1.0f, diffuse_extent_ = 1.0f;
    uint32_t fresnel_count_ = 0, fresnel_rows_ = 1, fresnel_samples_ = 2, probe_count_ = 1;
};

class EnvironmentLighting
{
  public:
    // The material over maps shared with other materials (`maps` stays alive as long as any of them).
    EnvironmentLighting(const MaterialSystem& system, std::shared_ptr<const EnvironmentMaps> maps,
                        std::span<const math::BrdfTable> brdf, const EnvironmentMaterial& material,
                        gpu::UploadBatch& upload);
    // `brdf` holds the factored BRDF's tables, one layer each, all of one size: Torrance-Sparrow's FD and G
    // (channel 0 each), or Banks' one table (channels diffuse, specular); empty binds zero tables (for the
    // env_* techniques). The environment's maps (all of them, every glossy map too) are uploaded for this
    // material alone (an EnvironmentMaps of its own; share one between materials with the constructor
    // above). Nothing is uploaded for a material that is refused. Throws std::invalid_argument for an
    // inconsistent asset (io::envmap_problem), a glossy or Fresnel index the asset does not have, tables of
    // different sizes or neither Torrance-Sparrow's nor Banks', weights that are not finite, a
    // world_to_env that is not a rotation, or a box projection without one valid box for each probe the
    // maps hold (maps of several probes need it).
    EnvironmentLighting(const MaterialSystem& system, const io::EnvmapAsset& environment,
                        std::span<const math::BrdfTable> brdf, const EnvironmentMaterial& material,
                        gpu::UploadBatch& upload);
    VkDescriptorSet set() const { return set_.get(); }
    // Outside a render pass: new weights, blend or rotation (the glossy and Fresnel indices are fixed).
    void record_update(VkCommandBuffer cmd, const EnvironmentMaterial& material) const;
    VkFormat map_format() const { return maps_->map_format(); }
    const std::shared_ptr<const EnvironmentMaps>& maps() const { return maps_; }

    // For an engine's own shaders (hemi/lib/environment.glsl, docs/glsl.md): the uploaded maps and tables
    // (2D_ARRAY views but the Fresnel table's 2D one, SHADER_READ_ONLY_OPTIMAL once the upload is recorded),
    // the trilinear sampler hemi reads them with, and the values its uniform block holds for `material`
    // (extents, weights, the Fresnel row's coordinate, table sizes, the rotation's rows).
    const gpu::Image& mirror_map() const { return maps_->mirror_map(); }
    const gpu::Image& glossy_map() const { return maps_->glossy_map(glossy_); }
    const gpu::Image& diffuse_map() const { return maps_->diffuse_map(); }
    const gpu::Image& fresnel_table() const { return maps_->fresnel_table(); }
    const gpu::Image& brdf_tables() const { return brdf_; }
    VkSampler sampler() const { return maps_->sampler(); }
    shared::EnvironmentUniforms uniforms(const EnvironmentMaterial& material) const;

  private:
    std::shared_ptr<const EnvironmentMaps> maps_;
    gpu::Image brdf_;
    gpu::Buffer uniforms_;
    gpu::DescriptorSet set_;
    uint32_t glossy_ = 0, fresnel_row_ = 0, table_size_ = 2;
};

} // namespace hemi::render
