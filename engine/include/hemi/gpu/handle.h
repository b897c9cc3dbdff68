#pragma once
// A move-only owner of one device-level Vulkan handle: destroys it with its vkDestroy* on destruction.

#include <vulkan/vulkan.h>

#include <utility>

namespace hemi::gpu
{

template <typename T, auto Destroy> class UniqueHandle
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
            Destroy(device_, handle_, nullptr);
        handle_ = VK_NULL_HANDLE;
    }

  private:
    VkDevice device_ = VK_NULL_HANDLE;
    T handle_ = VK_NULL_HANDLE;
};

using Sampler = UniqueHandle<VkSampler, vkDestroySampler>;
using BufferView = UniqueHandle<VkBufferView, vkDestroyBufferView>;
using ImageView = UniqueHandle<VkImageView, vkDestroyImageView>;
using ShaderModule = UniqueHandle<VkShaderModule, vkDestroyShaderModule>;
using DescriptorSetLayout = UniqueHandle<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout>;
using PipelineLayout = UniqueHandle<VkPipelineLayout, vkDestroyPipelineLayout>;
using Pipeline = UniqueHandle<VkPipeline, vkDestroyPipeline>;
using DescriptorPool = UniqueHandle<VkDescriptorPool, vkDestroyDescriptorPool>;
using RenderPass = UniqueHandle<VkRenderPass, vkDestroyRenderPass>;
using Framebuffer = UniqueHandle<VkFramebuffer, vkDestroyFramebuffer>;
using QueryPool = UniqueHandle<VkQueryPool, vkDestroyQueryPool>;
using CommandPool = UniqueHandle<VkCommandPool, vkDestroyCommandPool>;
using Fence = UniqueHandle<VkFence, vkDestroyFence>;
using DeviceMemory = UniqueHandle<VkDeviceMemory, vkFreeMemory>;
using VkBufferHandle = UniqueHandle<VkBuffer, vkDestroyBuffer>;
using VkImageHandle = UniqueHandle<VkImage, vkDestroyImage>;

} // namespace hemi::gpu
