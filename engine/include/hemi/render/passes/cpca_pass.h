#pragma once
// The CPCA per-frame transfer pass on the device (shaders/cpca_project.comp, then cpca_reconstruct.comp).

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

// The CPCA path on the device: a small dispatch projecting every cluster's mean and PCA matrices on the
// lighting ((V + 1) * K RGB values per cluster), then one invocation per vertex summing its V weighted
// projections. The per-frame memory traffic per vertex is V weights instead of K * L matrix elements.
class CpcaTransferPass : public CoefficientSource
{
  public:
    // Throws std::invalid_argument on inconsistent sizes, a cluster out of range or a non-finite value, and
    // std::runtime_error when the data exceed the device's storage-buffer range or texel-buffer size.
    // `instances`, `upload`, `descriptors` and `output` as for TransferPass.
    CpcaTransferPass(const gpu::Device& device, const CpcaMatrices& cpca, uint32_t instances = 1,
                     gpu::UploadBatch* upload = nullptr, gpu::DescriptorAllocator* descriptors = nullptr,
                     const gpu::BufferRange& output = {});
    ~CpcaTransferPass();
    CpcaTransferPass(const CpcaTransferPass&) = delete;
    CpcaTransferPass& operator=(const CpcaTransferPass&) = delete;

    // The lighting through mapped memory, the projections, one barrier (compute writes of the projections to
    // the reconstruction's uniform reads: a buffer no one else touches), the reconstruction. It reports five
    // accesses by the compute shader stage: the cluster matrices, weights, slots and the instances' lighting
    // read, their coefficients written.
    void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting, uint32_t first_instance = 0,
                AccessList* accesses = nullptr) override;
    gpu::BufferRange coefficients() const override;
    void write_coefficients(std::span<const float> coefficients) override;
    uint32_t vertex_count() const override;
    uint32_t k() const override;
    uint32_t l() const override;
    const gpu::Device& device() const override;
    uint32_t instances() const override;
    uint64_t instance_stride() const override;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace hemi::render
