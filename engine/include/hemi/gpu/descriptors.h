#pragma once
// One growable allocator of descriptor sets shared by many objects (every material instance, coefficient
// source, PRT transfer pass, frame set and environment made with one render::MaterialSystem): pools of a
// fixed capacity, another pool only when those are full, and sets freed back to their pool when their owner
// goes. A thousand materials and a thousand probe-lit objects take two pools, not two thousand.
#include <hemi/gpu/pipeline.h>

#include <vulkan/vulkan.h>

#include <cstdint>
#include <mutex>
#include <span>
#include <vector>

namespace hemi::gpu
{

class Device;
class DescriptorAllocator;

// A descriptor set of a DescriptorAllocator, freed back to it on destruction (keep it while a command buffer
// that binds it is pending, as for any Vulkan object). Move-only.
class DescriptorSet
{
  public:
    DescriptorSet() = default;
    DescriptorSet(DescriptorSet&& o) noexcept { *this = std::move(o); }
    DescriptorSet& operator=(DescriptorSet&& o) noexcept;
    DescriptorSet(const DescriptorSet&) = delete;
    DescriptorSet& operator=(const DescriptorSet&) = delete;
    ~DescriptorSet() { release(); }

    VkDescriptorSet get() const { return set_; }
    operator VkDescriptorSet() const { return set_; }

  private:
    friend class DescriptorAllocator;
    void release() noexcept;
    DescriptorAllocator* allocator_ = nullptr;
    size_t pool_ = 0;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
    std::vector<uint32_t> counts_; // descriptors of each of the allocator's types it took
};

class DescriptorAllocator
{
  public:
    // Each pool holds `sets_per_pool` sets and 4 x `sets_per_pool` descriptors of each type hemi's layouts
    // use (uniform, dynamic uniform and storage buffers, combined image samplers, uniform and storage texel
    // buffers). Pools
    // are made with FREE_DESCRIPTOR_SET so that sets go back one by one.
    explicit DescriptorAllocator(const Device& device, uint32_t sets_per_pool = 1024);
    // Every set it gave out must be gone (the objects holding them are destroyed first).
    ~DescriptorAllocator();
    DescriptorAllocator(const DescriptorAllocator&) = delete;
    DescriptorAllocator& operator=(const DescriptorAllocator&) = delete;

    // A set of `layout`, whose `bindings` say how many descriptors of each type it takes: from the first
    // pool with room for them, or from a new pool. Safe to call from several threads. Throws
    // std::invalid_argument for a layout larger than a pool, VulkanError when Vulkan fails.
    DescriptorSet allocate(VkDescriptorSetLayout layout, std::span<const Binding> bindings);

    size_t pool_count() const;
    size_t live_sets() const;

  private:
    friend class DescriptorSet;
    struct Pool
    {
        VkDescriptorPool pool = VK_NULL_HANDLE;
        uint32_t sets = 0;            // room left
        std::vector<uint32_t> counts; // room left per type
    };
    void free(size_t pool, VkDescriptorSet set, const std::vector<uint32_t>& counts) noexcept;

    const Device* device_;
    uint32_t sets_per_pool_;
    mutable std::mutex mutex_;
    std::vector<Pool> pools_;
    size_t live_ = 0;
};

} // namespace hemi::gpu
