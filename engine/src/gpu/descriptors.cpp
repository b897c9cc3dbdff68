#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/device.h>
#include <hemi/gpu/vk_check.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hemi::gpu
{
namespace
{
constexpr VkDescriptorType kTypes[] = {
    VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,       VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,       VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
    VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER};
constexpr size_t kTypeCount = sizeof kTypes / sizeof kTypes[0];
} // namespace

DescriptorSet& DescriptorSet::operator=(DescriptorSet&& o) noexcept
{
    if (this != &o)
    {
        release();
        allocator_ = std::exchange(o.allocator_, nullptr);
        pool_ = o.pool_;
        set_ = std::exchange(o.set_, VK_NULL_HANDLE);
        counts_ = std::move(o.counts_);
    }
    return *this;
}

void DescriptorSet::release() noexcept
{
    if (allocator_ && set_)
        allocator_->free(pool_, set_, counts_);
    allocator_ = nullptr;
    set_ = VK_NULL_HANDLE;
}

DescriptorAllocator::DescriptorAllocator(const Device& device, uint32_t sets_per_pool)
    : device_(&device), sets_per_pool_(std::max(sets_per_pool, 1u))
{
}

DescriptorAllocator::~DescriptorAllocator()
{
    for (const Pool& p : pools_)
        vkDestroyDescriptorPool(device_->device(), p.pool, nullptr);
}

DescriptorSet DescriptorAllocator::allocate(VkDescriptorSetLayout layout, std::span<const Binding> bindings)
{
    std::vector<uint32_t> need(kTypeCount, 0);
    for (const Binding& b : bindings)
    {
        const auto* t = std::find(std::begin(kTypes), std::end(kTypes), b.type);
        if (t == std::end(kTypes))
            throw std::invalid_argument("hemi: the descriptor allocator holds no descriptors of type " +
                                        std::to_string(int(b.type)));
        need[size_t(t - std::begin(kTypes))] += b.count;
    }
    const uint32_t per_type = 4 * sets_per_pool_;
    for (uint32_t n : need)
        if (n > per_type)
            throw std::invalid_argument("hemi: a descriptor set of " + std::to_string(n) +
                                        " descriptors of one type does not fit a pool of " +
                                        std::to_string(per_type));
    std::lock_guard<std::mutex> lock(mutex_);
    auto fits = [&](const Pool& p)
    {
        if (p.sets == 0)
            return false;
        for (size_t i = 0; i < kTypeCount; ++i)
            if (p.counts[i] < need[i])
                return false;
        return true;
    };
    size_t index = 0;
    while (index < pools_.size() && !fits(pools_[index]))
        ++index;
    if (index == pools_.size())
    {
        VkDescriptorPoolSize sizes[kTypeCount];
        for (size_t i = 0; i < kTypeCount; ++i)
            sizes[i] = {kTypes[i], per_type};
        VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        info.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
        info.maxSets = sets_per_pool_;
        info.poolSizeCount = uint32_t(kTypeCount);
        info.pPoolSizes = sizes;
        Pool p;
        HEMI_VK_CHECK(vkCreateDescriptorPool(device_->device(), &info, nullptr, &p.pool));
        p.sets = sets_per_pool_;
        p.counts.assign(kTypeCount, per_type);
        device_->set_name(VK_OBJECT_TYPE_DESCRIPTOR_POOL, p.pool,
                          "hemi descriptor pool " + std::to_string(pools_.size()));
        pools_.push_back(std::move(p));
    }
    Pool& p = pools_[index];
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = p.pool;
    info.descriptorSetCount = 1;
    info.pSetLayouts = &layout;
    DescriptorSet set;
    HEMI_VK_CHECK(vkAllocateDescriptorSets(device_->device(), &info, &set.set_));
    device_->set_name(VK_OBJECT_TYPE_DESCRIPTOR_SET, set.set_, "hemi descriptor set");
    --p.sets;
    for (size_t i = 0; i < kTypeCount; ++i)
        p.counts[i] -= need[i];
    ++live_;
    set.allocator_ = this;
    set.pool_ = index;
    set.counts_ = std::move(need);
    return set;
}

void DescriptorAllocator::free(size_t pool, VkDescriptorSet set, const std::vector<uint32_t>& counts) noexcept
{
    std::lock_guard<std::mutex> lock(mutex_);
    Pool& p = pools_[pool];
    vkFreeDescriptorSets(device_->device(), p.pool, 1, &set);
    ++p.sets;
    for (size_t i = 0; i < kTypeCount && i < counts.size(); ++i)
        p.counts[i] += counts[i];
    --live_;
}

size_t DescriptorAllocator::pool_count() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return pools_.size();
}

size_t DescriptorAllocator::live_sets() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return live_;
}

} // namespace hemi::gpu
