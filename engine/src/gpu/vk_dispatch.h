#pragma once
// hemi's Vulkan entry points, loaded at run time (as volk does) instead of linked: hemi's link interface
// does not force the Vulkan loader, an engine that loads Vulkan its own way (volk, its own loader) hands
// hemi its vkGetInstanceProcAddr (gpu::ExternalDevice), and a headless gpu::Device opens the loader
// (libvulkan.so.1) itself. hemi's sources are compiled with VK_NO_PROTOTYPES and include this header
// (engine/CMakeLists.txt); each entry point is a function pointer in namespace hemi, so that hemi's code
// calls vkCmdDraw(...) as usual and no symbol of the loader's or of volk's is defined twice.
#ifndef VK_NO_PROTOTYPES
#error "hemi's sources are compiled with VK_NO_PROTOTYPES (engine/CMakeLists.txt)"
#endif
#include <vulkan/vulkan.h>

// Global entry points (no instance yet).
#define HEMI_VK_GLOBAL_FUNCTIONS(X)                                                                          \
    X(vkCreateInstance)                                                                                      \
    X(vkEnumerateInstanceLayerProperties)                                                                    \
    X(vkEnumerateInstanceExtensionProperties)
// Every other entry point hemi calls, loaded through the instance (the loader's dispatching trampolines,
// valid for every device of the instance).
#define HEMI_VK_INSTANCE_FUNCTIONS(X)                                                                        \
    X(vkDestroyBuffer)                                                                                       \
    X(vkDestroyBufferView)                                                                                   \
    X(vkDestroyCommandPool)                                                                                  \
    X(vkDestroyDescriptorPool)                                                                               \
    X(vkDestroyDescriptorSetLayout)                                                                          \
    X(vkDestroyFence)                                                                                        \
    X(vkDestroyFramebuffer)                                                                                  \
    X(vkDestroyImage)                                                                                        \
    X(vkDestroyImageView)                                                                                    \
    X(vkDestroyPipeline)                                                                                     \
    X(vkDestroyPipelineLayout)                                                                               \
    X(vkDestroyQueryPool)                                                                                    \
    X(vkDestroyRenderPass)                                                                                   \
    X(vkDestroySampler)                                                                                      \
    X(vkDestroyShaderModule)                                                                                 \
    X(vkAllocateCommandBuffers)                                                                              \
    X(vkAllocateDescriptorSets)                                                                              \
    X(vkAllocateMemory)                                                                                      \
    X(vkBeginCommandBuffer)                                                                                  \
    X(vkBindBufferMemory)                                                                                    \
    X(vkBindImageMemory)                                                                                     \
    X(vkCmdBeginRenderPass)                                                                                  \
    X(vkCmdBindDescriptorSets)                                                                               \
    X(vkCmdBindIndexBuffer)                                                                                  \
    X(vkCmdBindPipeline)                                                                                     \
    X(vkCmdBindVertexBuffers)                                                                                \
    X(vkCmdBlitImage)                                                                                        \
    X(vkCmdCopyBuffer)                                                                                       \
    X(vkCmdCopyBufferToImage)                                                                                \
    X(vkCmdCopyImageToBuffer)                                                                                \
    X(vkCmdDispatch)                                                                                         \
    X(vkCmdDrawIndexed)                                                                                      \
    X(vkCmdEndRenderPass)                                                                                    \
    X(vkCmdPipelineBarrier)                                                                                  \
    X(vkCmdPushConstants)                                                                                    \
    X(vkCmdResetQueryPool)                                                                                   \
    X(vkCmdSetScissor)                                                                                       \
    X(vkCmdSetViewport)                                                                                      \
    X(vkCmdUpdateBuffer)                                                                                     \
    X(vkCmdWriteTimestamp)                                                                                   \
    X(vkCreateBuffer)                                                                                        \
    X(vkCreateBufferView)                                                                                    \
    X(vkCreateCommandPool)                                                                                   \
    X(vkCreateComputePipelines)                                                                              \
    X(vkCreateDescriptorPool)                                                                                \
    X(vkCreateDescriptorSetLayout)                                                                           \
    X(vkCreateDevice)                                                                                        \
    X(vkCreateFence)                                                                                         \
    X(vkCreateFramebuffer)                                                                                   \
    X(vkCreateGraphicsPipelines)                                                                             \
    X(vkCreateImage)                                                                                         \
    X(vkCreateImageView)                                                                                     \
    X(vkCreatePipelineLayout)                                                                                \
    X(vkCreateQueryPool)                                                                                     \
    X(vkCreateRenderPass)                                                                                    \
    X(vkCreateSampler)                                                                                       \
    X(vkCreateShaderModule)                                                                                  \
    X(vkDestroyDevice)                                                                                       \
    X(vkDestroyInstance)                                                                                     \
    X(vkDeviceWaitIdle)                                                                                      \
    X(vkEndCommandBuffer)                                                                                    \
    X(vkEnumeratePhysicalDevices)                                                                            \
    X(vkEnumerateDeviceExtensionProperties)                                                                  \
    X(vkFreeDescriptorSets)                                                                                  \
    X(vkFreeMemory)                                                                                          \
    X(vkGetBufferMemoryRequirements2)                                                                        \
    X(vkGetDeviceQueue)                                                                                      \
    X(vkGetImageMemoryRequirements2)                                                                         \
    X(vkGetPhysicalDeviceFeatures)                                                                           \
    X(vkGetPhysicalDeviceFeatures2)                                                                          \
    X(vkGetPhysicalDeviceFormatProperties)                                                                   \
    X(vkGetPhysicalDeviceMemoryProperties)                                                                   \
    X(vkGetPhysicalDeviceMemoryProperties2)                                                                  \
    X(vkGetPhysicalDeviceProperties)                                                                         \
    X(vkGetPhysicalDeviceProperties2)                                                                        \
    X(vkGetPhysicalDeviceQueueFamilyProperties)                                                              \
    X(vkGetQueryPoolResults)                                                                                 \
    X(vkMapMemory)                                                                                           \
    X(vkQueueSubmit)                                                                                         \
    X(vkResetCommandBuffer)                                                                                  \
    X(vkResetFences)                                                                                         \
    X(vkUpdateDescriptorSets)                                                                                \
    X(vkWaitForFences)

namespace hemi
{
#define HEMI_VK_DECLARE(name) extern PFN_##name name;
HEMI_VK_GLOBAL_FUNCTIONS(HEMI_VK_DECLARE)
HEMI_VK_INSTANCE_FUNCTIONS(HEMI_VK_DECLARE)
#undef HEMI_VK_DECLARE
extern PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr;

namespace gpu::dispatch
{
// Loads the global entry points from `get_instance_proc_addr`, or, when it is null, from the Vulkan loader
// opened with dlopen (libvulkan.so.1; std::runtime_error naming it when it cannot be opened).
void load_global(PFN_vkGetInstanceProcAddr get_instance_proc_addr);
// Loads every other entry point through `instance` (after load_global). Throws std::runtime_error naming
// an entry point the implementation does not have.
void load_instance(VkInstance instance);
} // namespace gpu::dispatch
} // namespace hemi
