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
#include <stdexcept>

namespace hemi::test
{

struct VulkanCalls
{
    std::atomic<uint64_t> pipeline_barriers{0}, pipeline_binds{0}, descriptor_set_binds{0}, buffer_updates{0},
        draws{0}, dispatches{0}, submits{0}, fence_waits{0}, idle_waits{0}, memory_allocations{0},
        memory_frees{0};

    void reset()
    {
        for (std::atomic<uint64_t>* c :
             {&pipeline_barriers, &pipeline_binds, &descriptor_set_binds, &buffer_updates, &draws,
              &dispatches, &submits, &fence_waits, &idle_waits, &memory_allocations, &memory_frees})
            c->store(0);
    }
    // Work handed to a queue or waited on by the host: what the engine path must never do.
    uint64_t queue_work() const { return submits + fence_waits + idle_waits; }
};

inline VulkanCalls& vulkan_calls()
{
    static VulkanCalls calls;
    return calls;
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
    X(vkQueueSubmit, submits)                                                                                \
    X(vkWaitForFences, fence_waits)                                                                          \
    X(vkDeviceWaitIdle, idle_waits)                                                                          \
    X(vkAllocateMemory, memory_allocations)                                                                  \
    X(vkFreeMemory, memory_frees)

#define HEMI_TEST_REAL(name, counter) inline PFN_##name real_##name = nullptr;
HEMI_TEST_COUNTED(HEMI_TEST_REAL)
#undef HEMI_TEST_REAL

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
    return gipa(instance, name);
}
#undef HEMI_TEST_COUNTED

} // namespace hemi::test
