#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::gpu
{

uint32_t full_mip_count(uint32_t width, uint32_t height)
{
    uint32_t levels = 1;
    for (uint32_t s = std::max(width, height); s > 1; s >>= 1)
        ++levels;
    return levels;
}

void UploadBatch::buffer(const Buffer& dst, const void* data, VkDeviceSize size, VkDeviceSize offset)
{
    if (offset + size > dst.size())
        throw std::invalid_argument("hemi: upload of " + std::to_string(size) + " bytes at " +
                                    std::to_string(offset) + " overruns a buffer of " +
                                    std::to_string(dst.size()));
    if (size == 0)
        return;
    if (dst.mapped())
    {
        std::memcpy(static_cast<std::byte*>(dst.mapped()) + offset, data, size);
        return;
    }
    Buffer staging = create_buffer(*device_, {size, 0, MemoryUsage::Upload});
    std::memcpy(staging.mapped(), data, size);
    const VkBuffer src = staging, target = dst;
    staging_.push_back(std::move(staging));
    pending_.push_back(
        [src, target, size, offset](VkCommandBuffer cmd)
        {
            const VkBufferCopy region{0, offset, size};
            vkCmdCopyBuffer(cmd, src, target, 1, &region);
        });
}

namespace
{
void barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, uint32_t layers, uint32_t mip,
             uint32_t mips, VkImageLayout from, VkImageLayout to, VkAccessFlags src_access,
             VkAccessFlags dst_access, VkPipelineStageFlags src_stage, VkPipelineStageFlags dst_stage)
{
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = src_access;
    b.dstAccessMask = dst_access;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange = {aspect, mip, mips, 0, layers};
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, nullptr, 0, nullptr, 1, &b);
}
} // namespace

void UploadBatch::image(const Image& dst, const void* texels, size_t bytes)
{
    const size_t expected = size_t(dst.width()) * dst.height() * format_size(dst.format()) * dst.layers();
    if (bytes != expected)
        throw std::invalid_argument("hemi: image upload got " + std::to_string(bytes) + " bytes for a " +
                                    std::to_string(dst.width()) + "x" + std::to_string(dst.height()) +
                                    " image that needs " + std::to_string(expected));
    if (dst.mip_levels() > 1)
    {
        VkFormatProperties props{};
        vkGetPhysicalDeviceFormatProperties(device_->physical_device(), dst.format(), &props);
        const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_BLIT_SRC_BIT | VK_FORMAT_FEATURE_BLIT_DST_BIT |
                                          VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
        if ((props.optimalTilingFeatures & need) != need)
            throw std::runtime_error("hemi: device " + std::string(device_->name()) +
                                     " cannot generate mipmaps of this format by linear blits");
    }
    Buffer staging = create_buffer(*device_, {bytes, 0, MemoryUsage::Upload});
    std::memcpy(staging.mapped(), texels, bytes);
    const VkBuffer src = staging;
    staging_.push_back(std::move(staging));
    const VkImage image = dst.handle();
    const VkImageAspectFlags aspect = dst.aspect();
    const uint32_t mips = dst.mip_levels(), width = dst.width(), height = dst.height(), layers = dst.layers();
    pending_.push_back(
        [=](VkCommandBuffer cmd)
        {
            const VkImageLayout dst_layout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
            barrier(cmd, image, aspect, layers, 0, mips, VK_IMAGE_LAYOUT_UNDEFINED, dst_layout, 0,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                    VK_PIPELINE_STAGE_TRANSFER_BIT);
            VkBufferImageCopy region{};
            region.imageSubresource = {aspect, 0, 0, layers}; // layer after layer in `texels`
            region.imageExtent = {width, height, 1};
            vkCmdCopyBufferToImage(cmd, src, image, dst_layout, 1, &region);
            // Mip i from mip i - 1: each source level goes TRANSFER_DST -> TRANSFER_SRC once written.
            int32_t w = int32_t(width), h = int32_t(height);
            for (uint32_t mip = 1; mip < mips; ++mip)
            {
                barrier(cmd, image, aspect, layers, mip - 1, 1, dst_layout,
                        VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT);
                const int32_t nw = std::max(1, w / 2), nh = std::max(1, h / 2);
                VkImageBlit blit{};
                blit.srcSubresource = {aspect, mip - 1, 0, layers};
                blit.srcOffsets[1] = {w, h, 1};
                blit.dstSubresource = {aspect, mip, 0, layers};
                blit.dstOffsets[1] = {nw, nh, 1};
                vkCmdBlitImage(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, image, dst_layout, 1, &blit,
                               VK_FILTER_LINEAR);
                w = nw, h = nh;
            }
            if (mips > 1)
                barrier(cmd, image, aspect, layers, 0, mips - 1, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                        VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_ACCESS_TRANSFER_READ_BIT,
                        VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
            barrier(cmd, image, aspect, layers, mips - 1, 1, dst_layout,
                    VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_ACCESS_TRANSFER_WRITE_BIT,
                    VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
        });
}

void UploadBatch::image_levels(const Image& dst, std::span<const std::vector<std::byte>> levels)
{
    if (levels.size() != dst.mip_levels())
        throw std::invalid_argument("hemi: image upload got " + std::to_string(levels.size()) +
                                    " mip levels for an image of " + std::to_string(dst.mip_levels()));
    std::vector<VkBufferImageCopy> regions;
    size_t total = 0;
    for (uint32_t mip = 0; mip < levels.size(); ++mip)
    {
        const uint32_t w = std::max(1u, dst.width() >> mip), h = std::max(1u, dst.height() >> mip);
        const size_t expected = size_t(w) * h * format_size(dst.format()) * dst.layers();
        if (levels[mip].size() != expected)
            throw std::invalid_argument("hemi: mip " + std::to_string(mip) + " upload got " +
                                        std::to_string(levels[mip].size()) + " bytes, a " +
                                        std::to_string(w) + "x" + std::to_string(h) + " level needs " +
                                        std::to_string(expected));
        VkBufferImageCopy region{};
        region.bufferOffset = total;
        region.imageSubresource = {dst.aspect(), mip, 0, dst.layers()};
        region.imageExtent = {w, h, 1};
        regions.push_back(region);
        total += expected;
    }
    Buffer staging = create_buffer(*device_, {total, 0, MemoryUsage::Upload});
    for (size_t mip = 0; mip < levels.size(); ++mip)
        std::memcpy(static_cast<std::byte*>(staging.mapped()) + regions[mip].bufferOffset, levels[mip].data(),
                    levels[mip].size());
    const VkBuffer src = staging;
    staging_.push_back(std::move(staging));
    const VkImage image = dst.handle();
    const VkImageAspectFlags aspect = dst.aspect();
    const uint32_t mips = dst.mip_levels(), layers = dst.layers();
    pending_.push_back(
        [=](VkCommandBuffer cmd)
        {
            const VkImageLayout dst_layout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
            barrier(cmd, image, aspect, layers, 0, mips, VK_IMAGE_LAYOUT_UNDEFINED, dst_layout, 0,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                    VK_PIPELINE_STAGE_TRANSFER_BIT);
            vkCmdCopyBufferToImage(cmd, src, image, dst_layout, uint32_t(regions.size()), regions.data());
            barrier(cmd, image, aspect, layers, 0, mips, dst_layout, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
        });
}

void UploadBatch::record(VkCommandBuffer cmd)
{
    for (auto& p : pending_)
        p(cmd);
    pending_.clear();
    // Buffer copies (and host writes of mapped buffers, made visible by the submission itself) before any
    // later read as vertices, indices, uniforms or storage.
    memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                   VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT |
                       VK_ACCESS_UNIFORM_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
}

void UploadBatch::submit_and_wait()
{
    one_shot(*device_, [&](VkCommandBuffer cmd) { record(cmd); });
    clear();
}

void UploadBatch::clear()
{
    pending_.clear();
    staging_.clear();
}

} // namespace hemi::gpu
