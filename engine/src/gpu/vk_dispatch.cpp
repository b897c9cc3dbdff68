#include "vk_dispatch.h"

#include <dlfcn.h>

#include <stdexcept>
#include <string>

namespace hemi
{
#define HEMI_VK_DEFINE(name) PFN_##name name = nullptr;
HEMI_VK_GLOBAL_FUNCTIONS(HEMI_VK_DEFINE)
HEMI_VK_INSTANCE_FUNCTIONS(HEMI_VK_DEFINE)
#undef HEMI_VK_DEFINE
PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;

namespace gpu::dispatch
{
namespace
{
// The loader, opened once and kept for the life of the process (as volk does).
PFN_vkGetInstanceProcAddr open_loader()
{
    static PFN_vkGetInstanceProcAddr gipa = []
    {
        void* library = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        if (!library)
            library = dlopen("libvulkan.so", RTLD_NOW | RTLD_LOCAL);
        if (!library)
            throw std::runtime_error("hemi: cannot open the Vulkan loader libvulkan.so.1 (" +
                                     std::string(dlerror()) + ")");
        return reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(library, "vkGetInstanceProcAddr"));
    }();
    if (!gipa)
        throw std::runtime_error("hemi: the Vulkan loader libvulkan.so.1 has no vkGetInstanceProcAddr");
    return gipa;
}
} // namespace

void load_global(PFN_vkGetInstanceProcAddr get_instance_proc_addr)
{
    vkGetInstanceProcAddr = get_instance_proc_addr ? get_instance_proc_addr : open_loader();
#define HEMI_VK_LOAD(name)                                                                                   \
    name = reinterpret_cast<PFN_##name>(vkGetInstanceProcAddr(VK_NULL_HANDLE, #name));                       \
    if (!name)                                                                                               \
        throw std::runtime_error("hemi: the Vulkan implementation has no " #name);
    HEMI_VK_GLOBAL_FUNCTIONS(HEMI_VK_LOAD)
#undef HEMI_VK_LOAD
}

void load_instance(VkInstance instance)
{
#define HEMI_VK_LOAD(name)                                                                                   \
    name = reinterpret_cast<PFN_##name>(vkGetInstanceProcAddr(instance, #name));                             \
    if (!name)                                                                                               \
        throw std::runtime_error("hemi: the Vulkan instance has no " #name);
    HEMI_VK_INSTANCE_FUNCTIONS(HEMI_VK_LOAD)
#undef HEMI_VK_LOAD
}

} // namespace gpu::dispatch
} // namespace hemi
