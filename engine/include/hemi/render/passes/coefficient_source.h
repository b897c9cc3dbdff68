#pragma once
// What a per-vertex material reads: basis coefficients on the device, written each frame by a compute pass.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>
#include <hemi/render/access.h>

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
    // Writes the lighting through persistently mapped memory (no command) and records the compute work that
    // relights the instances. Records no barrier (CpcaTransferPass: one, between its two dispatches, on a
    // buffer only it touches): `accesses`, when given, receives what the work reads and writes on the device
    // (access.h), from which the caller orders it after earlier reads of the same coefficients and ahead of
    // later ones (record_barrier, or the engine's render graph). The instances' lighting must not be in use
    // by the GPU (the caller's frames in flight, access.h).
    // `lighting` holds L finite entries per instance, for 1 to instances() instances (instance i's at
    // i * L): every instance shares the matrices and is relit with its own lighting (each object's
    // environment rotated into its frame), into its own coefficients at instance_offset(i). With
    // `first_instance`, the lighting is that of instances first_instance, first_instance + 1, ... (a frame in
    // flight's range of instances: PrtModel).
    virtual void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting, uint32_t first_instance = 0,
                        AccessList* accesses = nullptr) = 0;
    // The coefficients of instances [first, first + count) accessed by `stages` with `access`: what record()
    // reports it writes, and what draws reading them declare (PrtModel::draw_accesses).
    BufferAccess coefficient_access(uint32_t first, uint32_t count, VkPipelineStageFlags stages,
                                    VkAccessFlags access) const;
    virtual uint32_t instances() const = 0;
    // Texels between two instances' coefficients (>= N*K, aligned for texel-buffer views).
    virtual uint64_t instance_stride() const = 0;
    uint64_t instance_offset(uint32_t instance) const { return instance * instance_stride(); }
    // Records, submits and waits (with the coefficients made visible to the host): for tools and tests.
    void run(std::span<const glm::vec3> lighting);
    // Where the coefficients are: the pass's own buffer, or the caller's output range. Texel t of the
    // source is at coefficients().offset + 16 t; as a vertex stream, vertex v of instance i reads K
    // RGBA32F attributes at stride 16 K from byte offset coefficients().offset + 16 instance_offset(i).
    virtual gpu::BufferRange coefficients() const = 0;
    // The host path: instance 0's coefficients computed by the CPU (N*K*4 floats) written where the draws
    // read them (a memcpy into the pass's own buffer when it is mapped, else a copy, waited for).
    virtual void write_coefficients(std::span<const float> coefficients) = 0;
    // Reads instance 0's coefficients back (N*K*4 floats).
    std::vector<float> read_coefficients() const;
    virtual uint32_t vertex_count() const = 0;
    virtual uint32_t k() const = 0;
    virtual uint32_t l() const = 0;
    virtual const gpu::Device& device() const = 0;
};

} // namespace hemi::render
