#pragma once
// Buffers, images, samplers and buffer views: move-only owners created from small descs with defaults, their
// memory sub-allocated by the device's MemoryAllocator (gpu/allocator.h). Destruction is immediate: the
// caller makes sure the GPU no longer uses the object, e.g. by handing it to a gpu::DeletionQueue
// (gpu/deletion_queue.h) until the frame that used it has finished.

#include <hemi/gpu/allocator.h>
#include <hemi/gpu/device.h>
#include <hemi/gpu/handle.h>

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace hemi::gpu
{

struct BufferDesc
{
    VkDeviceSize size = 0;
    // TRANSFER_SRC and TRANSFER_DST are always added so that write_buffer/read_buffer work on any buffer.
    VkBufferUsageFlags usage = 0;
    MemoryUsage memory = MemoryUsage::GpuOnly;
};

class Buffer
{
  public:
    Buffer() = default;
    Buffer(Buffer&& o) noexcept
        : memory_(std::move(o.memory_)), buffer_(std::move(o.buffer_)), size_(std::exchange(o.size_, 0)),
          mapped_(std::exchange(o.mapped_, nullptr))
    {
    }
    Buffer& operator=(Buffer&& o) noexcept
    {
        if (this != &o)
        {
            buffer_ = std::move(o.buffer_); // the buffer goes before its memory
            memory_ = std::move(o.memory_);
            size_ = std::exchange(o.size_, 0);
            mapped_ = std::exchange(o.mapped_, nullptr);
        }
        return *this;
    }
    VkBuffer handle() const { return buffer_; }
    operator VkBuffer() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    // Persistently mapped pointer when the memory is host-visible and coherent (always on lavapipe), else
    // nullptr (then write_buffer/read_buffer stage through a copy).
    void* mapped() const { return mapped_; }

  private:
    friend Buffer create_buffer(const Device&, const BufferDesc&);
    Allocation memory_;
    VkBufferHandle buffer_;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
};

// A range of a buffer hemi may not own (an engine's): what hemi writes into or views by handle.
struct BufferRange
{
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceSize offset = 0, size = 0;
};

// Throws std::invalid_argument for size 0, VulkanError when allocation fails.
Buffer create_buffer(const Device& device, const BufferDesc& desc);
// Copies `size` bytes into the buffer at `offset`: memcpy when mapped, otherwise through a staging buffer.
void write_buffer(const Device& device, const Buffer& buffer, const void* data, VkDeviceSize size,
                  VkDeviceSize offset = 0);
// The same into a buffer hemi does not own (created with TRANSFER_DST usage): always a copy, waited for.
void write_buffer(const Device& device, const BufferRange& range, const void* data);
// Copies `size` bytes at `offset` out of the buffer (waits for the copy when not mapped).
void read_buffer(const Device& device, const Buffer& buffer, void* out, VkDeviceSize size,
                 VkDeviceSize offset = 0);
// The same from a buffer hemi does not own (created with TRANSFER_SRC usage): always a copy, waited for.
void read_buffer(const Device& device, const BufferRange& range, void* out);

struct ImageDesc
{
    uint32_t width = 0;
    uint32_t height = 0;
    VkFormat format = VK_FORMAT_R8G8B8A8_UNORM;
    // TRANSFER_SRC and TRANSFER_DST are always added (uploads, readback).
    VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT;
    uint32_t mip_levels = 1;
    uint32_t layers = 1; // > 1: a 2D array image with a 2D_ARRAY view (packed coefficient maps)
    bool array = false;  // a 2D_ARRAY view even for one layer (what a sampler2DArray needs)
};

class Image
{
  public:
    Image() = default;
    VkImage handle() const { return image_; }
    VkImageView view() const { return view_; }
    VkFormat format() const { return format_; }
    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }
    uint32_t mip_levels() const { return mip_levels_; }
    uint32_t layers() const { return layers_; }
    VkImageAspectFlags aspect() const { return aspect_; }

  private:
    friend Image create_image(const Device&, const ImageDesc&);
    Allocation memory_;
    VkImageHandle image_;
    ImageView view_;
    VkFormat format_ = VK_FORMAT_UNDEFINED;
    uint32_t width_ = 0, height_ = 0, mip_levels_ = 1, layers_ = 1;
    VkImageAspectFlags aspect_ = VK_IMAGE_ASPECT_COLOR_BIT;
};

// A 2D image (or 2D array image) with a view of all its mips and layers, in VK_IMAGE_LAYOUT_UNDEFINED. Depth
// formats get a depth view.
Image create_image(const Device& device, const ImageDesc& desc);
// Bytes per texel of the formats hemi uses (throws for others).
uint32_t format_size(VkFormat format);
// Uploads tightly packed texels into mip 0 and leaves every mip in `final_layout`.
void upload_image(const Device& device, const Image& image, const void* texels, size_t bytes,
                  VkImageLayout final_layout);
// Reads mip 0 back, tightly packed; `current_layout` is the layout the image is in (and is left in).
std::vector<std::byte> read_image(const Device& device, const Image& image, VkImageLayout current_layout);
// Records a layout transition of every mip with a conservative (all-commands) barrier.
void transition_image(VkCommandBuffer cmd, const Image& image, VkImageLayout from, VkImageLayout to);

struct SamplerDesc
{
    VkFilter filter = VK_FILTER_LINEAR;
    VkSamplerMipmapMode mipmap_mode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
    VkSamplerAddressMode address = VK_SAMPLER_ADDRESS_MODE_REPEAT;
    float max_lod = VK_LOD_CLAMP_NONE;
};
Sampler create_sampler(const Device& device, const SamplerDesc& desc = {});

// A typed view of [offset, offset + range) of a buffer, for uniform/storage texel buffers.
BufferView create_buffer_view(const Device& device, VkBuffer buffer, VkFormat format, VkDeviceSize offset,
                              VkDeviceSize range);

} // namespace hemi::gpu
