#include "vk_dispatch.h"

#include <dlfcn.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>

namespace hemi::gpu::dispatch
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

// The bindings: a few slots (one to three keys per live Device), read without a lock on every Vulkan call
// hemi makes, written under one. A slot is live while its key is not null; `order` tells the later of two
// bindings of one key.
struct Slot
{
    std::atomic<const void*> key{nullptr};
    std::atomic<const Table*> table{nullptr};
    std::atomic<uint64_t> order{0};
};
constexpr size_t kSlots = 64;
std::array<Slot, kSlots> slots;
std::atomic<size_t> used{0}; // slots [0, used) may be live
std::mutex writer;
uint64_t next_order = 1; // under writer

const void* key_of(const void* handle)
{
    return handle ? *static_cast<const void* const*>(handle) : nullptr;
}
} // namespace

Globals load_global(PFN_vkGetInstanceProcAddr get_instance_proc_addr)
{
    Globals g;
    g.vkGetInstanceProcAddr = get_instance_proc_addr ? get_instance_proc_addr : open_loader();
#define HEMI_VK_LOAD(name)                                                                                   \
    g.name = reinterpret_cast<PFN_##name>(g.vkGetInstanceProcAddr(VK_NULL_HANDLE, #name));                   \
    if (!g.name)                                                                                             \
        throw std::runtime_error("hemi: the Vulkan implementation has no " #name);
    HEMI_VK_GLOBAL_FUNCTIONS(HEMI_VK_LOAD)
#undef HEMI_VK_LOAD
    return g;
}

void load_instance(const Globals& globals, VkInstance instance, Table& table)
{
    table.vkGetInstanceProcAddr = globals.vkGetInstanceProcAddr;
#define HEMI_VK_LOAD(name)                                                                                   \
    table.name = reinterpret_cast<PFN_##name>(globals.vkGetInstanceProcAddr(instance, #name));               \
    if (!table.name)                                                                                         \
        throw std::runtime_error("hemi: the Vulkan instance has no " #name);
    HEMI_VK_INSTANCE_FUNCTIONS(HEMI_VK_LOAD)
#undef HEMI_VK_LOAD
}

void bind(const void* handle, const Table* table)
{
    const void* key = key_of(handle);
    if (!key || !table)
        throw std::invalid_argument("hemi: a Vulkan handle without a dispatch key cannot be bound");
    const std::lock_guard<std::mutex> lock(writer);
    const size_t n = used.load(std::memory_order_relaxed);
    for (size_t i = 0; i < n; ++i)
        if (slots[i].key.load(std::memory_order_relaxed) == key &&
            slots[i].table.load(std::memory_order_relaxed) == table)
            return; // already bound (a physical device that shares its instance's key)
    size_t free = n;
    for (size_t i = 0; i < n && free == n; ++i)
        if (!slots[i].key.load(std::memory_order_relaxed))
            free = i;
    if (free == kSlots)
        throw std::runtime_error("hemi: more than " + std::to_string(kSlots) +
                                 " Vulkan dispatch keys bound at once (gpu::Device objects alive)");
    slots[free].table.store(table, std::memory_order_relaxed);
    slots[free].order.store(next_order++, std::memory_order_relaxed);
    slots[free].key.store(key, std::memory_order_release);
    if (free == n)
        used.store(n + 1, std::memory_order_release);
}

void unbind(const Table* table)
{
    const std::lock_guard<std::mutex> lock(writer);
    const size_t n = used.load(std::memory_order_relaxed);
    for (size_t i = 0; i < n; ++i)
        if (slots[i].table.load(std::memory_order_relaxed) == table)
            slots[i].key.store(nullptr, std::memory_order_release);
}

const Table& of(const void* handle)
{
    const void* key = key_of(handle);
    const Table* found = nullptr;
    uint64_t latest = 0;
    const size_t n = used.load(std::memory_order_acquire);
    for (size_t i = 0; i < n; ++i)
        if (key && slots[i].key.load(std::memory_order_acquire) == key)
        {
            const uint64_t order = slots[i].order.load(std::memory_order_relaxed);
            if (order > latest)
            {
                latest = order;
                found = slots[i].table.load(std::memory_order_relaxed);
            }
        }
    if (!found)
    {
        std::fprintf(stderr,
                     "hemi: Vulkan handle %p belongs to no live gpu::Device (a handle of another device, or "
                     "one used after its Device was destroyed)\n",
                     handle);
        std::abort();
    }
    return *found;
}

} // namespace hemi::gpu::dispatch
