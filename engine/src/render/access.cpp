#include <hemi/render/access.h>

#include <hemi/gpu/commands.h>

namespace hemi::render
{

namespace
{
constexpr VkAccessFlags kWrites = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                                  VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                                  VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_HOST_WRITE_BIT |
                                  VK_ACCESS_MEMORY_WRITE_BIT;
}

bool BufferAccess::writes() const noexcept
{
    return (access & kWrites) != 0;
}

bool BufferAccess::overlaps(const BufferAccess& other) const noexcept
{
    if (buffer == VK_NULL_HANDLE || other.buffer == VK_NULL_HANDLE)
        return true;
    return buffer == other.buffer && offset < other.offset + other.size && other.offset < offset + size;
}

void AccessList::add(const BufferAccess& access) noexcept
{
    if (count_ < kCapacity)
    {
        items_[count_++] = access;
        return;
    }
    BufferAccess& last = items_[kCapacity - 1];
    last.buffer = VK_NULL_HANDLE;
    last.offset = 0;
    last.size = VK_WHOLE_SIZE;
    last.stages |= access.stages;
    last.access |= access.access;
}

void record_barrier(VkCommandBuffer cmd, std::span<const BufferAccess> before,
                    std::span<const BufferAccess> after) noexcept
{
    VkPipelineStageFlags src_stages = 0, dst_stages = 0;
    VkAccessFlags src_access = 0, dst_access = 0;
    bool writes = false;
    for (const BufferAccess& a : before)
    {
        src_stages |= a.stages;
        src_access |= a.access & kWrites; // only writes need making available
        writes = writes || a.writes();
    }
    for (const BufferAccess& a : after)
    {
        dst_stages |= a.stages;
        dst_access |= a.access;
        writes = writes || a.writes();
    }
    if (!writes || src_stages == 0 || dst_stages == 0)
        return;
    gpu::memory_barrier(cmd, src_stages, src_access, dst_stages, dst_access);
}

} // namespace hemi::render
