#include "pass_detail.h"

#include <hemi/gpu/commands.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::render::detail
{

void check_lighting(std::span<const glm::vec3> lighting, uint32_t l)
{
    if (lighting.size() != l)
        throw std::invalid_argument("hemi: transfer lighting has " + std::to_string(lighting.size()) +
                                    " coefficients, the matrices expect L = " + std::to_string(l));
    for (const glm::vec3& c : lighting)
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
            throw std::invalid_argument("hemi: transfer lighting contains a non-finite value");
}

void validate_cpca(const CpcaMatrices& c, bool values)
{
    validate_transfer_shape(c.vertex_count, c.k, c.l);
    const size_t d = size_t(c.k) * c.l;
    if (c.clusters == 0 || c.vectors == 0)
        throw std::invalid_argument("hemi: CPCA needs at least one cluster and one vector");
    if (c.means.size() != c.clusters * d || c.basis.size() != size_t(c.clusters) * c.vectors * d ||
        c.cluster.size() != c.vertex_count || c.weights.size() != size_t(c.vertex_count) * c.vectors)
        throw std::invalid_argument("hemi: CPCA array sizes do not match " + std::to_string(c.clusters) +
                                    "x" + std::to_string(c.vectors) + " clusters x vectors over " +
                                    std::to_string(c.vertex_count) + " vertices");
    for (uint32_t id : c.cluster)
        if (id >= c.clusters)
            throw std::invalid_argument("hemi: CPCA cluster id " + std::to_string(id) + " out of range");
    if (values)
        for (std::span<const float> array : {c.means, c.basis, c.weights})
            for (float v : array)
                if (!std::isfinite(v))
                    throw std::invalid_argument("hemi: CPCA data contain a non-finite value");
}

uint64_t align_up(uint64_t value, uint64_t alignment)
{
    alignment = std::max<uint64_t>(1, alignment);
    return (value + alignment - 1) / alignment * alignment;
}

InstanceLayout instance_layout(const gpu::Device& device, uint32_t instances, uint32_t n, uint32_t k)
{
    if (instances == 0)
        throw std::invalid_argument("hemi: a coefficient source needs at least one instance");
    const VkPhysicalDeviceLimits& limits = device.limits();
    InstanceLayout layout;
    layout.count = instances;
    layout.lighting_stride = align_up(HEMI_TRANSFER_MAX_L * 16, limits.minUniformBufferOffsetAlignment);
    layout.coefficient_stride =
        align_up(uint64_t(n) * k * 16,
                 std::lcm<uint64_t>(16, std::max<uint64_t>(1, limits.minTexelBufferOffsetAlignment))) /
        16;
    if (layout.coefficient_stride * instances > limits.maxTexelBufferElements)
        throw std::invalid_argument("hemi: " + std::to_string(instances) + " instances of " +
                                    std::to_string(n) +
                                    " vertices' coefficients exceed the device's maxTexelBufferElements");
    return layout;
}

// How many instances `lighting` holds (L coefficients each); throws when it is not a whole number of them
// within the capacity.
uint32_t lighting_instances(std::span<const glm::vec3> lighting, uint32_t l, uint32_t capacity,
                            uint32_t first)
{
    const uint32_t room = first < capacity ? capacity - first : 0;
    if (lighting.empty() || lighting.size() % l != 0 || lighting.size() / l > room)
        throw std::invalid_argument("hemi: lighting has " + std::to_string(lighting.size()) +
                                    " SH coefficients: expected L = " + std::to_string(l) +
                                    " per instance for 1 to " + std::to_string(room) + " instances" +
                                    (first ? " from instance " + std::to_string(first) : std::string()));
    for (size_t i = 0; i < lighting.size(); i += l)
        check_lighting(lighting.subspan(i, l), l);
    return uint32_t(lighting.size() / l);
}

// The per-frame lighting update both passes start with: instance i's L coefficients at i * stride bytes.
void record_lighting_update(VkCommandBuffer cmd, const gpu::Buffer& buffer,
                            std::span<const glm::vec3> lighting, uint32_t l, VkDeviceSize stride,
                            uint32_t first)
{
    const size_t instances = lighting.size() / l;
    std::vector<float> packed(instances * stride / 4, 0.0f);
    for (size_t i = 0; i < instances; ++i)
        for (uint32_t j = 0; j < l; ++j)
        {
            float* p = &packed[i * stride / 4 + j * 4];
            p[0] = lighting[i * l + j].x;
            p[1] = lighting[i * l + j].y;
            p[2] = lighting[i * l + j].z;
        }
    // Earlier reads of the lighting (a previous frame's dispatch) finish before the update; the update
    // finishes before this frame's dispatch reads it. Earlier reads of the coefficients (vertex shaders)
    // finish before this dispatch overwrites them.
    // ALL_COMMANDS as the source: valid on compute-only queues, and covers readers in any shader stage.
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                        VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                        VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    // vkCmdUpdateBuffer takes at most 65,536 bytes per call.
    const VkDeviceSize bytes = packed.size() * 4;
    for (VkDeviceSize offset = 0; offset < bytes; offset += 65536)
        vkCmdUpdateBuffer(cmd, buffer, first * stride + offset, std::min<VkDeviceSize>(65536, bytes - offset),
                          reinterpret_cast<const std::byte*>(packed.data()) + offset);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_UNIFORM_READ_BIT);
}

} // namespace hemi::render::detail
