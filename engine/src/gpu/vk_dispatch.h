#pragma once
// hemi's Vulkan entry points, loaded at run time (as volk does) instead of linked: hemi's link interface
// does not force the Vulkan loader, an engine that loads Vulkan its own way (volk, its own loader) hands
// hemi its vkGetInstanceProcAddr (gpu::ExternalDevice), and a headless gpu::Device opens the loader
// (libvulkan.so.1) itself. hemi's sources are compiled with VK_NO_PROTOTYPES and include this header
// (engine/CMakeLists.txt).
//
// One table of entry points per gpu::Device, as VmaVulkanFunctions is per allocator: each Device loads its
// own through its own vkGetInstanceProcAddr, so that two Devices on two instances in one process (an
// engine's, and a tool's headless one in the same editor) each reach only their own. hemi's code still
// calls vkCmdDraw(cmd, ...): in namespace hemi each entry point is a small inline function that finds the
// table of the Device its first argument belongs to. That argument is always a dispatchable handle
// (VkInstance, VkPhysicalDevice, VkDevice, VkQueue, VkCommandBuffer), and the Vulkan loader writes into the
// first word of every dispatchable object the dispatch table of its instance (VkInstance, VkPhysicalDevice)
// or its device (VkDevice and its queues and command buffers): the key under which each Device binds its
// table (dispatch::bind), the key validation layers use for the same purpose.
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

#include <utility>

namespace hemi
{
namespace gpu::dispatch
{
// The entry points that need no instance, from one vkGetInstanceProcAddr.
struct Globals
{
    PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;
#define HEMI_VK_MEMBER(name) PFN_##name name = nullptr;
    HEMI_VK_GLOBAL_FUNCTIONS(HEMI_VK_MEMBER)
};
// A Device's entry points.
struct Table
{
    PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;
    HEMI_VK_INSTANCE_FUNCTIONS(HEMI_VK_MEMBER)
#undef HEMI_VK_MEMBER
};

// Loads the global entry points from `get_instance_proc_addr`, or, when it is null, from the Vulkan loader
// opened with dlopen (libvulkan.so.1; std::runtime_error naming it when it cannot be opened).
Globals load_global(PFN_vkGetInstanceProcAddr get_instance_proc_addr);
// Loads every other entry point through `instance`. Throws std::runtime_error naming an entry point the
// implementation does not have.
void load_instance(const Globals& globals, VkInstance instance, Table& table);

// Makes `table` the one for every dispatchable handle that shares `handle`'s dispatch key (a Device binds
// its instance, physical device and device). A key bound twice (two Devices adopting one VkDevice) goes to
// the later table until it is unbound.
void bind(const void* handle, const Table* table);
// Removes every binding of `table` (before the Device that owns it goes).
void unbind(const Table* table);
// The table bound to the dispatch key of `handle`; a handle of no Device's terminates the process with a
// message naming it (a handle from outside hemi's Devices is a programming error, not an input).
const Table& of(const void* handle);
} // namespace gpu::dispatch

#define HEMI_VK_FORWARD(name)                                                                                \
    template <class Handle, class... Args> inline auto name(Handle handle, Args&&... args)                   \
    {                                                                                                        \
        return gpu::dispatch::of(handle).name(handle, std::forward<Args>(args)...);                          \
    }
HEMI_VK_INSTANCE_FUNCTIONS(HEMI_VK_FORWARD)
#undef HEMI_VK_FORWARD
} // namespace hemi
