#pragma once
// Error handling for every Vulkan call hemi makes: HEMI_VK_CHECK(vkCall(...)) throws
// hemi::gpu::VulkanError("vkCall: VK_ERROR_... (file.cpp:42)") when the call does not return VK_SUCCESS.

#include <vulkan/vulkan.h>

#include <stdexcept>
#include <string>

namespace hemi::gpu
{

class VulkanError : public std::runtime_error
{
  public:
    VulkanError(const std::string& message, VkResult result) : std::runtime_error(message), result_(result) {}
    VkResult result() const { return result_; }

  private:
    VkResult result_;
};

// The enumerant's name, e.g. "VK_ERROR_DEVICE_LOST"; "VK_RESULT(<n>)" for values this build does not know.
std::string result_name(VkResult result);

// Throws VulkanError naming the call (the text up to its first '('), the result and file:line.
[[noreturn]] void throw_vulkan_error(const char* call, VkResult result, const char* file, int line);

} // namespace hemi::gpu

#define HEMI_VK_CHECK(call)                                                                                  \
    do                                                                                                       \
    {                                                                                                        \
        VkResult hemi_vk_result_ = (call);                                                                   \
        if (hemi_vk_result_ != VK_SUCCESS)                                                                   \
            ::hemi::gpu::throw_vulkan_error(#call, hemi_vk_result_, __FILE__, __LINE__);                     \
    } while (0)
