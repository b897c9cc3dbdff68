#include "pass_detail.h"

#include <hemi/gpu/commands.h>

#include <algorithm>
#include <cmath>
#include <cstring>
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

void write_lighting(const gpu::Buffer& buffer, std::span<const glm::vec3> lighting, uint32_t l,
                    VkDeviceSize stride, uint32_t first)
{
    auto* base = static_cast<std::byte*>(buffer.mapped());
    const size_t instances = lighting.size() / l;
    for (size_t i = 0; i < instances; ++i)
    {
        auto* p = reinterpret_cast<float*>(base + (first + i) * stride);
        for (uint32_t j = 0; j < l; ++j)
        {
            p[j * 4 + 0] = lighting[i * l + j].x;
            p[j * 4 + 1] = lighting[i * l + j].y;
            p[j * 4 + 2] = lighting[i * l + j].z;
            p[j * 4 + 3] = 0.0f;
        }
    }
}

gpu::Buffer create_lighting_buffer(const gpu::Device& device, VkDeviceSize stride, uint32_t instances)
{
    gpu::Buffer buffer = gpu::create_buffer(
        device, {stride * instances, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, gpu::MemoryUsage::Dynamic});
    if (!buffer.mapped())
        throw std::runtime_error("hemi: the PRT lighting buffer got memory that is not mapped "
                                 "(a gpu::MemoryProvider must map MemoryUsage::Dynamic memory)");
    std::memset(buffer.mapped(), 0, stride * instances);
    device.set_name(VK_OBJECT_TYPE_BUFFER, buffer.handle(), "hemi PRT lighting");
    return buffer;
}

CoefficientStore coefficient_store(const gpu::Device& device, VkDeviceSize bytes,
                                   const gpu::BufferRange& output)
{
    CoefficientStore store;
    if (output.buffer == VK_NULL_HANDLE)
    {
        store.own = gpu::create_buffer(device, {bytes, VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT |
                                                           VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
        device.set_name(VK_OBJECT_TYPE_BUFFER, store.own.handle(), "hemi PRT coefficients");
        store.range = {store.own.handle(), 0, bytes};
        return store;
    }
    const uint64_t align =
        std::lcm<uint64_t>(16, std::max<uint64_t>(1, device.limits().minTexelBufferOffsetAlignment));
    if (output.size < bytes || output.offset % align != 0)
        throw std::invalid_argument("hemi: the coefficient output range (" + std::to_string(output.size) +
                                    " bytes at offset " + std::to_string(output.offset) + ") must hold " +
                                    std::to_string(bytes) + " bytes at an offset that is a multiple of " +
                                    std::to_string(align));
    store.range = {output.buffer, output.offset, bytes};
    return store;
}

void write_coefficients(const gpu::Device& device, const CoefficientStore& store, std::span<const float> data,
                        uint32_t n, uint32_t k)
{
    if (data.size() != size_t(n) * k * 4)
        throw std::invalid_argument("hemi: " + std::to_string(data.size()) + " coefficient floats for " +
                                    std::to_string(n) + " vertices of K = " + std::to_string(k) +
                                    " (expected N * K * 4)");
    if (store.own.handle() != VK_NULL_HANDLE)
        gpu::write_buffer(device, store.own, data.data(), data.size_bytes());
    else
        gpu::write_buffer(device, {store.range.buffer, store.range.offset, data.size_bytes()}, data.data());
}

PassDescriptors pass_descriptors(const gpu::Device& device, gpu::DescriptorAllocator* shared, uint32_t sets)
{
    PassDescriptors d;
    if (!shared)
        d.own = std::make_unique<gpu::DescriptorAllocator>(device, sets);
    d.allocator = shared ? shared : d.own.get();
    return d;
}

} // namespace hemi::render::detail
