// An engine that loads Vulkan with volk (Debian's libvulkan-volk-dev: VK_NO_PROTOTYPES, volk's function
// pointers in place of the loader's prototypes) includes every public header of hemi in the same translation
// unit, hands hemi its device and volk's vkGetInstanceProcAddr, and uses it: hemi uploads and reads back a
// buffer and an image, under the validation layer, whose warnings and errors fail the program. The
// executable does not link the Vulkan loader (volk opens it; hemi loads through volk's entry point).
#include <volk.h>

#include "hemi_public_headers.h" // generated: every header of engine/include, baker/include, shaders/include

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace
{
int messages = 0;

VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                          VkDebugUtilsMessageTypeFlagsEXT types,
                                          const VkDebugUtilsMessengerCallbackDataEXT* data, void*)
{
    if (hemi::gpu::is_loader_message(types, data))
        return VK_FALSE;
    std::fprintf(stderr, "validation: %s\n", data->pMessage);
    ++messages;
    return VK_FALSE;
}

void check(VkResult r, const char* what)
{
    if (r != VK_SUCCESS)
        throw std::runtime_error(std::string(what) + " failed: " + std::to_string(int(r)));
}
} // namespace

int main()
{
    try
    {
        check(volkInitialize(), "volkInitialize");
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.apiVersion = VK_API_VERSION_1_1;
        const char* layer = "VK_LAYER_KHRONOS_validation";
        const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
        VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        ici.pApplicationInfo = &app;
        ici.enabledLayerCount = 1;
        ici.ppEnabledLayerNames = &layer;
        ici.enabledExtensionCount = 1;
        ici.ppEnabledExtensionNames = &extension;
        VkInstance instance;
        check(vkCreateInstance(&ici, nullptr, &instance), "vkCreateInstance");
        volkLoadInstance(instance);
        VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        mci.messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                          VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                          VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
        mci.pfnUserCallback = on_message;
        VkDebugUtilsMessengerEXT messenger;
        check(vkCreateDebugUtilsMessengerEXT(instance, &mci, nullptr, &messenger),
              "vkCreateDebugUtilsMessengerEXT");

        uint32_t count = 0;
        vkEnumeratePhysicalDevices(instance, &count, nullptr);
        std::vector<VkPhysicalDevice> physicals(count);
        vkEnumeratePhysicalDevices(instance, &count, physicals.data());
        if (physicals.empty())
            throw std::runtime_error("no Vulkan device");
        const VkPhysicalDevice physical = physicals[0];
        uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, nullptr);
        std::vector<VkQueueFamilyProperties> props(families);
        vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, props.data());
        uint32_t family = 0;
        while (family < families &&
               (props[family].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) !=
                   (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT))
            ++family;
        const float priority = 1.0f;
        VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        qci.queueFamilyIndex = family;
        qci.queueCount = 1;
        qci.pQueuePriorities = &priority;
        VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        dci.queueCreateInfoCount = 1;
        dci.pQueueCreateInfos = &qci;
        VkDevice device;
        check(vkCreateDevice(physical, &dci, nullptr, &device), "vkCreateDevice");
        volkLoadDevice(device);
        VkQueue queue;
        vkGetDeviceQueue(device, family, 0, &queue);

        {
            hemi::gpu::ExternalDevice external;
            external.instance = instance;
            external.physical_device = physical;
            external.device = device;
            external.queue = queue;
            external.queue_family = family;
            external.get_instance_proc_addr = vkGetInstanceProcAddr; // volk's
            const hemi::gpu::Device hemi_device(external);
            std::vector<float> values(256);
            for (size_t i = 0; i < values.size(); ++i)
                values[i] = float(i) * 0.5f;
            const hemi::gpu::Buffer buffer = hemi::gpu::create_buffer(
                hemi_device, {values.size() * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                              hemi::gpu::MemoryUsage::GpuOnly});
            hemi::gpu::write_buffer(hemi_device, buffer, values.data(), values.size() * sizeof(float));
            std::vector<float> back(values.size());
            hemi::gpu::read_buffer(hemi_device, buffer, back.data(), back.size() * sizeof(float));
            if (back != values)
                throw std::runtime_error("a buffer written and read back through hemi differs");
            const hemi::gpu::Image image = hemi::gpu::create_image(
                hemi_device, {4, 4, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT});
            std::vector<uint8_t> texels(64);
            for (size_t i = 0; i < texels.size(); ++i)
                texels[i] = uint8_t(i * 3);
            hemi::gpu::upload_image(hemi_device, image, texels.data(), texels.size(),
                                    VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
            const std::vector<std::byte> read =
                hemi::gpu::read_image(hemi_device, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
            if (read.size() != texels.size() || std::memcmp(read.data(), texels.data(), texels.size()) != 0)
                throw std::runtime_error("an image uploaded and read back through hemi differs");
        }
        vkDeviceWaitIdle(device);
        vkDestroyDevice(device, nullptr);
        vkDestroyDebugUtilsMessengerEXT(instance, messenger, nullptr);
        vkDestroyInstance(instance, nullptr);
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "volk test: %s\n", e.what());
        return 1;
    }
    if (messages)
    {
        std::fprintf(stderr, "volk test: %d validation message(s)\n", messages);
        return 1;
    }
    std::printf("volk test: hemi ran on volk's entry points, 0 validation messages\n");
    return 0;
}
