#pragma once
// A move-only owner of one device-level Vulkan handle: destroys it with its vkDestroy* on destruction.
// The destroy calls live in hemi's sources (gpu/handle.cpp, through hemi's own entry points), so this header
// names no Vulkan function: it compiles beside volk (VK_NO_PROTOTYPES) or any other way of loading Vulkan.

#include <vulkan/vulkan.h>

#include <utility>

namespace hemi::gpu
{

namespace detail
{
// Non-dispatchable handles are distinct pointer types on 64-bit targets (what hemi supports), so each has
// its own overload.
static_assert(sizeof(void*) == 8, "hemi supports 64-bit targets only");
void destroy(VkDevice device, VkSampler handle);
void destroy(VkDevice device, VkBufferView handle);
void destroy(VkDevice device, VkImageView handle);
void destroy(VkDevice device, VkShaderModule handle);
void destroy(VkDevice device, VkDescriptorSetLayout handle);
void destroy(VkDevice device, VkPipelineLayout handle);
void destroy(VkDevice device, VkPipeline handle);
void destroy(VkDevice device, VkDescriptorPool handle);
void destroy(VkDevice device, VkRenderPass handle);
void destroy(VkDevice device, VkFramebuffer handle);
void destroy(VkDevice device, VkQueryPool handle);
void destroy(VkDevice device, VkCommandPool handle);
void destroy(VkDevice device, VkFence handle);
void destroy(VkDevice device, VkDeviceMemory handle);
void destroy(VkDevice device, VkBuffer handle);
void destroy(VkDevice device, VkImage handle);
} // namespace detail

template <typename T> class UniqueHandle
{
  public:
    UniqueHandle() = default;
    UniqueHandle(VkDevice device, T handle) : device_(device), handle_(handle) {}
    ~UniqueHandle() { reset(); }
    UniqueHandle(UniqueHandle&& o) noexcept
        : device_(o.device_), handle_(std::exchange(o.handle_, static_cast<T>(VK_NULL_HANDLE)))
    {
    }
    UniqueHandle& operator=(UniqueHandle&& o) noexcept
    {
        if (this != &o)
        {
            reset();
            device_ = o.device_;
            handle_ = std::exchange(o.handle_, static_cast<T>(VK_NULL_HANDLE));
        }
        return *this;
    }
    UniqueHandle(const UniqueHandle&) = delete;
    UniqueHandle& operator=(const UniqueHandle&) = delete;

    T get() const { return handle_; }
    operator T() const { return handle_; }
    explicit operator bool() const { return handle_ != VK_NULL_HANDLE; }
    void reset()
    {
        if (handle_ != VK_NULL_HANDLE)
            detail::destroy(device_, handle_);
        handle_ = VK_NULL_HANDLE;
    }

  private:
    VkDevice device_ = VK_NULL_HANDLE;
    T handle_ = VK_NULL_HANDLE;
};

using Sampler = UniqueHandle<VkSampler>;
using BufferView = UniqueHandle<VkBufferView>;
using ImageView = UniqueHandle<VkImageView>;
using ShaderModule = UniqueHandle<VkShaderModule>;
using DescriptorSetLayout = UniqueHandle<VkDescriptorSetLayout>;
using PipelineLayout = UniqueHandle<VkPipelineLayout>;
using Pipeline = UniqueHandle<VkPipeline>;
using DescriptorPool = UniqueHandle<VkDescriptorPool>;
using RenderPass = UniqueHandle<VkRenderPass>;
using Framebuffer = UniqueHandle<VkFramebuffer>;
using QueryPool = UniqueHandle<VkQueryPool>;
using CommandPool = UniqueHandle<VkCommandPool>;
using Fence = UniqueHandle<VkFence>;
using DeviceMemory = UniqueHandle<VkDeviceMemory>;
using VkBufferHandle = UniqueHandle<VkBuffer>;
using VkImageHandle = UniqueHandle<VkImage>;

} // namespace hemi::gpu
