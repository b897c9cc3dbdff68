#include "context.h"

#include <hemi/gpu/device.h> // gpu::is_loader_message: the loader's notes are not findings

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace engine
{
namespace
{

void check(VkResult r, const char* what)
{
    if (r != VK_SUCCESS)
        throw std::runtime_error(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
}

bool has_layer(const char* name)
{
    uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> layers(n);
    vkEnumerateInstanceLayerProperties(&n, layers.data());
    return std::any_of(layers.begin(), layers.end(),
                       [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

} // namespace

VkBool32 VKAPI_PTR Context::on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                       VkDebugUtilsMessageTypeFlagsEXT types,
                                       const VkDebugUtilsMessengerCallbackDataEXT* data, void* user)
{
    if (hemi::gpu::is_loader_message(types, data))
        return VK_FALSE;
    auto* self = static_cast<Context*>(user);
    self->messages_.fetch_add(1);
    std::fprintf(stderr, "engine: validation %s: %s\n",
                 severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error" : "warning",
                 data->pMessage ? data->pMessage : "");
    return VK_FALSE;
}

Context::Context(GLFWwindow* window, bool validation)
{
    check(volkInitialize(), "volkInitialize (is a Vulkan loader installed?)");
    uint32_t glfw_count = 0;
    const char** glfw_extensions = glfwGetRequiredInstanceExtensions(&glfw_count);
    if (!glfw_extensions)
        throw std::runtime_error("GLFW finds no Vulkan surface support on this display");
    std::vector<const char*> extensions(glfw_extensions, glfw_extensions + glfw_count);
    std::vector<const char*> layers;
    if (validation)
    {
        if (!has_layer("VK_LAYER_KHRONOS_validation"))
            throw std::runtime_error("--validation: VK_LAYER_KHRONOS_validation is not installed "
                                     "(Debian: vulkan-validationlayers)");
        layers.push_back("VK_LAYER_KHRONOS_validation");
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
        extensions.push_back(VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME);
        debug_utils = true;
    }
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "hemi engine sample";
    app.pEngineName = "engine sample";
    app.apiVersion = VK_API_VERSION_1_2;

    VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messenger.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                            VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                            VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messenger.pfnUserCallback = &Context::on_message;
    messenger.pUserData = this;
    // Synchronisation validation: two frames overlap, so every hazard between them is reported.
    const VkValidationFeatureEnableEXT enables[] = {
        VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
    features.enabledValidationFeatureCount = 1;
    features.pEnabledValidationFeatures = enables;
    features.pNext = &messenger;

    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    info.enabledLayerCount = uint32_t(layers.size());
    info.ppEnabledLayerNames = layers.data();
    info.enabledExtensionCount = uint32_t(extensions.size());
    info.ppEnabledExtensionNames = extensions.data();
    if (validation)
        info.pNext = &features;
    check(vkCreateInstance(&info, nullptr, &instance), "vkCreateInstance");
    volkLoadInstance(instance);
    if (validation)
        check(vkCreateDebugUtilsMessengerEXT(instance, &messenger, nullptr, &messenger_),
              "vkCreateDebugUtilsMessengerEXT");
    check(glfwCreateWindowSurface(instance, window, nullptr, &surface), "glfwCreateWindowSurface");

    // The first device with a queue family that draws, computes and presents to the window.
    uint32_t n = 0;
    vkEnumeratePhysicalDevices(instance, &n, nullptr);
    std::vector<VkPhysicalDevice> devices(n);
    vkEnumeratePhysicalDevices(instance, &n, devices.data());
    for (VkPhysicalDevice pd : devices)
    {
        uint32_t q = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &q, nullptr);
        std::vector<VkQueueFamilyProperties> families(q);
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &q, families.data());
        for (uint32_t i = 0; i < q && !physical_device; ++i)
        {
            VkBool32 present = VK_FALSE;
            vkGetPhysicalDeviceSurfaceSupportKHR(pd, i, surface, &present);
            const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
            if (present && (families[i].queueFlags & need) == need)
            {
                physical_device = pd;
                queue_family = i;
            }
        }
        if (physical_device)
            break;
    }
    if (!physical_device)
        throw std::runtime_error("no Vulkan device draws and presents to this window");

    VkPhysicalDeviceFeatures supported{}, enabled{};
    vkGetPhysicalDeviceFeatures(physical_device, &supported);
    enabled.independentBlend = supported.independentBlend;
    independent_blend = supported.independentBlend;
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = queue_family;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    const char* device_extensions[] = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue_info;
    device_info.enabledExtensionCount = 1;
    device_info.ppEnabledExtensionNames = device_extensions;
    device_info.pEnabledFeatures = &enabled;
    check(vkCreateDevice(physical_device, &device_info, nullptr, &device), "vkCreateDevice");
    volkLoadDevice(device);
    vkGetDeviceQueue(device, queue_family, 0, &queue);
}

Context::~Context()
{
    if (device)
        vkDestroyDevice(device, nullptr);
    if (surface)
        vkDestroySurfaceKHR(instance, surface, nullptr);
    if (messenger_)
        vkDestroyDebugUtilsMessengerEXT(instance, messenger_, nullptr);
    if (instance)
        vkDestroyInstance(instance, nullptr);
}

Swapchain::Swapchain(const Context& context, GLFWwindow* window) : context_(&context), window_(window)
{
    create(VK_NULL_HANDLE);
}

Swapchain::~Swapchain()
{
    destroy_views();
    if (handle)
        vkDestroySwapchainKHR(context_->device, handle, nullptr);
}

void Swapchain::recreate()
{
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    while ((w == 0 || h == 0) && !glfwWindowShouldClose(window_))
    {
        glfwWaitEvents();
        glfwGetFramebufferSize(window_, &w, &h);
    }
    vkDeviceWaitIdle(context_->device);
    destroy_views();
    const VkSwapchainKHR old = handle;
    create(old);
    vkDestroySwapchainKHR(context_->device, old, nullptr);
    ++generation;
}

void Swapchain::destroy_views()
{
    for (VkImageView v : views)
        vkDestroyImageView(context_->device, v, nullptr);
    views.clear();
}

void Swapchain::create(VkSwapchainKHR old)
{
    const VkPhysicalDevice pd = context_->physical_device;
    VkSurfaceCapabilitiesKHR caps{};
    check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(pd, context_->surface, &caps),
          "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
    uint32_t n = 0;
    vkGetPhysicalDeviceSurfaceFormatsKHR(pd, context_->surface, &n, nullptr);
    std::vector<VkSurfaceFormatKHR> formats(n);
    vkGetPhysicalDeviceSurfaceFormatsKHR(pd, context_->surface, &n, formats.data());
    if (formats.empty())
        throw std::runtime_error("the window's surface offers no formats");
    // An sRGB format encodes the tonemapped colour on write; otherwise the post pass encodes it.
    VkSurfaceFormatKHR chosen = formats.front();
    for (const VkSurfaceFormatKHR& f : formats)
        if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) &&
            f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR)
            chosen = f;
    format = chosen.format;
    srgb = format == VK_FORMAT_B8G8R8A8_SRGB || format == VK_FORMAT_R8G8B8A8_SRGB;
    if (caps.currentExtent.width != UINT32_MAX)
        extent = caps.currentExtent;
    else
    {
        int w = 0, h = 0;
        glfwGetFramebufferSize(window_, &w, &h);
        extent.width = std::clamp(uint32_t(w), caps.minImageExtent.width, caps.maxImageExtent.width);
        extent.height = std::clamp(uint32_t(h), caps.minImageExtent.height, caps.maxImageExtent.height);
    }
    VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
    info.surface = context_->surface;
    info.minImageCount = std::max(caps.minImageCount, 3u);
    if (caps.maxImageCount > 0)
        info.minImageCount = std::min(info.minImageCount, caps.maxImageCount);
    info.imageFormat = chosen.format;
    info.imageColorSpace = chosen.colorSpace;
    info.imageExtent = extent;
    info.imageArrayLayers = 1;
    // TRANSFER_SRC: screenshots copy the presented image.
    info.imageUsage =
        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT);
    info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.preTransform = caps.currentTransform;
    info.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
    info.presentMode = VK_PRESENT_MODE_FIFO_KHR; // always there; paced by the display
    info.clipped = VK_TRUE;
    info.oldSwapchain = old;
    check(vkCreateSwapchainKHR(context_->device, &info, nullptr, &handle), "vkCreateSwapchainKHR");
    n = 0;
    vkGetSwapchainImagesKHR(context_->device, handle, &n, nullptr);
    images.resize(n);
    vkGetSwapchainImagesKHR(context_->device, handle, &n, images.data());
    for (VkImage image : images)
    {
        VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        v.image = image;
        v.viewType = VK_IMAGE_VIEW_TYPE_2D;
        v.format = format;
        v.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        VkImageView view;
        check(vkCreateImageView(context_->device, &v, nullptr, &view), "vkCreateImageView");
        views.push_back(view);
    }
}

} // namespace engine
