#pragma once
// Counts the Vulkan commands hemi records and the queue work it does, as an engine would see them in a
// capture: a vkGetInstanceProcAddr for gpu::ExternalDevice that hands hemi counting wrappers of a few entry
// points and the loader's own for the rest. Used by tests (no submit on the engine path, barriers per frame)
// and by hemi-bench's scale benchmarks (their counters). Header-only; the counts are process-wide.
#include <vulkan/vulkan.h>

#include <dlfcn.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace hemi::test
{

struct VulkanCalls
{
    std::atomic<uint64_t> pipeline_barriers{0}, pipeline_binds{0}, descriptor_set_binds{0}, buffer_updates{0},
        draws{0}, dispatches{0}, push_constants{0}, vertex_buffer_binds{0}, index_buffer_binds{0}, submits{0},
        fence_waits{0}, idle_waits{0}, memory_allocations{0}, memory_frees{0};

    void reset()
    {
        for (std::atomic<uint64_t>* c :
             {&pipeline_barriers, &pipeline_binds, &descriptor_set_binds, &buffer_updates, &draws,
              &dispatches, &push_constants, &vertex_buffer_binds, &index_buffer_binds, &submits, &fence_waits,
              &idle_waits, &memory_allocations, &memory_frees})
            c->store(0);
    }
    // Commands recorded into command buffers (of the kinds hemi records on the frame path).
    uint64_t commands() const
    {
        return pipeline_barriers + pipeline_binds + descriptor_set_binds + buffer_updates + draws +
               dispatches + push_constants + vertex_buffer_binds + index_buffer_binds;
    }
    // Work handed to a queue or waited on by the host: what the engine path must never do.
    uint64_t queue_work() const { return submits + fence_waits + idle_waits; }
};

inline VulkanCalls& vulkan_calls()
{
    static VulkanCalls calls;
    return calls;
}

// The Vulkan objects made through counting_proc_addr, and the debug-utils names given to them (issue 42:
// hemi names every object it creates). Keyed by handle value; a handle made again after its destruction
// keeps its first record.
struct CreatedObjects
{
    std::mutex mutex;
    std::map<uint64_t, VkObjectType> created;
    std::map<uint64_t, std::string> names;
    std::map<uint64_t, VkBufferUsageFlags> buffer_usage; // of each buffer made

    void clear()
    {
        const std::lock_guard<std::mutex> lock(mutex);
        created.clear();
        names.clear();
        buffer_usage.clear();
    }
    // Buffers made with any of `usage`'s bits (vertex or index buffers, say).
    size_t buffers_with(VkBufferUsageFlags usage)
    {
        const std::lock_guard<std::mutex> lock(mutex);
        size_t n = 0;
        for (const auto& [handle, flags] : buffer_usage)
            n += (flags & usage) ? 1 : 0;
        return n;
    }
    void add(VkObjectType type, uint64_t handle)
    {
        const std::lock_guard<std::mutex> lock(mutex);
        created.emplace(handle, type);
    }
    // "type handle" of each object made and never named.
    std::vector<std::string> unnamed()
    {
        const std::lock_guard<std::mutex> lock(mutex);
        std::vector<std::string> out;
        for (const auto& [handle, type] : created)
            if (!names.count(handle))
                out.push_back("object type " + std::to_string(int(type)) + " handle " +
                              std::to_string(handle));
        return out;
    }
};

inline CreatedObjects& created_objects()
{
    static CreatedObjects objects;
    return objects;
}

namespace detail
{
inline PFN_vkGetInstanceProcAddr loader_proc_addr()
{
    static PFN_vkGetInstanceProcAddr gipa = []
    {
        void* library = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        if (!library)
            throw std::runtime_error("cannot open libvulkan.so.1");
        return reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(library, "vkGetInstanceProcAddr"));
    }();
    return gipa;
}

// The real entry points, fetched the first time hemi asks for them through counting_proc_addr.
#define HEMI_TEST_COUNTED(X)                                                                                 \
    X(vkCmdPipelineBarrier, pipeline_barriers)                                                               \
    X(vkCmdBindPipeline, pipeline_binds)                                                                     \
    X(vkCmdBindDescriptorSets, descriptor_set_binds)                                                         \
    X(vkCmdUpdateBuffer, buffer_updates)                                                                     \
    X(vkCmdDrawIndexed, draws)                                                                               \
    X(vkCmdDispatch, dispatches)                                                                             \
    X(vkCmdPushConstants, push_constants)                                                                    \
    X(vkCmdBindVertexBuffers, vertex_buffer_binds)                                                           \
    X(vkCmdBindIndexBuffer, index_buffer_binds)                                                              \
    X(vkQueueSubmit, submits)                                                                                \
    X(vkWaitForFences, fence_waits)                                                                          \
    X(vkDeviceWaitIdle, idle_waits)                                                                          \
    X(vkAllocateMemory, memory_allocations)                                                                  \
    X(vkFreeMemory, memory_frees)

#define HEMI_TEST_REAL(name, counter) inline PFN_##name real_##name = nullptr;
HEMI_TEST_COUNTED(HEMI_TEST_REAL)
#undef HEMI_TEST_REAL

// Entry points that make objects: vkCreateX(device, info, allocator, handle*) and the batch ones.
#define HEMI_TEST_CREATES(X)                                                                                 \
    X(vkCreateBuffer, VK_OBJECT_TYPE_BUFFER)                                                                 \
    X(vkCreateImage, VK_OBJECT_TYPE_IMAGE)                                                                   \
    X(vkCreateImageView, VK_OBJECT_TYPE_IMAGE_VIEW)                                                          \
    X(vkCreateBufferView, VK_OBJECT_TYPE_BUFFER_VIEW)                                                        \
    X(vkCreateSampler, VK_OBJECT_TYPE_SAMPLER)                                                               \
    X(vkCreatePipelineLayout, VK_OBJECT_TYPE_PIPELINE_LAYOUT)                                                \
    X(vkCreateDescriptorSetLayout, VK_OBJECT_TYPE_DESCRIPTOR_SET_LAYOUT)                                     \
    X(vkCreateDescriptorPool, VK_OBJECT_TYPE_DESCRIPTOR_POOL)                                                \
    X(vkCreateShaderModule, VK_OBJECT_TYPE_SHADER_MODULE)                                                    \
    X(vkCreateRenderPass, VK_OBJECT_TYPE_RENDER_PASS)                                                        \
    X(vkCreateFramebuffer, VK_OBJECT_TYPE_FRAMEBUFFER)                                                       \
    X(vkCreateQueryPool, VK_OBJECT_TYPE_QUERY_POOL)                                                          \
    X(vkCreateCommandPool, VK_OBJECT_TYPE_COMMAND_POOL)                                                      \
    X(vkCreateFence, VK_OBJECT_TYPE_FENCE)

#define HEMI_TEST_REAL(name, type) inline PFN_##name real_##name = nullptr;
HEMI_TEST_CREATES(HEMI_TEST_REAL)
#undef HEMI_TEST_REAL
inline PFN_vkCreateGraphicsPipelines real_vkCreateGraphicsPipelines = nullptr;
inline PFN_vkCreateComputePipelines real_vkCreateComputePipelines = nullptr;
inline PFN_vkAllocateDescriptorSets real_vkAllocateDescriptorSets = nullptr;
inline PFN_vkAllocateCommandBuffers real_vkAllocateCommandBuffers = nullptr;
inline PFN_vkSetDebugUtilsObjectNameEXT real_vkSetDebugUtilsObjectNameEXT = nullptr;

template <typename Handle> uint64_t handle_value(Handle h)
{
    if constexpr (std::is_pointer_v<Handle>)
        return uint64_t(reinterpret_cast<uintptr_t>(h));
    else
        return uint64_t(h);
}

template <typename F> struct Create;
template <typename Info, typename Handle>
struct Create<VkResult(VKAPI_PTR*)(VkDevice, const Info*, const VkAllocationCallbacks*, Handle*)>
{
    template <VkResult(VKAPI_PTR** real)(VkDevice, const Info*, const VkAllocationCallbacks*, Handle*),
              VkObjectType type>
    static VKAPI_ATTR VkResult VKAPI_CALL call(VkDevice device, const Info* info,
                                               const VkAllocationCallbacks* allocator, Handle* out)
    {
        const VkResult r = (*real)(device, info, allocator, out);
        if (r == VK_SUCCESS)
            created_objects().add(type, handle_value(*out));
        if constexpr (std::is_same_v<Info, VkBufferCreateInfo>)
            if (r == VK_SUCCESS)
            {
                CreatedObjects& c = created_objects();
                const std::lock_guard<std::mutex> lock(c.mutex);
                c.buffer_usage[handle_value(*out)] = info->usage;
            }
        return r;
    }
};

// vkCreateGraphicsPipelines and vkCreateComputePipelines: `count` pipelines at once.
template <typename Info, VkResult(VKAPI_PTR** real)(VkDevice, VkPipelineCache, uint32_t, const Info*,
                                                    const VkAllocationCallbacks*, VkPipeline*)>
VKAPI_ATTR VkResult VKAPI_CALL created_pipelines(VkDevice device, VkPipelineCache cache, uint32_t count,
                                                 const Info* infos, const VkAllocationCallbacks* allocator,
                                                 VkPipeline* out)
{
    const VkResult r = (*real)(device, cache, count, infos, allocator, out);
    for (uint32_t i = 0; r == VK_SUCCESS && i < count; ++i)
        created_objects().add(VK_OBJECT_TYPE_PIPELINE, handle_value(out[i]));
    return r;
}
inline VKAPI_ATTR VkResult VKAPI_CALL allocated_descriptor_sets(VkDevice device,
                                                                const VkDescriptorSetAllocateInfo* info,
                                                                VkDescriptorSet* out)
{
    const VkResult r = real_vkAllocateDescriptorSets(device, info, out);
    for (uint32_t i = 0; r == VK_SUCCESS && i < info->descriptorSetCount; ++i)
        created_objects().add(VK_OBJECT_TYPE_DESCRIPTOR_SET, handle_value(out[i]));
    return r;
}
inline VKAPI_ATTR VkResult VKAPI_CALL allocated_command_buffers(VkDevice device,
                                                                const VkCommandBufferAllocateInfo* info,
                                                                VkCommandBuffer* out)
{
    const VkResult r = real_vkAllocateCommandBuffers(device, info, out);
    for (uint32_t i = 0; r == VK_SUCCESS && i < info->commandBufferCount; ++i)
        created_objects().add(VK_OBJECT_TYPE_COMMAND_BUFFER, handle_value(out[i]));
    return r;
}
inline VKAPI_ATTR VkResult VKAPI_CALL named_object(VkDevice device, const VkDebugUtilsObjectNameInfoEXT* info)
{
    {
        CreatedObjects& c = created_objects();
        const std::lock_guard<std::mutex> lock(c.mutex);
        c.names[info->objectHandle] = info->pObjectName ? info->pObjectName : "";
    }
    return real_vkSetDebugUtilsObjectNameEXT ? real_vkSetDebugUtilsObjectNameEXT(device, info) : VK_SUCCESS;
}

template <typename R, typename... A> struct Wrap;
template <typename R, typename... A> struct Wrap<R(VKAPI_PTR*)(A...)>
{
    template <R(VKAPI_PTR** real)(A...), std::atomic<uint64_t> VulkanCalls::*counter>
    static VKAPI_ATTR R VKAPI_CALL call(A... args)
    {
        ++(vulkan_calls().*counter);
        return (*real)(args...);
    }
};
} // namespace detail

// Hand this to gpu::ExternalDevice::get_instance_proc_addr.
inline VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL counting_proc_addr(VkInstance instance, const char* name)
{
    using namespace detail;
    const PFN_vkGetInstanceProcAddr gipa = loader_proc_addr();
#define HEMI_TEST_WRAP(fn, counter)                                                                          \
    if (std::strcmp(name, #fn) == 0)                                                                         \
    {                                                                                                        \
        real_##fn = reinterpret_cast<PFN_##fn>(gipa(instance, name));                                        \
        if (!real_##fn)                                                                                      \
            return nullptr;                                                                                  \
        return reinterpret_cast<PFN_vkVoidFunction>(                                                         \
            &Wrap<PFN_##fn>::call<&real_##fn, &VulkanCalls::counter>);                                       \
    }
    HEMI_TEST_COUNTED(HEMI_TEST_WRAP)
#undef HEMI_TEST_WRAP
#define HEMI_TEST_WRAP(fn, type)                                                                             \
    if (std::strcmp(name, #fn) == 0)                                                                         \
    {                                                                                                        \
        real_##fn = reinterpret_cast<PFN_##fn>(gipa(instance, name));                                        \
        if (!real_##fn)                                                                                      \
            return nullptr;                                                                                  \
        return reinterpret_cast<PFN_vkVoidFunction>(&Create<PFN_##fn>::call<&real_##fn, type>);              \
    }
    HEMI_TEST_CREATES(HEMI_TEST_WRAP)
#undef HEMI_TEST_WRAP
#define HEMI_TEST_WRAP(fn, wrapper)                                                                          \
    if (std::strcmp(name, #fn) == 0)                                                                         \
    {                                                                                                        \
        real_##fn = reinterpret_cast<PFN_##fn>(gipa(instance, name));                                        \
        return real_##fn ? reinterpret_cast<PFN_vkVoidFunction>(&wrapper) : nullptr;                         \
    }
    HEMI_TEST_WRAP(vkCreateGraphicsPipelines,
                   (created_pipelines<VkGraphicsPipelineCreateInfo, &real_vkCreateGraphicsPipelines>))
    HEMI_TEST_WRAP(vkCreateComputePipelines,
                   (created_pipelines<VkComputePipelineCreateInfo, &real_vkCreateComputePipelines>))
    HEMI_TEST_WRAP(vkAllocateDescriptorSets, allocated_descriptor_sets)
    HEMI_TEST_WRAP(vkAllocateCommandBuffers, allocated_command_buffers)
    HEMI_TEST_WRAP(vkSetDebugUtilsObjectNameEXT, named_object)
#undef HEMI_TEST_WRAP
    return gipa(instance, name);
}
#undef HEMI_TEST_COUNTED
#undef HEMI_TEST_CREATES

} // namespace hemi::test
