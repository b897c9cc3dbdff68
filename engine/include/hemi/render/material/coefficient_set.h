#pragma once
// Descriptor set 2 of the material system: where one object instance's coefficients come from.
//   VertexCoefficients: a transfer or CPCA pass's output buffer (per vertex; shared::DrawPush carries the
//                       instance's texel offset into it).
//   ProbeBuffer:        one set of K RGB coefficients per object (an SH9 irradiance probe in world space,
//                       say), many objects and frames in flight in one buffer, updated per frame.
//   TexelCoefficients:  K coefficient maps sampled at TEXCOORD_1 (directional lightmaps), packed into the
//                       RGBA layers of a ceil(3K / 4)-layer 2D array image, bilinear, clamped to the edge;
//                       paged: only the 64 x 64-texel pages that hold texels are stored.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/render/material/material_system.h>

#include <hemi/io/block_maps.h>

#include <glm/vec3.hpp>

#include <array>
#include <span>

namespace hemi::render
{

class VertexCoefficients
{
  public:
    // Views `texels` RGBA32F texels of `coefficients` from its offset (every instance of a multi-instance
    // source; draws pick theirs by shared::DrawPush::coefficient_offset). The buffer must outlive this.
    VertexCoefficients(const MaterialSystem& system, const gpu::BufferRange& coefficients, uint64_t texels);
    VkDescriptorSet set() const { return set_.get(); }

  private:
    gpu::BufferView view_;
    gpu::DescriptorSet set_;
};

// Light-probe coefficients (an SH9 irradiance probe in world space, say) of many objects in one storage
// buffer: the descriptor set of every probe-lit draw. A draw picks its probe by shared::DrawPush::
// coefficient_offset = offset(frame, probe). `frames_in_flight` slots let an engine write frame N+1's
// lighting while the GPU still reads frame N's.
//   write():         through persistently mapped memory (host-visible, device-local where the device has
//                    such memory): no command, no barrier. Write slot `frame` only once the GPU has finished
//                    the frame that last read it (the engine's per-frame fence); the queue submission that
//                    follows makes the host writes visible.
//   record_update(): in the command buffer (vkCmdUpdateBuffer between two barriers), for a frame recorded and
//                    submitted at once (tools, tests, one object).
class ProbeBuffer
{
  public:
    // Throws std::invalid_argument for no probes or no frames.
    ProbeBuffer(const MaterialSystem& system, uint32_t probes, uint32_t frames_in_flight = 1);
    // Up to HEMI_BASIS_MAX_SIZE RGB coefficients (finite; std::invalid_argument else) of probe `probe` in
    // slot `frame` (< frames_in_flight); the rest of the probe's coefficients become 0. `occlusion`: the
    // share of each shadowmask channel's mixed light that reaches the object (io::LightProbes::occlusion_at;
    // in [0, 1]), by which hemi's materials multiply the frame's mixed lights
    // (DynamicLight::shadowmask_channel), stored in the fourth components of the probe's first four vec4s.
    using Occlusion = std::array<float, 4>;
    void write(uint32_t frame, uint32_t probe, std::span<const glm::vec3> coefficients,
               const Occlusion& occlusion = {1.0f, 1.0f, 1.0f, 1.0f});
    // Outside a render pass: the same, recorded (the previous reads of the buffer finish first).
    void record_update(VkCommandBuffer cmd, uint32_t frame, uint32_t probe,
                       std::span<const glm::vec3> coefficients,
                       const Occlusion& occlusion = {1.0f, 1.0f, 1.0f, 1.0f}) const;
    // shared::DrawPush::coefficient_offset of probe `probe` in slot `frame`.
    uint32_t offset(uint32_t frame, uint32_t probe) const;
    VkDescriptorSet set() const { return set_.get(); }
    uint32_t probes() const { return probes_; }
    uint32_t frames_in_flight() const { return frames_; }
    // For an engine's own shaders: vec4 coefficients, probe p of slot f from vec4 offset(f, p).
    const gpu::Buffer& buffer() const { return buffer_; }

  private:
    void pack(uint32_t frame, uint32_t probe, std::span<const glm::vec3> coefficients,
              const Occlusion& occlusion, glm::vec4* out) const;
    gpu::Buffer buffer_;
    gpu::DescriptorSet set_;
    uint32_t probes_ = 0, frames_ = 0;
};

class TexelCoefficients
{
  public:
    // The maps of a lightmap asset's output (io::BlockMaps, the blocks that hold texels), paged as
    // hemi_lightmap_coefficients(pages, page_table, ...) reads them (hemi/lib/coefficients.glsl): the atlas
    // is cut into pages of HEMI_LIGHTMAP_PAGE^2 texels, each page that holds a kept block gets a slot of the
    // packed maps with a one-texel border copied from its neighbours (the edge texels at the atlas's edge),
    // and the page table maps pages to slots. Memory follows the covered texels, and an atlas may be larger
    // than the device's largest image (up to 2^18 texels a side, BlockGrid's limit) as long as its stored
    // pages fit one image of slots: std::invalid_argument says how many pages that is.
    // With a `shadowmask` (io::LightmapAsset::shadowmask: 4 maps of the same atlas, channel c in map c), its
    // four channels are stored as one RGBA8 layer in the same slots (the pages of both maps' blocks), read by
    // hemi_lightmap_shadowmask(shadowmask(), page_table(), uv) and by hemi's materials for the frame's mixed
    // lights (DynamicLight::shadowmask_channel); without one, shadowmask() is a single white texel, so the
    // same lookup reads 1. Throws std::invalid_argument for a mask of another atlas or a value outside [0,
    // 1].
    TexelCoefficients(const MaterialSystem& system, const io::BlockMaps& maps, gpu::UploadBatch& upload,
                      bool full_precision = false, const io::BlockMaps* shadowmask = nullptr);
    // `rgb` holds K maps of width x height RGB texels, map after map, rows from the top (v = 0), 3 floats a
    // texel: coefficient k of texel (x, y) is rgb[((k * height + y) * width + x) * 3 + c]. Stored packed, as
    // hemi_lightmap_coefficients reads them: the texel's 3K floats fill the RGBA channels of
    // packed_layers(K) = ceil(3K / 4) layers in order (float f = 3 k + c is channel f % 4 of layer f / 4),
    // as RGBA16F (half floats, as lightmaps usually are, divided by the power-of-two scale() that the lookup
    // multiplies back, so light of any magnitude fits; `full_precision` stores RGBA32F), uploaded through
    // `upload`. Bilinear filtering is linear per channel, so packing changes no value.
    // Throws std::invalid_argument for K outside [1, HEMI_BASIS_MAX_SIZE], a size mismatch or a value that
    // is not finite.
    TexelCoefficients(const MaterialSystem& system, uint32_t width, uint32_t height, uint32_t k,
                      std::span<const float> rgb, gpu::UploadBatch& upload, bool full_precision = false);
    VkDescriptorSet set() const { return set_.get(); }
    uint32_t k() const { return k_; }
    // The layers K packed coefficients take: ceil(3K / 4) (sh9: 7, h6: 5, h4: 3, hl2 and rnm: 3, plain: 1).
    static constexpr uint32_t packed_layers(uint32_t k) { return (3 * k + 3) / 4; }
    // For an engine's own shaders (hemi_lightmap_coefficients(pages, page_table, ...), docs/glsl.md): the
    // packed_layers(K)-layer image of slots (a 2D_ARRAY view, SHADER_READ_ONLY_OPTIMAL once the upload is
    // recorded) with its bilinear sampler, and the R32_UINT page table with its nearest sampler.
    const gpu::Image& pages() const { return pages_; }
    VkSampler sampler() const { return sampler_; }
    const gpu::Image& page_table() const { return page_table_; }
    // The shadowmask's RGBA8 layer in the same slots (a 2D_ARRAY view of one layer; sampled with sampler()),
    // or one white texel.
    const gpu::Image& shadowmask() const { return shadowmask_; }
    bool has_shadowmask() const { return has_shadowmask_; }
    VkSampler table_sampler() const { return table_sampler_; }
    uint32_t stored_pages() const { return stored_pages_; }
    // The power of two the stored halves are times (io/half_scale.h; 1 unless the values leave [2^-6, 2^15],
    // always 1 at full precision). The page table holds it (texel 2 of its last row), so the paged lookup
    // applies it; an engine that reads pages() with its own lookup multiplies by it.
    float scale() const { return scale_; }

  private:
    gpu::Image pages_, page_table_, shadowmask_;
    bool has_shadowmask_ = false;
    gpu::Sampler sampler_, table_sampler_;
    uint32_t stored_pages_ = 0;
    float scale_ = 1.0f;
    gpu::DescriptorSet set_;
    uint32_t k_ = 0;
};

} // namespace hemi::render
