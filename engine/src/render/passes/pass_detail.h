#pragma once
// Internal helpers the transfer passes share (not installed): lighting checks and uploads, instance layout,
// CPCA validation.
#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>
#include <hemi/render/passes/transfer_matrices.h>

#include "hemi/shared/transfer.h"

#include <glm/vec3.hpp>

#include <cstdint>
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
// The per-frame lighting update both passes start with: instance first + i's L coefficients at
// (first + i) * stride bytes.
void record_lighting_update(VkCommandBuffer cmd, const gpu::Buffer& buffer,
                            std::span<const glm::vec3> lighting, uint32_t l, VkDeviceSize stride,
                            uint32_t first = 0);

} // namespace hemi::render::detail
