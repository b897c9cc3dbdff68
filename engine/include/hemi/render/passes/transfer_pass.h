#pragma once
// The dense per-frame transfer pass on the device (shaders/prt_transfer.comp).

#include <hemi/render/passes/coefficient_source.h>
#include <hemi/render/passes/transfer_matrices.h>

#include <memory>

namespace hemi::gpu
{
class DescriptorAllocator;
class UploadBatch;
} // namespace hemi::gpu

namespace hemi::render
{

// Device path. Owns the matrices' GPU copy, the lighting uniform buffer, the output coefficient buffer and
// the compute pipeline; one dispatch per segment of at most maxTexelBufferElements texels.
class TransferPass : public CoefficientSource
{
  public:
    // `max_view_texels` bounds the texels of one texel-buffer view (and so one dispatch's segment);
    // 0 means the device's maxTexelBufferElements. Smaller values exist to exercise segmenting in tests.
    // `instances` objects can be relit per frame from the one copy of the matrices. With `upload`, the
    // matrices are staged there (the caller records it before the first record()); without, written now
    // (a submit-and-wait when the device memory is not host-visible). The descriptor sets come from
    // `descriptors` (a MaterialSystem's, shared with every other pass and material), or without it from a
    // pool of the pass's own. The coefficients go to `output` when it names a buffer (the engine's, with
    // STORAGE_TEXEL_BUFFER usage, plus UNIFORM_TEXEL_BUFFER for hemi's materials and VERTEX_BUFFER for the
    // engine's own vertex stream): instances() * instance_stride() * 16 bytes from an offset aligned to 16
    // and minTexelBufferOffsetAlignment (std::invalid_argument else); else to a buffer of the pass's own.
    TransferPass(const gpu::Device& device, const TransferMatrices& matrices, uint64_t max_view_texels = 0,
                 uint32_t instances = 1, gpu::UploadBatch* upload = nullptr,
                 gpu::DescriptorAllocator* descriptors = nullptr, const gpu::BufferRange& output = {});
    ~TransferPass();
    TransferPass(const TransferPass&) = delete;
    TransferPass& operator=(const TransferPass&) = delete;

    // The lighting through mapped memory, then one dispatch per segment and instance; no barrier
    // (CoefficientSource::record). It reports three accesses: the matrices and the instances' lighting read,
    // their coefficients written, all by the compute shader stage.
    void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting, uint32_t first_instance = 0,
                AccessList* accesses = nullptr) override;

    // RGBA32F texels: coefficient k of vertex v is texel v*K + k. Usable as a uniform texel buffer.
    gpu::BufferRange coefficients() const override;
    void write_coefficients(std::span<const float> coefficients) override;

    uint32_t vertex_count() const override;
    uint32_t k() const override;
    uint32_t l() const override;
    const gpu::Device& device() const override;
    uint32_t segment_count() const;
    uint32_t instances() const override;
    uint64_t instance_stride() const override;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace hemi::render
