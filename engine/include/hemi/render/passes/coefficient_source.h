#pragma once
// What a per-vertex material reads: basis coefficients on the device, written each frame by a compute pass.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hemi::render
{

// What a PRT material reads: per-vertex basis coefficients on the device (texel v*K + k, RGBA32F), written
// each frame from the lighting by a compute pass. TransferPass (dense matrices) and CpcaTransferPass (CPCA)
// are the two sources; the materials take either.
class CoefficientSource
{
  public:
    virtual ~CoefficientSource() = default;
    // Records the lighting update and the compute work. The caller orders later reads of coefficients()
    // with a barrier from VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT / VK_ACCESS_SHADER_WRITE_BIT.
    // `lighting` holds L finite entries per instance, for 1 to instances() instances (instance i's at
    // i * L): every instance shares the matrices and is relit with its own lighting (each object's
    // environment rotated into its frame), into its own coefficients at instance_offset(i). With
    // `first_instance`, the lighting is that of instances first_instance, first_instance + 1, ... (a frame in
    // flight's range of instances: PrtModel).
    virtual void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                        uint32_t first_instance = 0) = 0;
    virtual uint32_t instances() const = 0;
    // Texels between two instances' coefficients (>= N*K, aligned for texel-buffer views).
    virtual uint64_t instance_stride() const = 0;
    uint64_t instance_offset(uint32_t instance) const { return instance * instance_stride(); }
    // Records, submits and waits (with the coefficients made visible to the host): for tools and tests.
    void run(std::span<const glm::vec3> lighting);
    virtual const gpu::Buffer& coefficients() const = 0;
    // Reads instance 0's coefficients back (N*K*4 floats).
    std::vector<float> read_coefficients() const;
    virtual uint32_t vertex_count() const = 0;
    virtual uint32_t k() const = 0;
    virtual uint32_t l() const = 0;
    virtual const gpu::Device& device() const = 0;
};

} // namespace hemi::render
