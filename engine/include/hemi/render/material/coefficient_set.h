#pragma once
// Descriptor set 2 of the material system: where one object instance's coefficients come from.
//   VertexCoefficients: a transfer or CPCA pass's output buffer (per vertex; shared::DrawPush carries the
//                       instance's texel offset into it).
//   ProbeCoefficients:  one set of K RGB coefficients for the whole object (an SH9 irradiance probe in
//                       world space, say), updated per frame.
//   TexelCoefficients:  K coefficient maps sampled at TEXCOORD_1 (directional lightmaps): a K-layer 2D
//                       array image, bilinear, clamped to the edge.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/render/material/material_system.h>

#include <glm/vec3.hpp>

#include <span>

namespace hemi::render
{

class VertexCoefficients
{
  public:
    // Views `texels` RGBA32F texels of `coefficients` from its start (every instance of a multi-instance
    // source; draws pick theirs by shared::DrawPush::coefficient_offset). The buffer must outlive this.
    VertexCoefficients(const MaterialSystem& system, const gpu::Buffer& coefficients, uint64_t texels);
    VkDescriptorSet set() const { return set_.get(); }

  private:
    gpu::BufferView view_;
    gpu::DescriptorSet set_;
};

class ProbeCoefficients
{
  public:
    explicit ProbeCoefficients(const MaterialSystem& system);
    // Outside a render pass: up to HEMI_BASIS_MAX_SIZE RGB coefficients (finite; std::invalid_argument else).
    void record_update(VkCommandBuffer cmd, std::span<const glm::vec3> coefficients) const;
    VkDescriptorSet set() const { return set_.get(); }

  private:
    gpu::Buffer uniforms_;
    gpu::DescriptorSet set_;
};

class TexelCoefficients
{
  public:
    // `rgb` holds K maps of width x height RGB texels, map after map, rows from the top (v = 0), 3 floats a
    // texel: coefficient k of texel (x, y) is rgb[((k * height + y) * width + x) * 3 + c]. Stored as RGBA16F
    // (half floats, as lightmaps usually are; `full_precision` stores RGBA32F), uploaded through `upload`.
    // Throws std::invalid_argument for K outside [1, HEMI_BASIS_MAX_SIZE], a size mismatch or a value that
    // is not finite or does not fit a half float.
    TexelCoefficients(const MaterialSystem& system, uint32_t width, uint32_t height, uint32_t k,
                      std::span<const float> rgb, gpu::UploadBatch& upload, bool full_precision = false);
    VkDescriptorSet set() const { return set_.get(); }
    uint32_t k() const { return k_; }
    // For an engine's own shaders (hemi_lightmap_coefficients, docs/glsl.md): the K-layer image (a 2D_ARRAY
    // view, SHADER_READ_ONLY_OPTIMAL once the upload is recorded) and its bilinear, edge-clamped sampler.
    const gpu::Image& maps() const { return maps_; }
    VkSampler sampler() const { return sampler_; }

  private:
    gpu::Image maps_;
    gpu::Sampler sampler_;
    gpu::DescriptorSet set_;
    uint32_t k_ = 0;
};

} // namespace hemi::render
