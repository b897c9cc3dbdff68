#pragma once
// The Vulkan device hemi renders and computes with: either one hemi creates (headless, no surface),
// or the host engine's own instance / physical device / device / queue, adopted without taking ownership.

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

namespace hemi::gpu
{

class MemoryAllocator;
class MemoryProvider;
namespace dispatch
{
struct Table; // the Device's own Vulkan entry points (internal)
} // namespace dispatch

enum class LogLevel
{
    Debug,
    Info,
    Warning,
    Error,
};

// hemi never prints: everything it has to say goes through the host's callback. Messages from the
// Khronos validation layer arrive with `validation == true`. May be called from any thread, and from calls on
// the frame path that refuse a bad argument (LogLevel::Error, docs/engine.md): it must not throw.
using LogCallback = std::function<void(LogLevel level, bool validation, std::string_view message)>;

struct DeviceDesc
{
    // Which physical device to use. Empty: the HEMI_DEVICE environment variable, and if that is unset,
    // the first discrete GPU, else integrated, else virtual, else CPU (lavapipe). A selector is either a
    // decimal index into vkEnumeratePhysicalDevices or a case-insensitive substring of the device name
    // (e.g. "llvmpipe", "NVIDIA").
    std::string device_selector;
    // Enables VK_LAYER_KHRONOS_validation and routes its warnings and errors to `log`.
    // The HEMI_VALIDATION environment variable ("1"/"0") overrides this. With validation on,
    // HEMI_VALIDATION_SELFTEST=1 (for tests only) makes the device submit one synthetic validation warning
    // through its messenger right after creating it: it reaches `log` and counts in validation_messages()
    // exactly like a message of the layer's own.
    bool validation = false;
    LogCallback log;
    std::string application_name = "hemi";
};

// A host engine's device. hemi uses these handles and destroys none of them. Requirements: Vulkan 1.1,
// `queue` supports graphics and compute, and the host keeps every handle alive while hemi uses it.
struct ExternalDevice
{
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family = 0;
    LogCallback log;
    // True when `device` was created with Vulkan 1.3's dynamicRendering feature enabled: then hemi's
    // materials can also draw inside vkCmdBeginRendering (RenderTargetDesc without a render pass).
    bool dynamic_rendering = false;
    // True when `device` was created with the independentBlend feature: then hemi's colour pipelines leave
    // colour attachments past their own (0, and 1 for aux output) as the engine left them; without it every
    // attachment of a subpass gets the same blend state, so hemi writes them all.
    bool independent_blend = false;
    // Where hemi gets its Vulkan entry points: the engine's vkGetInstanceProcAddr (volk's, its own loader's,
    // a layer chain's); null opens the system's loader (libvulkan.so.1) at run time. hemi does not link the
    // loader. Each Device keeps its own entry points: other Devices in the process never change them.
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
    // True when `instance` was created with VK_EXT_debug_utils enabled: then hemi names the Vulkan objects it
    // creates (vkSetDebugUtilsObjectNameEXT: "hemi mesh vertices", "hemi lightmap 'h4'", "hemi material
    // irradiance/h4/texel ...", a texture's glTF image name), so RenderDoc and the validation layer's
    // messages show them by name.
    bool debug_utils = false;
    // The engine's own memory allocator (gpu/allocator.h), which then serves every buffer and image hemi
    // makes on this device; it must outlive the Device and everything made with it. Null: hemi's own
    // MemoryAllocator (Device::allocator()).
    MemoryProvider* memory = nullptr;
    // True when `device` was created with VK_EXT_memory_budget enabled: then hemi's allocator refuses a new
    // block that would take its heap past the budget the driver reports (Device::heap_budget).
    bool memory_budget = false;
};

// Whether a debug-utils message comes from the Vulkan loader (e.g. "Layer ... forced enabled due to env var
// 'VK_LOADER_LAYERS_ENABLE'"), a note about the setup rather than a validation finding: the loader names
// itself in pMessageIdName ("Loader Message") and sends general messages only. hemi's own messenger logs
// these as Info and does not count them; a host engine's messenger can use the same test.
bool is_loader_message(VkDebugUtilsMessageTypeFlagsEXT types,
                       const VkDebugUtilsMessengerCallbackDataEXT* data);

enum class MemoryUsage
{
    GpuOnly,  // device-local; uploads go through a staging copy unless the memory is also host-visible
    Upload,   // host-visible, coherent, written by the CPU
    Readback, // host-visible, preferably cached, read by the CPU
    Dynamic,  // host-visible, coherent, preferably device-local: per-frame data the CPU writes, the GPU reads
};

class Device
{
  public:
    // Creates an instance and device of its own. Throws VulkanError (e.g. VK_ERROR_INCOMPATIBLE_DRIVER
    // when no Vulkan driver is installed) or std::runtime_error (no device matches the selector).
    explicit Device(const DeviceDesc& desc = {});
    // Adopts the host's device; destroys nothing of it.
    explicit Device(const ExternalDevice& external);
    ~Device();

    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physical_device() const { return physical_device_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    uint32_t queue_family() const { return queue_family_; }
    bool owns_device() const { return owns_; }

    const VkPhysicalDeviceProperties& properties() const { return properties_; }
    const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
    std::string_view name() const { return properties_.deviceName; }
    // The largest single VkDeviceMemory allocation (maxMemoryAllocationSize) and a memory type's heap size.
    VkDeviceSize max_allocation_size() const { return max_allocation_size_; }
    VkDeviceSize heap_size(uint32_t memory_type) const;
    // VK_EXT_memory_budget's report for a memory type's heap: how much this process may use of it and how
    // much it uses now (every allocation of the process, hemi's and the engine's). nullopt without the
    // extension (hemi enables it on devices it creates where the device has it; an engine says so in
    // ExternalDevice::memory_budget).
    struct HeapBudget
    {
        VkDeviceSize budget = 0, usage = 0;
    };
    std::optional<HeapBudget> heap_budget(uint32_t memory_type) const;
    // Lanes of a subgroup (8 on lavapipe with AVX2, 32 on NVIDIA, 32/64 on AMD).
    uint32_t subgroup_size() const { return subgroup_size_; }
    // Whether pipelines may draw with dynamic rendering (Vulkan 1.3 dynamicRendering enabled: hemi enables
    // it on devices it creates when the device supports it).
    bool dynamic_rendering() const { return dynamic_rendering_; }
    bool independent_blend() const { return independent_blend_; }
    // Nanoseconds per timestamp tick; 0 when the queue does not support timestamps.
    double timestamp_period_ns() const { return timestamp_period_ns_; }

    // A memory type index for `type_bits` with the properties `usage` needs. Throws when there is none.
    uint32_t memory_type(uint32_t type_bits, MemoryUsage usage) const;
    bool memory_is_host_visible(uint32_t memory_type) const;
    bool memory_is_host_coherent(uint32_t memory_type) const;

    // hemi's own allocator (gpu/allocator.h): sub-allocated from few blocks, its statistics and budget.
    MemoryAllocator& allocator() const { return *allocator_; }
    // Where hemi's buffers and images get their memory: the engine's provider (ExternalDevice::memory), or
    // allocator().
    MemoryProvider& memory() const;

    // Validation-layer warnings and errors seen so far (always 0 without validation).
    uint64_t validation_messages() const { return validation_messages_.load(); }

    // Hands `message` to the callback (nothing without one).
    void log(LogLevel level, std::string_view message) const noexcept;
    void wait_idle() const;

    // Names one of hemi's Vulkan objects for debuggers (RenderDoc, the validation layer's messages) when the
    // instance has VK_EXT_debug_utils enabled (a device of hemi's own: with validation on; an engine's:
    // ExternalDevice::debug_utils); otherwise does nothing. Never throws.
    void set_name(VkObjectType type, uint64_t handle, std::string_view name) const noexcept;
    template <class Handle>
    void set_name(VkObjectType type, Handle handle, std::string_view name) const noexcept
    {
        if constexpr (std::is_pointer_v<Handle>)
            set_name(type, uint64_t(reinterpret_cast<uintptr_t>(handle)), name);
        else
            set_name(type, uint64_t(handle), name);
    }
    bool debug_utils() const { return set_object_name_ != nullptr; }

  private:
    void init_properties();
    static VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                         VkDebugUtilsMessageTypeFlagsEXT types,
                                                         const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                         void* user);

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    uint32_t queue_family_ = 0;
    bool owns_ = false;
    bool dynamic_rendering_ = false;
    bool independent_blend_ = false;
    bool memory_budget_ = false;
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memory_{};
    uint32_t subgroup_size_ = 1;
    VkDeviceSize max_allocation_size_ = 0;
    double timestamp_period_ns_ = 0.0;
    LogCallback log_;
    PFN_vkSetDebugUtilsObjectNameEXT set_object_name_ = nullptr;
    std::unique_ptr<dispatch::Table> vk_; // bound to its instance, physical device and device while it lives
    std::unique_ptr<MemoryAllocator> allocator_;
    MemoryProvider* memory_provider_ = nullptr; // the engine's, or null
    std::atomic<uint64_t> validation_messages_{0};
};

} // namespace hemi::gpu
