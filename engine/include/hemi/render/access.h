#pragma once
// What hemi's recording calls read and write on the device, for an engine's render graph. A call that
// records GPU work into the engine's command buffer (the PRT transfer) or whose draws read what such work
// writes (PRT coefficients, light probes) reports the buffer ranges it touches, with pipeline stages and
// access masks, and records no barrier of its own: the engine turns the accesses into its barriers (or
// into queue-family ownership transfers), as it does for its own passes. record_barrier() is hemi's opt-in
// helper for callers without a render graph (tools, tests, samples).
//
// Host writes (per-frame data hemi writes through persistently mapped memory while recording) are not
// listed: a queue submission makes host writes visible to the device. Their contract is the engine's
// frames in flight: a frame slot is recorded again only once the GPU has finished the frame that last used
// it (the engine's per-frame fence).

#include <vulkan/vulkan.h>

#include <array>
#include <cstdint>
#include <span>

namespace hemi::render
{

// One access to a range of a buffer. The masks are Vulkan 1.0's (VkPipelineStageFlags, VkAccessFlags);
// VK_KHR_synchronization2's 64-bit flags have the same bits for every stage and access hemi reports.
// `buffer` VK_NULL_HANDLE stands for any buffer (a list that ran out of room: AccessList::add).
struct BufferAccess
{
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceSize offset = 0, size = 0;
    VkPipelineStageFlags stages = 0;
    VkAccessFlags access = 0;

    bool writes() const noexcept;
    // Whether the two touch a common byte (a null buffer overlaps everything).
    bool overlaps(const BufferAccess& other) const noexcept;
};

// The accesses recording calls report, in storage of its own (no allocation): each call appends its own.
// Room for kCapacity accesses; past that, an access is merged into the last one, which becomes a whole-device
// access (buffer VK_NULL_HANDLE) with the union of their masks: coarser barriers, never a missing one.
class AccessList
{
  public:
    static constexpr uint32_t kCapacity = 16;

    void clear() noexcept { count_ = 0; }
    void add(const BufferAccess& access) noexcept;
    std::span<const BufferAccess> accesses() const noexcept { return {items_.data(), count_}; }
    uint32_t size() const noexcept { return count_; }

  private:
    std::array<BufferAccess, kCapacity> items_{};
    uint32_t count_ = 0;
};

// hemi's own barrier, for callers without a render graph: one VkMemoryBarrier that orders every access of
// `before` ahead of every access of `after` and makes the writes of `before` visible to `after`. Records
// nothing when neither side writes (reads after reads need no barrier).
void record_barrier(VkCommandBuffer cmd, std::span<const BufferAccess> before,
                    std::span<const BufferAccess> after) noexcept;

} // namespace hemi::render
