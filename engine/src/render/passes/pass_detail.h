#pragma once
// Internal helpers the transfer passes share (not installed): lighting checks and uploads, instance layout,
// CPCA validation.
#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>
#include <hemi/render/passes/transfer_matrices.h>

#include "hemi/shared/transfer.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <span>

namespace hemi::render::detail
{

// Throws std::invalid_argument unless `lighting` has L finite entries.
void check_lighting(std::span<const glm::vec3> lighting, uint32_t l);
// Sizes and cluster ids always (memory safety); the values' finiteness when `values` (once, when data are
// loaded onto the device; read_prt_asset has checked them too).
void validate_cpca(const CpcaMatrices& c, bool values = true);

uint64_t align_up(uint64_t value, uint64_t alignment);

// Instances of one source: instance i's lighting at i * stride bytes of the lighting buffer (a dynamic
// uniform offset), its coefficients at i * stride texels of the output (views at aligned offsets).
struct InstanceLayout
{
    uint32_t count = 1;
    VkDeviceSize lighting_stride = 0; // bytes
    uint64_t coefficient_stride = 0;  // texels
};
InstanceLayout instance_layout(const gpu::Device& device, uint32_t instances, uint32_t n, uint32_t k);

// How many instances `lighting` holds (L coefficients each); throws when it is not a whole number of them
// within the capacity from `first` on, or a value is not finite.
uint32_t lighting_instances(std::span<const glm::vec3> lighting, uint32_t l, uint32_t capacity,
                            uint32_t first = 0);
// The per-frame lighting both passes read, written through `buffer`'s persistent mapping (no command):
// instance first + i's L coefficients at (first + i) * stride bytes. The caller's frames in flight keep the
// GPU off these bytes (access.h).
void write_lighting(const gpu::Buffer& buffer, std::span<const glm::vec3> lighting, uint32_t l,
                    VkDeviceSize stride, uint32_t first = 0);
// The lighting buffer both passes make: host-visible, persistently mapped, `instances` slots of `stride`.
gpu::Buffer create_lighting_buffer(const gpu::Device& device, VkDeviceSize stride, uint32_t instances);

// Where a pass writes its coefficients (`bytes`: every instance's): a buffer of its own, or the caller's
// range `output` (an engine's buffer, read as a vertex stream), checked for room and texel-view alignment.
struct CoefficientStore
{
    gpu::Buffer own;
    gpu::BufferRange range;
};
// The host path's write of instance 0's coefficients (CoefficientSource::write_coefficients).
void write_coefficients(const gpu::Device& device, const CoefficientStore& store, std::span<const float> data,
                        uint32_t n, uint32_t k);
CoefficientStore coefficient_store(const gpu::Device& device, VkDeviceSize bytes,
                                   const gpu::BufferRange& output);

// Where a pass takes its descriptor sets from: the caller's allocator (a MaterialSystem's, which every pass
// and material of it shares) or, without one, an allocator of its own sized for `sets`. Declare it before the
// sets, which go back to it.
struct PassDescriptors
{
    std::unique_ptr<gpu::DescriptorAllocator> own;
    gpu::DescriptorAllocator* allocator = nullptr;
};
PassDescriptors pass_descriptors(const gpu::Device& device, gpu::DescriptorAllocator* shared, uint32_t sets);

} // namespace hemi::render::detail
