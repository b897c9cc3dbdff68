#pragma once
// The engine's own Vulkan: its instance (with the Khronos validation layer and synchronisation validation
// when asked), its debug messenger counting every warning and error, a GLFW window's surface, its device and
// one graphics queue that presents, and a swapchain (FIFO) that is re-made when the window's size changes.
// hemi is handed these objects (gpu::ExternalDevice); it creates none of its own.
#include <volk.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <atomic>
#include <cstdint>
#include <vector>

namespace engine
{

class Context
{
  public:
    Context(GLFWwindow* window, bool validation);
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family = 0;
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    bool independent_blend = false;
    bool debug_utils = false; // VK_EXT_debug_utils is on (with --validation): hemi names its objects
    // Validation messages (warnings and errors, the loader's notes left out) since the start.
    uint64_t messages() const { return messages_.load(); }

  private:
    static VkBool32 VKAPI_PTR on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                         VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT*, void*);
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    std::atomic<uint64_t> messages_{0};
};

class Swapchain
{
  public:
    Swapchain(const Context& context, GLFWwindow* window);
    ~Swapchain();
    // Re-made at the window's current framebuffer size (waits while the window is minimised).
    void recreate();

    VkSwapchainKHR handle = VK_NULL_HANDLE;
    VkFormat format = VK_FORMAT_UNDEFINED;
    bool srgb = false; // the format encodes sRGB on write
    VkExtent2D extent{};
    std::vector<VkImage> images;
    std::vector<VkImageView> views;
    uint64_t generation = 0; // incremented by recreate(): what depends on the size is re-made

  private:
    void create(VkSwapchainKHR old);
    void destroy_views();
    const Context* context_;
    GLFWwindow* window_;
};

} // namespace engine
