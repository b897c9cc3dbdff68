#include <hemi/gpu/vk_check.h>

#include <string_view>

namespace hemi::gpu
{

std::string result_name(VkResult result)
{
    switch (result)
    {
#define HEMI_CASE(x)                                                                                         \
    case x:                                                                                                  \
        return #x;
        HEMI_CASE(VK_SUCCESS)
        HEMI_CASE(VK_NOT_READY)
        HEMI_CASE(VK_TIMEOUT)
        HEMI_CASE(VK_EVENT_SET)
        HEMI_CASE(VK_EVENT_RESET)
        HEMI_CASE(VK_INCOMPLETE)
        HEMI_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
        HEMI_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        HEMI_CASE(VK_ERROR_INITIALIZATION_FAILED)
        HEMI_CASE(VK_ERROR_DEVICE_LOST)
        HEMI_CASE(VK_ERROR_MEMORY_MAP_FAILED)
        HEMI_CASE(VK_ERROR_LAYER_NOT_PRESENT)
        HEMI_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
        HEMI_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
        HEMI_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
        HEMI_CASE(VK_ERROR_TOO_MANY_OBJECTS)
        HEMI_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
        HEMI_CASE(VK_ERROR_FRAGMENTED_POOL)
        HEMI_CASE(VK_ERROR_UNKNOWN)
        HEMI_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
        HEMI_CASE(VK_ERROR_INVALID_EXTERNAL_HANDLE)
        HEMI_CASE(VK_ERROR_FRAGMENTATION)
        HEMI_CASE(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
        HEMI_CASE(VK_PIPELINE_COMPILE_REQUIRED)
        HEMI_CASE(VK_ERROR_SURFACE_LOST_KHR)
        HEMI_CASE(VK_ERROR_NATIVE_WINDOW_IN_USE_KHR)
        HEMI_CASE(VK_SUBOPTIMAL_KHR)
        HEMI_CASE(VK_ERROR_OUT_OF_DATE_KHR)
        HEMI_CASE(VK_ERROR_VALIDATION_FAILED_EXT)
#undef HEMI_CASE
    default:
        return "VK_RESULT(" + std::to_string(static_cast<int>(result)) + ")";
    }
}

void throw_vulkan_error(const char* call, VkResult result, const char* file, int line)
{
    std::string_view c(call);
    c = c.substr(0, c.find('('));
    std::string_view f(file);
    if (auto slash = f.find_last_of("/\\"); slash != std::string_view::npos)
        f = f.substr(slash + 1);
    throw VulkanError(std::string(c) + ": " + result_name(result) + " (" + std::string(f) + ":" +
                          std::to_string(line) + ")",
                      result);
}

} // namespace hemi::gpu
