#pragma once
// The dense per-frame transfer pass on the device (shaders/prt_transfer.comp).

#include <hemi/render/passes/coefficient_source.h>
#include <hemi/render/passes/transfer_matrices.h>

#include <memory>

namespace hemi::gpu
{
class UploadBatch;
}

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
    // (a submit-and-wait when the device memory is not host-visible).
    TransferPass(const gpu::Device& device, const TransferMatrices& matrices, uint64_t max_view_texels = 0,
                 uint32_t instances = 1, gpu::UploadBatch* upload = nullptr);
    ~TransferPass();
    TransferPass(const TransferPass&) = delete;
    TransferPass& operator=(const TransferPass&) = delete;

    // Records: the lighting update (vkCmdUpdateBuffer, so no host synchronisation is needed between
    // frames), a barrier, and the dispatches. The caller orders later reads of coefficients() with a
    // barrier from VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT / VK_ACCESS_SHADER_WRITE_BIT.
    // `lighting` must have L entries of finite values.
    void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                uint32_t first_instance = 0) override;

    // RGBA32F texels: coefficient k of vertex v is texel v*K + k. Usable as a uniform texel buffer.
    const gpu::Buffer& coefficients() const override;

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
