#pragma once
// Device memory for hemi's buffers and images, sub-allocated from few large VkDeviceMemory blocks: an engine
// drawing thousands of objects stays far below maxMemoryAllocationCount (4096 on many drivers) and pays one
// vkAllocateMemory per block, not per resource. Each Device owns one allocator (Device::allocator()), used
// unless the engine hands hemi a MemoryProvider of its own (ExternalDevice::memory).
//
// Blocks are per memory type and per kind (linear: buffers; optimal: images), so bufferImageGranularity never
// applies inside a block. A request larger than half a block gets a block of its own, and so does a resource
// the driver asks to have its own memory (VkMemoryDedicatedRequirements: allocated with
// VkMemoryDedicatedAllocateInfo naming it). A block whose last resource is freed goes back to the driver at
// once (stats().blocks counts only blocks in use). Host-visible coherent blocks are mapped once,
// persistently. Two budgets bound the blocks: the engine's (set_budget) and, where the device has
// VK_EXT_memory_budget, the heap budget the driver reports. Thread-safe.

#include <hemi/gpu/device.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

namespace hemi::gpu
{

// Where hemi's buffers and images get their memory. hemi's MemoryAllocator is one; an engine with an
// allocator of its own (its VMA instance, its heaps) implements this interface and hands it to hemi
// (ExternalDevice::memory), so that every byte hemi binds comes from the engine's budget and statistics.
// What a buffer or image needs of its memory.
struct MemoryRequest
{
    VkMemoryRequirements requirements{};
    MemoryUsage usage = MemoryUsage::GpuOnly;
    bool linear = true; // a buffer; false: an optimally tiled image
    // VkMemoryDedicatedRequirements: the driver prefers (or requires) that the resource have a VkDeviceMemory
    // of its own, allocated with VkMemoryDedicatedAllocateInfo naming it (`buffer` or `image`).
    bool prefers_dedicated = false, requires_dedicated = false;
    VkBuffer buffer = VK_NULL_HANDLE;
    VkImage image = VK_NULL_HANDLE;
};

class MemoryProvider
{
  public:
    struct Range
    {
        VkDeviceMemory memory = VK_NULL_HANDLE;
        VkDeviceSize offset = 0; // where the resource binds: a multiple of the requirements' alignment
        VkDeviceSize size = 0;   // at least the requirements' size
        uint32_t memory_type = 0;
        // The range's host pointer, into host-coherent memory only (hemi never flushes or invalidates).
        // Required (persistently mapped) for MemoryUsage::Upload, Readback and Dynamic; optional for GpuOnly
        // (hemi then writes through it instead of a staging copy).
        void* mapped = nullptr;
        void* user = nullptr; // the provider's own handle for free() (a VmaAllocation, a block)
    };
    virtual ~MemoryProvider() = default;
    // Memory for a buffer (`linear`) or an optimally tiled image with `request.requirements`, of a memory
    // type in requirements.memoryTypeBits with the properties `request.usage` needs
    // (Device::memory_type(bits, usage) is hemi's choice); a memory of its own where the request requires
    // one. Throws when there is none (hemi passes the exception on to its caller).
    virtual Range allocate(const MemoryRequest& request) = 0;
    // The buffer or image bound to `range` is destroyed: the engine destroys hemi's objects once the GPU no
    // longer uses them, so the memory may be reused at once.
    virtual void free(const Range& range) noexcept = 0;
};

// A range from a provider, given back when destroyed. Move-only.
class Allocation
{
  public:
    Allocation() = default;
    // Takes `range` from `provider` (checked against `requirements` and `usage`: std::runtime_error naming
    // what an engine's provider got wrong, after giving the range back).
    Allocation(MemoryProvider& provider, const MemoryProvider::Range& range,
               const VkMemoryRequirements& requirements, MemoryUsage usage);
    Allocation(Allocation&& o) noexcept;
    Allocation& operator=(Allocation&& o) noexcept;
    Allocation(const Allocation&) = delete;
    Allocation& operator=(const Allocation&) = delete;
    ~Allocation();

    VkDeviceMemory memory() const { return range_.memory; }
    VkDeviceSize offset() const { return range_.offset; }
    VkDeviceSize size() const { return range_.size; }
    uint32_t memory_type() const { return range_.memory_type; }
    // The range's host pointer when host-visible and coherent, else nullptr.
    void* mapped() const { return range_.mapped; }
    explicit operator bool() const { return provider_ != nullptr; }

  private:
    void release();
    MemoryProvider* provider_ = nullptr;
    MemoryProvider::Range range_;
};

// Memory for `request` from the device's provider (Device::memory()).
Allocation allocate(const Device& device, const MemoryRequest& request);
// The request for `buffer` or `image` (vkGet*MemoryRequirements2, with its dedicated requirements).
MemoryRequest memory_request(const Device& device, VkBuffer buffer, MemoryUsage usage);
MemoryRequest memory_request(const Device& device, VkImage image);

class MemoryAllocator final : public MemoryProvider
{
  public:
    explicit MemoryAllocator(const Device& device, VkDeviceSize block_size = VkDeviceSize(64) << 20);
    // Frees every block; logs (Device::log, Warning) allocations still alive, which are then dangling.
    ~MemoryAllocator();
    MemoryAllocator(const MemoryAllocator&) = delete;
    MemoryAllocator& operator=(const MemoryAllocator&) = delete;

    // Memory for `request` with the properties its usage needs. Throws VulkanError when the driver refuses a
    // new block (VK_ERROR_OUT_OF_DEVICE_MEMORY), std::runtime_error when a new block would exceed the
    // engine's budget or the heap's (VK_EXT_memory_budget).
    Range allocate(const MemoryRequest& request) override;
    void free(const Range& range) noexcept override;

    // At most `bytes` of blocks alive at once (0: no limit, the default): a request that needs a new block
    // beyond it is refused with an error naming the budget, before the driver is asked.
    void set_budget(VkDeviceSize bytes);

    struct Stats
    {
        size_t blocks = 0;            // VkDeviceMemory objects alive
        size_t allocations = 0;       // live sub-allocations
        VkDeviceSize block_bytes = 0; // bytes of all blocks
        VkDeviceSize used_bytes = 0;  // bytes of live sub-allocations (after alignment)
        size_t dedicated = 0;         // blocks allocated for one resource the driver asked to have its own
    };
    Stats stats() const;

  private:
    struct Block
    {
        VkDeviceMemory memory = VK_NULL_HANDLE;
        VkDeviceSize size = 0;
        uint32_t type = 0;
        bool linear = true;
        bool single = false;    // holds one resource (too large for a shared block, or dedicated)
        bool dedicated = false; // allocated with VkMemoryDedicatedAllocateInfo
        void* mapped = nullptr;
        std::map<VkDeviceSize, VkDeviceSize> free; // offset -> size, coalesced
        size_t live = 0;
    };
    // `request` non-null: a block of its own for that resource (dedicated when the driver asks).
    Block* new_block(uint32_t type, bool linear, VkDeviceSize size, const MemoryRequest* request);

    const Device* device_;
    VkDeviceSize block_size_;
    VkDeviceSize budget_ = 0;
    mutable std::mutex mutex_;
    std::vector<std::unique_ptr<Block>> blocks_;
};

} // namespace hemi::gpu
