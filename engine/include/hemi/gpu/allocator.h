#pragma once
// Device memory for hemi's buffers and images, sub-allocated from few large VkDeviceMemory blocks: an engine
// drawing thousands of objects stays far below maxMemoryAllocationCount (4096 on many drivers) and pays one
// vkAllocateMemory per block, not per resource. Each Device owns one allocator (Device::allocator()).
//
// Blocks are per memory type and per kind (linear: buffers; optimal: images), so bufferImageGranularity never
// applies inside a block. A request larger than half a block gets a block of its own. A block whose last
// resource is freed goes back to the driver at once (stats().blocks counts only blocks in use). Host-visible
// coherent blocks are mapped once, persistently. Thread-safe.

#include <hemi/gpu/device.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

namespace hemi::gpu
{

class MemoryAllocator;

// A range of a block, freed when destroyed. Move-only.
class Allocation
{
  public:
    Allocation() = default;
    Allocation(Allocation&& o) noexcept;
    Allocation& operator=(Allocation&& o) noexcept;
    Allocation(const Allocation&) = delete;
    Allocation& operator=(const Allocation&) = delete;
    ~Allocation();

    VkDeviceMemory memory() const;
    VkDeviceSize offset() const { return offset_; }
    VkDeviceSize size() const { return size_; }
    uint32_t memory_type() const;
    // The range's host pointer when the block is host-visible and coherent, else nullptr.
    void* mapped() const;
    explicit operator bool() const { return block_ != nullptr; }

  private:
    friend class MemoryAllocator;
    void release();
    MemoryAllocator* allocator_ = nullptr;
    void* block_ = nullptr; // MemoryAllocator::Block
    VkDeviceSize offset_ = 0, size_ = 0;
};

class MemoryAllocator
{
  public:
    explicit MemoryAllocator(const Device& device, VkDeviceSize block_size = VkDeviceSize(64) << 20);
    // Frees every block; logs (Device::log, Warning) allocations still alive, which are then dangling.
    ~MemoryAllocator();
    MemoryAllocator(const MemoryAllocator&) = delete;
    MemoryAllocator& operator=(const MemoryAllocator&) = delete;

    // Memory for `requirements` with the properties `usage` needs; `linear` for buffers, false for optimally
    // tiled images. Throws VulkanError when the driver refuses a new block (VK_ERROR_OUT_OF_DEVICE_MEMORY).
    Allocation allocate(const VkMemoryRequirements& requirements, MemoryUsage usage, bool linear);

    struct Stats
    {
        size_t blocks = 0;            // VkDeviceMemory objects alive
        size_t allocations = 0;       // live sub-allocations
        VkDeviceSize block_bytes = 0; // bytes of all blocks
        VkDeviceSize used_bytes = 0;  // bytes of live sub-allocations (after alignment)
    };
    Stats stats() const;

  private:
    friend class Allocation;
    struct Block
    {
        VkDeviceMemory memory = VK_NULL_HANDLE;
        VkDeviceSize size = 0;
        uint32_t type = 0;
        bool linear = true, dedicated = false;
        void* mapped = nullptr;
        std::map<VkDeviceSize, VkDeviceSize> free; // offset -> size, coalesced
        size_t live = 0;
    };
    void free(Block* block, VkDeviceSize offset, VkDeviceSize size);
    Block* new_block(uint32_t type, bool linear, VkDeviceSize size, bool dedicated);

    const Device* device_;
    VkDeviceSize block_size_;
    mutable std::mutex mutex_;
    std::vector<std::unique_ptr<Block>> blocks_;
};

} // namespace hemi::gpu
