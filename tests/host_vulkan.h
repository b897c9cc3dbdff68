#pragma once
// A host engine's own Vulkan for tests of hemi on an adopted device (gpu::ExternalDevice): an instance with
// the validation layer (optionally synchronisation validation too), debug utils and its own messenger, the
// lavapipe device, one queue of a graphics family. Destroyed by the host, after hemi let go of it. The
// messenger's messages go to the test's validation log, so any message fails the test; the loader's notes
// about the setup (e.g. that VK_LOADER_LAYERS_ENABLE forced the layer on) do not, by the same test hemi's
// own messenger uses.
#include "gpu_fixture.h"

#include <hemi/gpu/device.h>

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

namespace hemi::test
{

inline VKAPI_ATTR VkBool32 VKAPI_CALL host_messenger(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                     VkDebugUtilsMessageTypeFlagsEXT types,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data, void*)
{
    if (gpu::is_loader_message(types, data))
        return VK_FALSE;
    validation_log().add(std::string("(host instance) ") + data->pMessage);
    return VK_FALSE;
}

struct HostVulkan
{
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice pd = VK_NULL_HANDLE;
    VkDevice vk_device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t family = 0;

    // A failure leaves queue null: the test checks it.
    explicit HostVulkan(bool synchronization_validation = false) { create(synchronization_validation); }
    ~HostVulkan()
    {
        if (vk_device)
            vkDestroyDevice(vk_device, nullptr);
        if (messenger)
            reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(vkGetInstanceProcAddr(
                instance, "vkDestroyDebugUtilsMessengerEXT"))(instance, messenger, nullptr);
        if (instance)
            vkDestroyInstance(instance, nullptr);
    }
    HostVulkan(const HostVulkan&) = delete;
    HostVulkan& operator=(const HostVulkan&) = delete;

    // What hemi adopts; `gipa`: where hemi gets its entry points (null: the loader).
    gpu::ExternalDevice external(PFN_vkGetInstanceProcAddr gipa = nullptr) const
    {
        gpu::ExternalDevice e{instance, pd, vk_device, queue, family, {}};
        e.get_instance_proc_addr = gipa;
        e.debug_utils = true;
        return e;
    }

  private:
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;

    void create(bool synchronization_validation)
    {
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.apiVersion = VK_API_VERSION_1_1;
        const char* layer = "VK_LAYER_KHRONOS_validation";
        const char* ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
        VkDebugUtilsMessengerCreateInfoEXT mi{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        mi.messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        mi.messageType =
            VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
        mi.pfnUserCallback = host_messenger;
        const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
        VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
        features.enabledValidationFeatureCount = 1;
        features.pEnabledValidationFeatures = &sync;
        if (synchronization_validation)
            mi.pNext = &features;
        VkInstanceCreateInfo ii{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        ii.pNext = &mi;
        ii.pApplicationInfo = &app;
        ii.enabledLayerCount = 1;
        ii.ppEnabledLayerNames = &layer;
        ii.enabledExtensionCount = 1;
        ii.ppEnabledExtensionNames = &ext;
        ASSERT_EQ(vkCreateInstance(&ii, nullptr, &instance), VK_SUCCESS);
        // The messenger chained to VkInstanceCreateInfo reports only while the instance is made and
        // destroyed: the one that hears every command's validation is made now.
        mi.pNext = nullptr;
        const auto create_messenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT"));
        ASSERT_NE(create_messenger, nullptr);
        ASSERT_EQ(create_messenger(instance, &mi, nullptr, &messenger), VK_SUCCESS);

        uint32_t count = 0;
        vkEnumeratePhysicalDevices(instance, &count, nullptr);
        std::vector<VkPhysicalDevice> pds(count);
        vkEnumeratePhysicalDevices(instance, &count, pds.data());
        for (VkPhysicalDevice p : pds)
        {
            VkPhysicalDeviceProperties props;
            vkGetPhysicalDeviceProperties(p, &props);
            if (std::strstr(props.deviceName, "llvmpipe"))
                pd = p;
        }
        ASSERT_NE(pd, VK_NULL_HANDLE);
        uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &families, nullptr);
        std::vector<VkQueueFamilyProperties> props(families);
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &families, props.data());
        for (uint32_t f = families; f-- > 0;)
            if ((props[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (props[f].queueFlags & VK_QUEUE_COMPUTE_BIT))
                family = f;
        float priority = 1.0f;
        VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        qi.queueFamilyIndex = family;
        qi.queueCount = 1;
        qi.pQueuePriorities = &priority;
        VkDeviceCreateInfo di{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        di.queueCreateInfoCount = 1;
        di.pQueueCreateInfos = &qi;
        ASSERT_EQ(vkCreateDevice(pd, &di, nullptr, &vk_device), VK_SUCCESS);
        vkGetDeviceQueue(vk_device, family, 0, &queue);
    }
};

} // namespace hemi::test
