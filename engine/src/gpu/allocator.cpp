#include <hemi/gpu/allocator.h>
#include <hemi/gpu/vk_check.h>

#include <algorithm>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

namespace hemi::gpu
{

Allocation::Allocation(MemoryProvider& provider, const MemoryProvider::Range& range,
                       const VkMemoryRequirements& req, MemoryUsage usage)
    : provider_(&provider), range_(range)
{
    std::string problem;
    if (range.memory == VK_NULL_HANDLE)
        problem = "no VkDeviceMemory";
    else if (range.memory_type >= 32 || !(req.memoryTypeBits & (1u << range.memory_type)))
        problem =
            "memory type " + std::to_string(range.memory_type) + " outside the resource's memoryTypeBits";
    else if (req.alignment > 1 && range.offset % req.alignment != 0)
        problem = "offset " + std::to_string(range.offset) + " not a multiple of the alignment " +
                  std::to_string(req.alignment);
    else if (range.size < req.size)
        problem = std::to_string(range.size) + " bytes for a resource of " + std::to_string(req.size);
    else if (usage != MemoryUsage::GpuOnly && range.mapped == nullptr)
        problem = "no host pointer for memory the CPU writes or reads";
    if (!problem.empty())
    {
        release();
        throw std::runtime_error("hemi: the memory provider returned " + problem);
    }
}

Allocation::Allocation(Allocation&& o) noexcept
    : provider_(std::exchange(o.provider_, nullptr)), range_(std::exchange(o.range_, {}))
{
}

Allocation& Allocation::operator=(Allocation&& o) noexcept
{
    if (this != &o)
    {
        release();
        provider_ = std::exchange(o.provider_, nullptr);
        range_ = std::exchange(o.range_, {});
    }
    return *this;
}

Allocation::~Allocation()
{
    release();
}

void Allocation::release()
{
    if (provider_)
        provider_->free(range_);
    provider_ = nullptr;
    range_ = {};
}

Allocation allocate(const Device& device, const MemoryRequest& request)
{
    MemoryProvider& provider = device.memory();
    Allocation a(provider, provider.allocate(request), request.requirements, request.usage);
    // hemi never flushes or invalidates: a host pointer into non-coherent memory would lose writes.
    if (a.mapped() && !device.memory_is_host_coherent(a.memory_type()))
        throw std::runtime_error("hemi: the memory provider returned a host pointer into memory type " +
                                 std::to_string(a.memory_type()) + ", which is not host-coherent");
    return a;
}

namespace
{
// A request from vkGet*MemoryRequirements2's answer: `query` fills requirements with the dedicated ones
// chained.
template <class Query> MemoryRequest query_request(Query query, MemoryUsage usage, bool linear)
{
    VkMemoryDedicatedRequirements dedicated{VK_STRUCTURE_TYPE_MEMORY_DEDICATED_REQUIREMENTS};
    VkMemoryRequirements2 requirements{VK_STRUCTURE_TYPE_MEMORY_REQUIREMENTS_2};
    requirements.pNext = &dedicated;
    query(requirements);
    MemoryRequest r;
    r.requirements = requirements.memoryRequirements;
    r.usage = usage;
    r.linear = linear;
    r.prefers_dedicated = dedicated.prefersDedicatedAllocation;
    r.requires_dedicated = dedicated.requiresDedicatedAllocation;
    return r;
}
} // namespace

MemoryRequest memory_request(const Device& device, VkBuffer buffer, MemoryUsage usage)
{
    VkBufferMemoryRequirementsInfo2 info{VK_STRUCTURE_TYPE_BUFFER_MEMORY_REQUIREMENTS_INFO_2};
    info.buffer = buffer;
    MemoryRequest r = query_request([&](VkMemoryRequirements2& q)
                                    { vkGetBufferMemoryRequirements2(device.device(), &info, &q); },
                                    usage, true);
    r.buffer = buffer;
    return r;
}

MemoryRequest memory_request(const Device& device, VkImage image)
{
    VkImageMemoryRequirementsInfo2 info{VK_STRUCTURE_TYPE_IMAGE_MEMORY_REQUIREMENTS_INFO_2};
    info.image = image;
    MemoryRequest r = query_request([&](VkMemoryRequirements2& q)
                                    { vkGetImageMemoryRequirements2(device.device(), &info, &q); },
                                    MemoryUsage::GpuOnly, false);
    r.image = image;
    return r;
}

MemoryAllocator::MemoryAllocator(const Device& device, VkDeviceSize block_size)
    : device_(&device), block_size_(block_size)
{
}

MemoryAllocator::~MemoryAllocator()
{
    size_t leaked = 0;
    for (const auto& b : blocks_)
    {
        leaked += b->live;
        vkFreeMemory(device_->device(), b->memory, nullptr);
    }
    if (leaked)
        device_->log(LogLevel::Warning, "hemi: " + std::to_string(leaked) +
                                            " buffers or images outlived their device's memory allocator");
}

MemoryAllocator::Block* MemoryAllocator::new_block(uint32_t type, bool linear, VkDeviceSize size,
                                                   const MemoryRequest* request)
{
    auto mib = [](VkDeviceSize b) { return std::to_string((b + (VkDeviceSize(1) << 20) - 1) >> 20); };
    if (budget_)
    {
        VkDeviceSize held = 0;
        for (const auto& b : blocks_)
            held += b->size;
        if (held + size > budget_)
            throw std::runtime_error("hemi: a memory block of " + mib(size) +
                                     " MiB would exceed the budget of " + mib(budget_) + " MiB (" +
                                     mib(held) + " MiB held)");
    }
    // The driver's budget for the heap (VK_EXT_memory_budget), which counts every allocation of the process:
    // beyond it the driver may still allocate, but pages memory out or fails later, somewhere less clear.
    if (const std::optional<Device::HeapBudget> heap = device_->heap_budget(type);
        heap && heap->usage + size > heap->budget)
        throw std::runtime_error("hemi: a memory block of " + mib(size) + " MiB would exceed the budget of " +
                                 mib(heap->budget) + " MiB that the driver reports for memory type " +
                                 std::to_string(type) + "'s heap (VK_EXT_memory_budget; " + mib(heap->usage) +
                                 " MiB in use by this process)");
    const bool dedicated = request && (request->prefers_dedicated || request->requires_dedicated);
    VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    info.allocationSize = size;
    info.memoryTypeIndex = type;
    VkMemoryDedicatedAllocateInfo dedicated_info{VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO};
    if (dedicated)
    {
        dedicated_info.buffer = request->buffer;
        dedicated_info.image = request->image;
        info.pNext = &dedicated_info;
    }
    VkDeviceMemory memory;
    HEMI_VK_CHECK(vkAllocateMemory(device_->device(), &info, nullptr, &memory));
    auto block = std::make_unique<Block>();
    block->memory = memory;
    block->size = size;
    block->type = type;
    block->linear = linear;
    block->single = request != nullptr;
    block->dedicated = dedicated;
    block->free[0] = size;
    // Only coherent memory is mapped: hemi never flushes or invalidates ranges.
    if (device_->memory_is_host_coherent(type))
    {
        VkResult r = vkMapMemory(device_->device(), memory, 0, VK_WHOLE_SIZE, 0, &block->mapped);
        if (r != VK_SUCCESS)
        {
            vkFreeMemory(device_->device(), memory, nullptr);
            HEMI_VK_CHECK(r);
        }
    }
    blocks_.push_back(std::move(block));
    return blocks_.back().get();
}

void MemoryAllocator::set_budget(VkDeviceSize bytes)
{
    std::lock_guard<std::mutex> lock(mutex_);
    budget_ = bytes;
}

MemoryProvider::Range MemoryAllocator::allocate(const MemoryRequest& request)
{
    const VkMemoryRequirements& req = request.requirements;
    const MemoryUsage usage = request.usage;
    const bool linear = request.linear;
    const uint32_t type = device_->memory_type(req.memoryTypeBits, usage);
    const VkDeviceSize align = std::max<VkDeviceSize>(1, req.alignment);
    // Refuse what the device cannot hold before asking it (a raw VK_ERROR_OUT_OF_DEVICE_MEMORY from deep in
    // a bind names no cause).
    auto mib = [](VkDeviceSize b)
    { return std::to_string((b + (VkDeviceSize(1) << 20) - 1) >> 20) + " MiB"; };
    // Every limit the request exceeds is named: its memory heap, maxMemoryAllocationSize (on lavapipe both
    // are the same 2 GiB).
    std::string exceeded;
    if (req.size > device_->heap_size(type))
        exceeded = "its memory heap (" + mib(device_->heap_size(type)) + ")";
    if (device_->max_allocation_size() && req.size > device_->max_allocation_size())
        exceeded += (exceeded.empty() ? "" : " and ") + std::string("maxMemoryAllocationSize (") +
                    mib(device_->max_allocation_size()) + ")";
    if (!exceeded.empty())
        throw std::invalid_argument("hemi: a resource of " + mib(req.size) + " exceeds " + exceeded +
                                    " on device " + std::string(device_->name()));
    std::lock_guard<std::mutex> lock(mutex_);
    Block* chosen = nullptr;
    VkDeviceSize offset = 0;
    if (req.size > block_size_ / 2 || request.prefers_dedicated || request.requires_dedicated)
        chosen = new_block(type, linear, req.size, &request);
    else
    {
        // First fit over the blocks of this type and kind.
        for (const auto& b : blocks_)
        {
            if (b->single || b->type != type || b->linear != linear)
                continue;
            for (const auto& [start, length] : b->free)
            {
                const VkDeviceSize aligned = (start + align - 1) / align * align;
                if (aligned + req.size <= start + length)
                {
                    chosen = b.get();
                    offset = aligned;
                    break;
                }
            }
            if (chosen)
                break;
        }
        if (!chosen)
            chosen = new_block(type, linear, block_size_, nullptr);
    }
    // Carve [offset, offset + size) out of the free range holding it.
    auto it = std::prev(chosen->free.upper_bound(offset));
    const VkDeviceSize start = it->first, length = it->second;
    chosen->free.erase(it);
    if (offset > start)
        chosen->free[start] = offset - start;
    if (offset + req.size < start + length)
        chosen->free[offset + req.size] = start + length - offset - req.size;
    ++chosen->live;
    Range r;
    r.memory = chosen->memory;
    r.offset = offset;
    r.size = req.size;
    r.memory_type = chosen->type;
    r.mapped = chosen->mapped ? static_cast<std::byte*>(chosen->mapped) + offset : nullptr;
    r.user = chosen;
    return r;
}

void MemoryAllocator::free(const Range& range) noexcept
{
    Block* block = static_cast<Block*>(range.user);
    const VkDeviceSize offset = range.offset, size = range.size;
    std::lock_guard<std::mutex> lock(mutex_);
    --block->live;
    // An empty block goes back to the driver at once: a level unloaded leaves no memory behind.
    if (block->single || block->live == 0)
    {
        vkFreeMemory(device_->device(), block->memory, nullptr);
        blocks_.erase(
            std::find_if(blocks_.begin(), blocks_.end(), [&](const auto& b) { return b.get() == block; }));
        return;
    }
    auto [it, inserted] = block->free.emplace(offset, size);
    (void)inserted;
    // Coalesce with the following and the preceding free ranges.
    if (auto next = std::next(it); next != block->free.end() && it->first + it->second == next->first)
    {
        it->second += next->second;
        block->free.erase(next);
    }
    if (it != block->free.begin())
        if (auto prev = std::prev(it); prev->first + prev->second == it->first)
        {
            prev->second += it->second;
            block->free.erase(it);
        }
}

MemoryAllocator::Stats MemoryAllocator::stats() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    Stats s;
    for (const auto& b : blocks_)
    {
        ++s.blocks;
        s.allocations += b->live;
        s.dedicated += b->dedicated;
        s.block_bytes += b->size;
        VkDeviceSize free_bytes = 0;
        for (const auto& [start, length] : b->free)
            free_bytes += length;
        s.used_bytes += b->size - free_bytes;
    }
    return s;
}

} // namespace hemi::gpu
