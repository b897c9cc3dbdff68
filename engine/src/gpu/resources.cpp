#include <hemi/gpu/commands.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/vk_check.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::gpu
{

Buffer create_buffer(const Device& device, const BufferDesc& desc)
{
    if (desc.size == 0)
        throw std::invalid_argument("hemi: create_buffer with size 0");
    VkDevice d = device.device();
    Buffer b;
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = desc.size;
    info.usage = desc.usage | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkBuffer buffer;
    HEMI_VK_CHECK(vkCreateBuffer(d, &info, nullptr, &buffer));
    b.buffer_ = VkBufferHandle(d, buffer);
    // Every object hemi makes carries a name from the start (renamed by its owner where it knows better).
    device.set_name(VK_OBJECT_TYPE_BUFFER, buffer, "hemi buffer of " + std::to_string(desc.size) + " bytes");

    b.memory_ = allocate(device, memory_request(device, buffer, desc.memory));
    HEMI_VK_CHECK(vkBindBufferMemory(d, buffer, b.memory_.memory(), b.memory_.offset()));
    b.mapped_ = b.memory_.mapped(); // coherent memory only: hemi never flushes or invalidates ranges
    b.size_ = desc.size;
    return b;
}

namespace
{
void check_range(const Buffer& buffer, VkDeviceSize size, VkDeviceSize offset, const char* what)
{
    if (offset > buffer.size() || size > buffer.size() - offset)
        throw std::out_of_range(std::string("hemi: ") + what + " of " + std::to_string(size) +
                                " bytes at offset " + std::to_string(offset) + " exceeds a buffer of " +
                                std::to_string(buffer.size()));
}
} // namespace

void write_buffer(const Device& device, const Buffer& buffer, const void* data, VkDeviceSize size,
                  VkDeviceSize offset)
{
    check_range(buffer, size, offset, "write_buffer");
    if (size == 0)
        return;
    if (buffer.mapped())
    {
        std::memcpy(static_cast<std::byte*>(buffer.mapped()) + offset, data, size);
        return;
    }
    write_buffer(device, BufferRange{buffer, offset, size}, data);
}

void write_buffer(const Device& device, const BufferRange& range, const void* data)
{
    if (range.size == 0)
        return;
    Buffer staging = create_buffer(device, {range.size, 0, MemoryUsage::Upload});
    std::memcpy(staging.mapped(), data, range.size);
    one_shot(device,
             [&](VkCommandBuffer cmd)
             {
                 VkBufferCopy region{0, range.offset, range.size};
                 vkCmdCopyBuffer(cmd, staging, range.buffer, 1, &region);
             });
}

void read_buffer(const Device& device, const Buffer& buffer, void* out, VkDeviceSize size,
                 VkDeviceSize offset)
{
    check_range(buffer, size, offset, "read_buffer");
    if (size == 0)
        return;
    if (buffer.mapped())
    {
        std::memcpy(out, static_cast<const std::byte*>(buffer.mapped()) + offset, size);
        return;
    }
    read_buffer(device, BufferRange{buffer, offset, size}, out);
}

void read_buffer(const Device& device, const BufferRange& range, void* out)
{
    if (range.size == 0)
        return;
    Buffer staging = create_buffer(device, {range.size, 0, MemoryUsage::Readback});
    one_shot(device,
             [&](VkCommandBuffer cmd)
             {
                 VkBufferCopy region{range.offset, 0, range.size};
                 vkCmdCopyBuffer(cmd, range.buffer, staging, 1, &region);
                 memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
             });
    std::memcpy(out, staging.mapped(), range.size);
}

uint32_t format_size(VkFormat format)
{
    switch (format)
    {
    case VK_FORMAT_R8G8B8A8_UNORM:
    case VK_FORMAT_R8G8B8A8_SRGB:
    case VK_FORMAT_B8G8R8A8_UNORM:
    case VK_FORMAT_R32_SFLOAT:
    case VK_FORMAT_R32_UINT:
    case VK_FORMAT_D32_SFLOAT:
    case VK_FORMAT_E5B9G9R9_UFLOAT_PACK32:
        return 4;
    case VK_FORMAT_R16G16B16A16_SFLOAT:
    case VK_FORMAT_R32G32_SFLOAT:
        return 8;
    case VK_FORMAT_R32G32B32A32_SFLOAT:
        return 16;
    default:
        throw std::invalid_argument("hemi: format_size: unsupported VkFormat " + std::to_string(int(format)));
    }
}

static bool is_depth(VkFormat f)
{
    return f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D16_UNORM ||
           f == VK_FORMAT_D32_SFLOAT_S8_UINT;
}

Image create_image(const Device& device, const ImageDesc& desc)
{
    if (desc.width == 0 || desc.height == 0 || desc.mip_levels == 0 || desc.layers == 0)
        throw std::invalid_argument("hemi: create_image with a zero size, mip or layer count");
    const VkPhysicalDeviceLimits& limits = device.limits();
    if (desc.width > limits.maxImageDimension2D || desc.height > limits.maxImageDimension2D)
        throw std::invalid_argument("hemi: a " + std::to_string(desc.width) + "x" +
                                    std::to_string(desc.height) + " image exceeds device " +
                                    std::string(device.name()) + "'s maxImageDimension2D (" +
                                    std::to_string(limits.maxImageDimension2D) + ")");
    if (desc.layers > limits.maxImageArrayLayers)
        throw std::invalid_argument("hemi: " + std::to_string(desc.layers) +
                                    " image layers exceed the device's "
                                    "maxImageArrayLayers (" +
                                    std::to_string(limits.maxImageArrayLayers) + ")");
    VkDevice d = device.device();
    Image img;
    img.aspect_ = is_depth(desc.format) ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = desc.format;
    info.extent = {desc.width, desc.height, 1};
    info.mipLevels = desc.mip_levels;
    info.arrayLayers = desc.layers;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = desc.usage | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VkImage image;
    HEMI_VK_CHECK(vkCreateImage(d, &info, nullptr, &image));
    img.image_ = VkImageHandle(d, image);
    const std::string extent = std::to_string(desc.width) + "x" + std::to_string(desc.height) + "x" +
                               std::to_string(desc.layers) + ", format " + std::to_string(int(desc.format));
    device.set_name(VK_OBJECT_TYPE_IMAGE, image, "hemi image " + extent);

    img.memory_ = allocate(device, memory_request(device, image));
    HEMI_VK_CHECK(vkBindImageMemory(d, image, img.memory_.memory(), img.memory_.offset()));

    VkImageViewCreateInfo view_info{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view_info.image = image;
    view_info.viewType = desc.layers > 1 || desc.array ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
    view_info.format = desc.format;
    view_info.subresourceRange = {img.aspect_, 0, desc.mip_levels, 0, desc.layers};
    VkImageView view;
    HEMI_VK_CHECK(vkCreateImageView(d, &view_info, nullptr, &view));
    img.view_ = ImageView(d, view);
    device.set_name(VK_OBJECT_TYPE_IMAGE_VIEW, view, "hemi view of image " + extent);
    img.format_ = desc.format;
    img.width_ = desc.width;
    img.height_ = desc.height;
    img.mip_levels_ = desc.mip_levels;
    img.layers_ = desc.layers;
    return img;
}

void transition_image(VkCommandBuffer cmd, const Image& image, VkImageLayout from, VkImageLayout to)
{
    VkImageMemoryBarrier barrier{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    barrier.oldLayout = from;
    barrier.newLayout = to;
    barrier.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    barrier.image = image.handle();
    barrier.subresourceRange = {image.aspect(), 0, image.mip_levels(), 0, image.layers()};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0,
                         nullptr, 0, nullptr, 1, &barrier);
}

void upload_image(const Device& device, const Image& image, const void* texels, size_t bytes,
                  VkImageLayout final_layout)
{
    if (image.mip_levels() != 1)
        throw std::invalid_argument(
            "hemi: upload_image fills mip 0 only; create the image with one mip level");
    size_t expected = size_t(image.width()) * image.height() * format_size(image.format());
    if (bytes != expected)
        throw std::invalid_argument("hemi: upload_image got " + std::to_string(bytes) + " bytes for a " +
                                    std::to_string(image.width()) + "x" + std::to_string(image.height()) +
                                    " image that needs " + std::to_string(expected));
    Buffer staging = create_buffer(device, {bytes, 0, MemoryUsage::Upload});
    std::memcpy(staging.mapped(), texels, bytes);
    one_shot(device,
             [&](VkCommandBuffer cmd)
             {
                 transition_image(cmd, image, VK_IMAGE_LAYOUT_UNDEFINED,
                                  VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
                 VkBufferImageCopy region{};
                 region.imageSubresource = {image.aspect(), 0, 0, 1};
                 region.imageExtent = {image.width(), image.height(), 1};
                 vkCmdCopyBufferToImage(cmd, staging, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                                        &region);
                 transition_image(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, final_layout);
             });
}

std::vector<std::byte> read_image(const Device& device, const Image& image, VkImageLayout current_layout)
{
    if (current_layout == VK_IMAGE_LAYOUT_UNDEFINED || current_layout == VK_IMAGE_LAYOUT_PREINITIALIZED)
        throw std::invalid_argument("hemi: read_image of an image with undefined contents");
    size_t bytes = size_t(image.width()) * image.height() * format_size(image.format());
    Buffer staging = create_buffer(device, {bytes, 0, MemoryUsage::Readback});
    one_shot(device,
             [&](VkCommandBuffer cmd)
             {
                 transition_image(cmd, image, current_layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
                 VkBufferImageCopy region{};
                 region.imageSubresource = {image.aspect(), 0, 0, 1};
                 region.imageExtent = {image.width(), image.height(), 1};
                 vkCmdCopyImageToBuffer(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging, 1,
                                        &region);
                 memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
                 transition_image(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, current_layout);
             });
    std::vector<std::byte> out(bytes);
    std::memcpy(out.data(), staging.mapped(), bytes);
    return out;
}

Sampler create_sampler(const Device& device, const SamplerDesc& desc)
{
    VkSamplerCreateInfo info{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    info.magFilter = desc.filter;
    info.minFilter = desc.filter;
    info.mipmapMode = desc.mipmap_mode;
    info.addressModeU = info.addressModeV = info.addressModeW = desc.address;
    info.maxLod = desc.max_lod;
    VkSampler sampler;
    HEMI_VK_CHECK(vkCreateSampler(device.device(), &info, nullptr, &sampler));
    device.set_name(VK_OBJECT_TYPE_SAMPLER, sampler, "hemi sampler");
    return Sampler(device.device(), sampler);
}

BufferView create_buffer_view(const Device& device, VkBuffer buffer, VkFormat format, VkDeviceSize offset,
                              VkDeviceSize range)
{
    VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    info.buffer = buffer;
    info.format = format;
    info.offset = offset;
    info.range = range;
    VkBufferView view;
    HEMI_VK_CHECK(vkCreateBufferView(device.device(), &info, nullptr, &view));
    device.set_name(VK_OBJECT_TYPE_BUFFER_VIEW, view,
                    "hemi buffer view, format " + std::to_string(int(format)));
    return BufferView(device.device(), view);
}

} // namespace hemi::gpu
