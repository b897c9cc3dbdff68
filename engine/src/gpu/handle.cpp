#include <hemi/gpu/handle.h>

namespace hemi::gpu::detail
{
void destroy(VkDevice device, VkSampler handle)
{
    vkDestroySampler(device, handle, nullptr);
}
void destroy(VkDevice device, VkBufferView handle)
{
    vkDestroyBufferView(device, handle, nullptr);
}
void destroy(VkDevice device, VkImageView handle)
{
    vkDestroyImageView(device, handle, nullptr);
}
void destroy(VkDevice device, VkShaderModule handle)
{
    vkDestroyShaderModule(device, handle, nullptr);
}
void destroy(VkDevice device, VkDescriptorSetLayout handle)
{
    vkDestroyDescriptorSetLayout(device, handle, nullptr);
}
void destroy(VkDevice device, VkPipelineLayout handle)
{
    vkDestroyPipelineLayout(device, handle, nullptr);
}
void destroy(VkDevice device, VkPipeline handle)
{
    vkDestroyPipeline(device, handle, nullptr);
}
void destroy(VkDevice device, VkDescriptorPool handle)
{
    vkDestroyDescriptorPool(device, handle, nullptr);
}
void destroy(VkDevice device, VkRenderPass handle)
{
    vkDestroyRenderPass(device, handle, nullptr);
}
void destroy(VkDevice device, VkFramebuffer handle)
{
    vkDestroyFramebuffer(device, handle, nullptr);
}
void destroy(VkDevice device, VkQueryPool handle)
{
    vkDestroyQueryPool(device, handle, nullptr);
}
void destroy(VkDevice device, VkCommandPool handle)
{
    vkDestroyCommandPool(device, handle, nullptr);
}
void destroy(VkDevice device, VkFence handle)
{
    vkDestroyFence(device, handle, nullptr);
}
void destroy(VkDevice device, VkDeviceMemory handle)
{
    vkFreeMemory(device, handle, nullptr);
}
void destroy(VkDevice device, VkBuffer handle)
{
    vkDestroyBuffer(device, handle, nullptr);
}
void destroy(VkDevice device, VkImage handle)
{
    vkDestroyImage(device, handle, nullptr);
}
} // namespace hemi::gpu::detail
