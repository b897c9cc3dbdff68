#include <hemi/gpu/allocator.h>

#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#endif
#include <hemi/gpu/device.h>
#include <hemi/gpu/vk_check.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::gpu
{
namespace
{

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string lower(std::string_view s)
{
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return out;
}

bool has_layer(const dispatch::Globals& vk, const char* name)
{
    uint32_t count = 0;
    HEMI_VK_CHECK(vk.vkEnumerateInstanceLayerProperties(&count, nullptr));
    std::vector<VkLayerProperties> layers(count);
    HEMI_VK_CHECK(vk.vkEnumerateInstanceLayerProperties(&count, layers.data()));
    return std::any_of(layers.begin(), layers.end(),
                       [&](const VkLayerProperties& l) { return std::string_view(l.layerName) == name; });
}

int type_rank(VkPhysicalDeviceType type)
{
    switch (type)
    {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return 3;
    default:
        return 4;
    }
}

bool find_queue_family(VkPhysicalDevice pd, uint32_t* family)
{
    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, families.data());
    for (uint32_t i = 0; i < count; ++i)
    {
        const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
        if ((families[i].queueFlags & need) == need)
        {
            *family = i;
            return true;
        }
    }
    return false;
}

VkPhysicalDevice choose_physical_device(VkInstance instance, const std::string& selector,
                                        const dispatch::Table* table)
{
    uint32_t count = 0;
    HEMI_VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    HEMI_VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, devices.data()));
    for (VkPhysicalDevice pd : devices)
        dispatch::bind(pd, table); // the loader gives them the instance's dispatch key; bound whatever it is

    std::vector<std::string> names;
    std::vector<VkPhysicalDevice> usable;
    for (VkPhysicalDevice pd : devices)
    {
        VkPhysicalDeviceProperties props;
        vkGetPhysicalDeviceProperties(pd, &props);
        names.push_back(props.deviceName);
    }
    std::string all;
    for (size_t i = 0; i < names.size(); ++i)
        all += (i ? ", " : "") + std::to_string(i) + ": " + names[i];
    if (devices.empty())
        throw std::runtime_error(
            "hemi: no Vulkan physical device found (install mesa-vulkan-drivers for lavapipe)");

    uint32_t family;
    if (!selector.empty())
    {
        bool numeric = selector.size() < 9 && std::all_of(selector.begin(), selector.end(),
                                                          [](unsigned char c) { return std::isdigit(c); });
        for (size_t i = 0; i < devices.size(); ++i)
        {
            VkPhysicalDeviceProperties props;
            vkGetPhysicalDeviceProperties(devices[i], &props);
            bool match = numeric ? std::stoul(selector) == i
                                 : lower(names[i]).find(lower(selector)) != std::string::npos;
            if (match && props.apiVersion >= VK_API_VERSION_1_1 && find_queue_family(devices[i], &family))
                return devices[i];
        }
        throw std::runtime_error("hemi: no Vulkan 1.1 device with a graphics+compute queue matches '" +
                                 selector + "' (devices: " + all + ")");
    }

    VkPhysicalDevice best = VK_NULL_HANDLE;
    int best_rank = 1 << 20;
    for (VkPhysicalDevice pd : devices)
    {
        VkPhysicalDeviceProperties props;
        vkGetPhysicalDeviceProperties(pd, &props);
        int rank = type_rank(props.deviceType);
        if (props.apiVersion >= VK_API_VERSION_1_1 && find_queue_family(pd, &family) && rank < best_rank)
        {
            best = pd;
            best_rank = rank;
        }
    }
    if (!best)
        throw std::runtime_error("hemi: no Vulkan 1.1 device with a graphics+compute queue (devices: " + all +
                                 ")");
    return best;
}

} // namespace

bool is_loader_message(VkDebugUtilsMessageTypeFlagsEXT types,
                       const VkDebugUtilsMessengerCallbackDataEXT* data)
{
    return !(types & (VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                      VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT)) &&
           data && data->pMessageIdName && std::string_view(data->pMessageIdName) == "Loader Message";
}

VKAPI_ATTR VkBool32 VKAPI_CALL Device::debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT types,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                      void* user)
{
    auto* self = static_cast<Device*>(user);
    // The Vulkan loader reports through the same messenger: notes about the setup, not validation findings.
    if (is_loader_message(types, data))
    {
        if (self->log_)
            self->log_(LogLevel::Info, false, data->pMessage ? data->pMessage : "(no message)");
        return VK_FALSE;
    }
    LogLevel level = LogLevel::Debug;
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)
        level = LogLevel::Error;
    else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT)
        level = LogLevel::Warning;
    else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_INFO_BIT_EXT)
        level = LogLevel::Info;
    if (level >= LogLevel::Warning)
        self->validation_messages_.fetch_add(1);
    if (self->log_)
        self->log_(level, true, data && data->pMessage ? data->pMessage : "(no message)");
    return VK_FALSE;
}

#if defined(__SANITIZE_ADDRESS__)
namespace
{
// AddressSanitizer builds only (the sanitizer preset): the loader unloads the driver and the validation layer
// with the instance, and what they keep for the process's lifetime then shows in LeakSanitizer's report as
// leaks from "<unknown module>", which no suppression can name. Holding them loaded keeps their names on the
// stacks, so tests/sanitize/lsan.supp suppresses exactly their allocations and a leak in hemi still fails.
void pin_vulkan_libraries()
{
    static const bool pinned = []
    {
        for (const char* lib : {"libvulkan_lvp.so", "libVkLayer_khronos_validation.so", "libvulkan.so.1"})
            dlopen(lib, RTLD_NOW | RTLD_NODELETE | RTLD_GLOBAL);
        return true;
    }();
    (void)pinned;
}
} // namespace
#endif

Device::Device(const DeviceDesc& desc) : owns_(true), log_(desc.log)
{
#if defined(__SANITIZE_ADDRESS__)
    pin_vulkan_libraries();
#endif
    const dispatch::Globals globals = dispatch::load_global(nullptr); // the loader, opened at run time
    bool validation = desc.validation;
    if (const char* env = std::getenv("HEMI_VALIDATION"); env && *env)
        validation = std::string_view(env) != "0";

    std::vector<const char*> layers;
    std::vector<const char*> extensions;
    if (validation)
    {
        if (!has_layer(globals, kValidationLayer))
            throw std::runtime_error(
                "hemi: validation requested but VK_LAYER_KHRONOS_validation is not installed "
                "(Debian: vulkan-validationlayers)");
        layers.push_back(kValidationLayer);
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }

    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = desc.application_name.c_str();
    app.pEngineName = "hemi";
    // The highest version hemi uses (1.3 for dynamic rendering); it still runs on 1.1 devices.
    uint32_t loader_version = VK_API_VERSION_1_0;
    if (auto enumerate = reinterpret_cast<PFN_vkEnumerateInstanceVersion>(
            globals.vkGetInstanceProcAddr(nullptr, "vkEnumerateInstanceVersion")))
        enumerate(&loader_version);
    app.apiVersion = loader_version >= VK_API_VERSION_1_3 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_1;

    VkDebugUtilsMessengerCreateInfoEXT messenger_info{
        VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messenger_info.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger_info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                                 VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                                 VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messenger_info.pfnUserCallback = &Device::debug_callback;
    messenger_info.pUserData = this;

    VkInstanceCreateInfo instance_info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    instance_info.pApplicationInfo = &app;
    instance_info.enabledLayerCount = uint32_t(layers.size());
    instance_info.ppEnabledLayerNames = layers.data();
    instance_info.enabledExtensionCount = uint32_t(extensions.size());
    instance_info.ppEnabledExtensionNames = extensions.data();
    // Chained so that messages from vkCreateInstance/vkDestroyInstance themselves are caught too.
    if (validation)
        instance_info.pNext = &messenger_info;
    HEMI_VK_CHECK(globals.vkCreateInstance(&instance_info, nullptr, &instance_));
    try
    {
        vk_ = std::make_unique<dispatch::Table>();
        dispatch::load_instance(globals, instance_, *vk_);
        dispatch::bind(instance_, vk_.get());
    }
    catch (...)
    {
        if (vk_)
            dispatch::unbind(vk_.get());
        if (auto destroy = reinterpret_cast<PFN_vkDestroyInstance>(
                globals.vkGetInstanceProcAddr(instance_, "vkDestroyInstance")))
            destroy(instance_, nullptr);
        throw;
    }

    try
    {
        if (validation)
        {
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vk_->vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            HEMI_VK_CHECK(create(instance_, &messenger_info, nullptr, &messenger_));
            set_object_name_ = reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(
                vk_->vkGetInstanceProcAddr(instance_, "vkSetDebugUtilsObjectNameEXT"));
            // HEMI_VALIDATION_SELFTEST=1 (test-only) submits one synthetic validation warning through the
            // messenger, so that a test can see a real message arrive at debug_callback, be counted by
            // validation_messages() and reach the log callback, without provoking a driver bug on purpose.
            if (const char* selftest = std::getenv("HEMI_VALIDATION_SELFTEST");
                selftest && *selftest && std::string_view(selftest) != "0")
            {
                auto submit = reinterpret_cast<PFN_vkSubmitDebugUtilsMessageEXT>(
                    vk_->vkGetInstanceProcAddr(instance_, "vkSubmitDebugUtilsMessageEXT"));
                VkDebugUtilsMessengerCallbackDataEXT message{
                    VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CALLBACK_DATA_EXT};
                message.pMessageIdName = "hemi-validation-selftest";
                message.pMessage =
                    "hemi validation self-test: a synthetic warning (HEMI_VALIDATION_SELFTEST=1)";
                submit(instance_, VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT,
                       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT, &message);
            }
        }

        std::string selector = desc.device_selector;
        if (const char* env = std::getenv("HEMI_DEVICE"); selector.empty() && env)
            selector = env;
        physical_device_ = choose_physical_device(instance_, selector, vk_.get());
        find_queue_family(physical_device_, &queue_family_);

        float priority = 1.0f;
        VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        queue_info.queueFamilyIndex = queue_family_;
        queue_info.queueCount = 1;
        queue_info.pQueuePriorities = &priority;

        VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        VkPhysicalDeviceProperties props{};
        vkGetPhysicalDeviceProperties(physical_device_, &props);
        VkPhysicalDeviceVulkan13Features features13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
        if (app.apiVersion >= VK_API_VERSION_1_3 && props.apiVersion >= VK_API_VERSION_1_3)
        {
            VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
            features.pNext = &features13;
            vkGetPhysicalDeviceFeatures2(physical_device_, &features);
            const bool dynamic = features13.dynamicRendering;
            features13 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
            features13.dynamicRendering = dynamic;
            dynamic_rendering_ = dynamic;
            if (dynamic)
                device_info.pNext = &features13;
        }
        // independentBlend where the device has it: hemi's colour pipelines then leave an engine's extra
        // colour attachments alone (gpu::GraphicsProgramDesc::written_color_attachments).
        VkPhysicalDeviceFeatures supported{}, enabled{};
        vkGetPhysicalDeviceFeatures(physical_device_, &supported);
        enabled.independentBlend = supported.independentBlend;
        independent_blend_ = supported.independentBlend;
        device_info.pEnabledFeatures = &enabled;
        // VK_EXT_memory_budget where the device has it: the allocator then keeps within each heap's budget.
        uint32_t extension_count = 0;
        vkEnumerateDeviceExtensionProperties(physical_device_, nullptr, &extension_count, nullptr);
        std::vector<VkExtensionProperties> device_extensions(extension_count);
        vkEnumerateDeviceExtensionProperties(physical_device_, nullptr, &extension_count,
                                             device_extensions.data());
        const char* budget_extension = VK_EXT_MEMORY_BUDGET_EXTENSION_NAME;
        for (const VkExtensionProperties& e : device_extensions)
            if (std::strcmp(e.extensionName, budget_extension) == 0)
                memory_budget_ = true;
        if (memory_budget_)
        {
            device_info.enabledExtensionCount = 1;
            device_info.ppEnabledExtensionNames = &budget_extension;
        }
        device_info.queueCreateInfoCount = 1;
        device_info.pQueueCreateInfos = &queue_info;
        HEMI_VK_CHECK(vkCreateDevice(physical_device_, &device_info, nullptr, &device_));
        dispatch::bind(device_, vk_.get());
        vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
        init_properties();
        log(LogLevel::Info, std::string("hemi: using ") + properties_.deviceName);
    }
    catch (...)
    {
        if (device_)
            vkDestroyDevice(device_, nullptr);
        if (messenger_)
        {
            auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
                vk_->vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
            destroy(instance_, messenger_, nullptr);
        }
        vkDestroyInstance(instance_, nullptr);
        dispatch::unbind(vk_.get());
        throw;
    }
}

Device::Device(const ExternalDevice& external)
    : instance_(external.instance), physical_device_(external.physical_device), device_(external.device),
      queue_(external.queue), queue_family_(external.queue_family), owns_(false),
      dynamic_rendering_(external.dynamic_rendering), independent_blend_(external.independent_blend),
      memory_budget_(external.memory_budget), log_(external.log), memory_provider_(external.memory)
{
#if defined(__SANITIZE_ADDRESS__)
    pin_vulkan_libraries(); // the host's instance loaded them; keep them for LeakSanitizer's report
#endif
    if (!instance_ || !physical_device_ || !device_ || !queue_)
        throw std::invalid_argument("hemi: ExternalDevice needs instance, physical_device, device and queue");
    vk_ = std::make_unique<dispatch::Table>();
    dispatch::load_instance(dispatch::load_global(external.get_instance_proc_addr), instance_, *vk_);
    dispatch::bind(instance_, vk_.get());
    dispatch::bind(physical_device_, vk_.get());
    dispatch::bind(device_, vk_.get());
    if (external.debug_utils)
        set_object_name_ = reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(
            vk_->vkGetInstanceProcAddr(instance_, "vkSetDebugUtilsObjectNameEXT"));
    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &count, families.data());
    const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    if (queue_family_ >= count || (families[queue_family_].queueFlags & need) != need)
        throw std::invalid_argument("hemi: ExternalDevice queue family " + std::to_string(queue_family_) +
                                    " does not support graphics and compute");
    init_properties();
    if (properties_.apiVersion < VK_API_VERSION_1_1)
        throw std::invalid_argument("hemi: ExternalDevice must support Vulkan 1.1");
}

MemoryProvider& Device::memory() const
{
    if (memory_provider_)
        return *memory_provider_;
    return *allocator_;
}

void Device::set_name(VkObjectType type, uint64_t handle, std::string_view name) const noexcept
{
    if (!set_object_name_ || handle == 0)
        return;
    try
    {
        const std::string text(name); // null-terminated
        VkDebugUtilsObjectNameInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT};
        info.objectType = type;
        info.objectHandle = handle;
        info.pObjectName = text.c_str();
        set_object_name_(device_,
                         &info); // its VkResult only reports host memory running out: names are optional
    }
    catch (...)
    {
    }
}

Device::~Device()
{
    if (!owns_)
    {
        allocator_.reset(); // the host's device: its memory blocks are hemi's to free
        dispatch::unbind(vk_.get());
        return;
    }
    vkDeviceWaitIdle(device_);
    allocator_.reset();
    vkDestroyDevice(device_, nullptr);
    if (messenger_)
    {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vk_->vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
        destroy(instance_, messenger_, nullptr);
    }
    vkDestroyInstance(instance_, nullptr);
    dispatch::unbind(vk_.get());
}

void Device::init_properties()
{
    VkPhysicalDeviceMaintenance3Properties maintenance3{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
    VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    subgroup.pNext = &maintenance3;
    VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props2.pNext = &subgroup;
    vkGetPhysicalDeviceProperties2(physical_device_, &props2);
    properties_ = props2.properties;
    subgroup_size_ = std::max(1u, subgroup.subgroupSize);
    max_allocation_size_ = maintenance3.maxMemoryAllocationSize;
    vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_);
    allocator_ = std::make_unique<MemoryAllocator>(*this);

    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_device_, &count, families.data());
    bool timestamps = queue_family_ < count && families[queue_family_].timestampValidBits > 0;
    timestamp_period_ns_ = timestamps ? double(properties_.limits.timestampPeriod) : 0.0;
}

uint32_t Device::memory_type(uint32_t type_bits, MemoryUsage usage) const
{
    VkMemoryPropertyFlags required = 0, preferred = 0;
    switch (usage)
    {
    case MemoryUsage::GpuOnly:
        preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
        break;
    case MemoryUsage::Upload:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        break;
    case MemoryUsage::Readback:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
        break;
    case MemoryUsage::Dynamic:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
        break;
    }
    int fallback = -1;
    for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i)
    {
        if (!(type_bits & (1u << i)))
            continue;
        VkMemoryPropertyFlags flags = memory_.memoryTypes[i].propertyFlags;
        if ((flags & required) != required)
            continue;
        if ((flags & preferred) == preferred)
            return i;
        if (fallback < 0)
            fallback = int(i);
    }
    if (fallback < 0)
        throw std::runtime_error("hemi: no Vulkan memory type for the requested usage on " +
                                 std::string(properties_.deviceName));
    return uint32_t(fallback);
}

VkDeviceSize Device::heap_size(uint32_t memory_type) const
{
    return memory_.memoryHeaps[memory_.memoryTypes[memory_type].heapIndex].size;
}

std::optional<Device::HeapBudget> Device::heap_budget(uint32_t memory_type) const
{
    if (!memory_budget_ || memory_type >= memory_.memoryTypeCount)
        return std::nullopt;
    VkPhysicalDeviceMemoryBudgetPropertiesEXT budget{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MEMORY_BUDGET_PROPERTIES_EXT};
    VkPhysicalDeviceMemoryProperties2 properties{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MEMORY_PROPERTIES_2};
    properties.pNext = &budget;
    vkGetPhysicalDeviceMemoryProperties2(physical_device_, &properties);
    const uint32_t heap = memory_.memoryTypes[memory_type].heapIndex;
    return HeapBudget{budget.heapBudget[heap], budget.heapUsage[heap]};
}

bool Device::memory_is_host_visible(uint32_t memory_type) const
{
    return memory_.memoryTypes[memory_type].propertyFlags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
}

bool Device::memory_is_host_coherent(uint32_t memory_type) const
{
    const VkMemoryPropertyFlags need =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    return (memory_.memoryTypes[memory_type].propertyFlags & need) == need;
}

void Device::log(LogLevel level, std::string_view message) const noexcept
{
    if (log_)
        log_(level, false, message);
}

void Device::wait_idle() const
{
    HEMI_VK_CHECK(vkDeviceWaitIdle(device_));
}

} // namespace hemi::gpu
