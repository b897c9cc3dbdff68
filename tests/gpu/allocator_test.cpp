// Device memory is sub-allocated: many small buffers and images share a few VkDeviceMemory blocks, freed
// ranges are reused, a block emptied goes back to the driver, and a request larger than half a block gets a
// block of its own. Objects retired to a DeletionQueue live until their frame is collected.
#include "../gpu_fixture.h"
#include "../host_vulkan.h"

#include <hemi/gpu/allocator.h>
#include <hemi/gpu/deletion_queue.h>
#include <hemi/gpu/resources.h>
#include <hemi/render/transfer.h>
#include <hemi/render/view/offscreen.h>

#include <dlfcn.h>

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace
{
class Allocator : public hemi::test::GpuTest
{
};
} // namespace

TEST_F(Allocator, ManyBuffersAndImagesShareFewBlocks)
{
    auto& dev = hemi::test::device();
    const auto before = dev.allocator().stats();
    {
        std::vector<hemi::gpu::Buffer> buffers;
        std::vector<hemi::gpu::Image> images;
        for (int i = 0; i < 300; ++i)
            buffers.push_back(hemi::gpu::create_buffer(dev, {4096, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT}));
        for (int i = 0; i < 100; ++i)
            images.push_back(hemi::gpu::create_image(dev, {64, 64, VK_FORMAT_R8G8B8A8_UNORM}));
        const auto during = dev.allocator().stats();
        EXPECT_EQ(during.allocations - before.allocations, 400u);
        // 300 x 4 KiB of buffers and 100 x 16 KiB of images: one linear and one optimal block at most.
        EXPECT_LE(during.blocks - before.blocks, 2u) << "each resource got its own vkAllocateMemory";
        // Distinct, non-overlapping ranges: each buffer keeps what is written to it.
        for (size_t i = 0; i < buffers.size(); ++i)
        {
            const uint32_t v = uint32_t(i) * 2654435761u;
            hemi::gpu::write_buffer(dev, buffers[i], &v, 4, 4092);
        }
        for (size_t i = 0; i < buffers.size(); ++i)
        {
            uint32_t v = 0;
            hemi::gpu::read_buffer(dev, buffers[i], &v, 4, 4092);
            ASSERT_EQ(v, uint32_t(i) * 2654435761u) << "buffer " << i << " overlaps another";
        }
    }
    const auto after = dev.allocator().stats();
    EXPECT_EQ(after.allocations, before.allocations);
    EXPECT_EQ(after.used_bytes, before.used_bytes) << "freed ranges return to their blocks";
    // The blocks the round emptied went back to the driver (an allocator that keeps empty blocks holds
    // 64 MiB per memory type for nothing after a level is unloaded).
    EXPECT_EQ(after.blocks, before.blocks) << "an empty block was kept";
    // Freed ranges of a block still in use are reused: every other buffer freed and made again takes no
    // new block.
    std::vector<hemi::gpu::Buffer> buffers;
    for (int i = 0; i < 300; ++i)
        buffers.push_back(hemi::gpu::create_buffer(dev, {4096, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT}));
    const size_t blocks = dev.allocator().stats().blocks;
    for (size_t i = 0; i < buffers.size(); i += 2)
        buffers[i] = {};
    for (size_t i = 0; i < buffers.size(); i += 2)
        buffers[i] = hemi::gpu::create_buffer(dev, {4096, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    EXPECT_EQ(dev.allocator().stats().blocks, blocks);
}

TEST_F(Allocator, LargeRequestsGetADedicatedBlockThatIsFreed)
{
    auto& dev = hemi::test::device();
    const auto before = dev.allocator().stats();
    {
        hemi::gpu::Buffer big =
            hemi::gpu::create_buffer(dev, {VkDeviceSize(48) << 20, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        EXPECT_EQ(dev.allocator().stats().blocks, before.blocks + 1);
    }
    EXPECT_EQ(dev.allocator().stats().blocks, before.blocks);
}

TEST(DeletionQueue, KeepsObjectsAliveUntilTheirFrameIsCollected)
{
    struct Tracked
    {
        int* alive;
        explicit Tracked(int* a) : alive(a) { ++*alive; }
        Tracked(Tracked&& o) noexcept : alive(o.alive) { o.alive = nullptr; }
        ~Tracked()
        {
            if (alive)
                --*alive;
        }
    };
    int alive = 0;
    hemi::gpu::DeletionQueue q;
    q.retire(5, Tracked(&alive));
    q.retire(7, Tracked(&alive));
    EXPECT_EQ(alive, 2);
    q.collect(4);
    EXPECT_EQ(alive, 2) << "frame 5 has not finished";
    q.collect(5);
    EXPECT_EQ(alive, 1);
    EXPECT_EQ(q.pending(), 1u);
    q.collect(100);
    EXPECT_EQ(alive, 0);
}

// Every device limit a request can exceed is refused before Vulkan is asked, naming the limit and the device
// (a raw VK_ERROR_* from deep in a create or a bind names no cause): an image wider than
// maxImageDimension2D, a render target taller than maxFramebufferHeight, a resource larger than its memory
// heap (and than maxMemoryAllocationSize: every limit exceeded is named). The limits are the device's own,
// read here; nothing is created.
TEST_F(Allocator, RequestsBeyondTheDevicesLimitsAreRefusedNamingTheLimit)
{
    auto& dev = hemi::test::device();
    const VkPhysicalDeviceLimits& limits = dev.limits();
    auto refused = [](const std::function<void()>& f) -> std::string
    {
        try
        {
            f();
        }
        catch (const std::invalid_argument& e)
        {
            return e.what();
        }
        return "(accepted)";
    };
    std::string why = refused(
        [&] {
            hemi::gpu::create_image(dev, {limits.maxImageDimension2D + 1, 1, VK_FORMAT_R8G8B8A8_UNORM});
        });
    EXPECT_NE(why.find("maxImageDimension2D (" + std::to_string(limits.maxImageDimension2D) + ")"),
              std::string::npos)
        << why;
    why = refused([&] { hemi::render::OffscreenTarget(dev, 1, limits.maxFramebufferHeight + 1); });
    EXPECT_NE(why.find("maxFramebufferWidth/Height"), std::string::npos) << why;
    EXPECT_NE(why.find(std::to_string(limits.maxFramebufferHeight)), std::string::npos) << why;

    const uint32_t type = dev.memory_type(~0u, hemi::gpu::MemoryUsage::GpuOnly);
    const VkDeviceSize heap = dev.heap_size(type);
    why = refused(
        [&] {
            dev.allocator().allocate({{heap + 1, 256, ~0u}, hemi::gpu::MemoryUsage::GpuOnly, false});
        });
    EXPECT_NE(why.find("exceeds its memory heap"), std::string::npos) << why;
    // Every limit exceeded is named: lavapipe's heap and maxMemoryAllocationSize are both 2 GiB.
    if (dev.max_allocation_size() && dev.max_allocation_size() < heap + 1)
    {
        EXPECT_NE(why.find("maxMemoryAllocationSize"), std::string::npos) << why;
    }
    // Within the heap but beyond one allocation's limit, where the device has such a gap.
    if (dev.max_allocation_size() && dev.max_allocation_size() < heap)
    {
        why = refused(
            [&]
            {
                dev.allocator().allocate(
                    {{dev.max_allocation_size() + 1, 256, ~0u}, hemi::gpu::MemoryUsage::GpuOnly, false});
            });
        EXPECT_NE(why.find("maxMemoryAllocationSize"), std::string::npos) << why;
        EXPECT_EQ(why.find("heap"), std::string::npos) << why;
    }
}

namespace
{
// An engine's own allocator, as simple as one can be: one vkAllocateMemory per resource, mapped when the
// memory is host-visible and coherent, counted.
struct EngineMemory final : hemi::gpu::MemoryProvider
{
    VkDevice device = VK_NULL_HANDLE;
    VkPhysicalDeviceMemoryProperties props{};
    int live = 0, total = 0;
    bool forget_mapping = false; // a broken provider: no host pointer for memory the CPU writes

    explicit EngineMemory(const hemi::test::HostVulkan& host) : device(host.vk_device)
    {
        vkGetPhysicalDeviceMemoryProperties(host.pd, &props);
    }
    Range allocate(const hemi::gpu::MemoryRequest& request) override
    {
        const VkMemoryRequirements& req = request.requirements;
        const hemi::gpu::MemoryUsage usage = request.usage;
        const VkMemoryPropertyFlags host =
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        const VkMemoryPropertyFlags need = usage == hemi::gpu::MemoryUsage::GpuOnly ? 0 : host;
        uint32_t type = 32;
        for (uint32_t i = 0; i < props.memoryTypeCount && type == 32; ++i)
            if ((req.memoryTypeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & need) == need)
                type = i;
        if (type == 32)
            throw std::runtime_error("engine: no memory type");
        VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        info.allocationSize = req.size;
        info.memoryTypeIndex = type;
        Range r;
        if (vkAllocateMemory(device, &info, nullptr, &r.memory) != VK_SUCCESS)
            throw std::runtime_error("engine: vkAllocateMemory failed");
        r.size = req.size;
        r.memory_type = type;
        if (!forget_mapping && (props.memoryTypes[type].propertyFlags & host) == host)
            vkMapMemory(device, r.memory, 0, VK_WHOLE_SIZE, 0, &r.mapped);
        ++live;
        ++total;
        return r;
    }
    void free(const Range& r) noexcept override
    {
        vkFreeMemory(device, r.memory, nullptr);
        --live;
    }
};
} // namespace

// An engine's own allocator serves hemi (ExternalDevice::memory): every buffer and image hemi makes on the
// adopted device comes from it, hemi's own allocator holds nothing, the data round-trips, and every range
// goes back when hemi's objects are destroyed. A provider that returns no host pointer for memory the CPU
// must write is refused by name, and its range given back.
TEST_F(Allocator, AnEnginesOwnProviderServesEveryResource)
{
    hemi::test::HostVulkan host;
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    EngineMemory engine(host);
    hemi::gpu::ExternalDevice external = host.external();
    external.memory = &engine;
    {
        hemi::gpu::Device dev(external);
        std::vector<float> t(40 * 4 * 9);
        for (size_t i = 0; i < t.size(); ++i)
            t[i] = float(i % 5) - 2.0f;
        hemi::render::TransferMatrices m(40, 4, 9, t);
        hemi::render::TransferPass pass(dev, m);
        std::vector<glm::vec3> light(9, glm::vec3(0.0f));
        light[4] = glm::vec3(1.0f);
        pass.run(light);
        const std::vector<float> c = pass.read_coefficients();
        EXPECT_EQ(c[(39 * 4 + 2) * 4 + 1], t[(39 * 4 + 2) * 9 + 4]);
        const hemi::gpu::Image image = hemi::gpu::create_image(dev, {32, 32, VK_FORMAT_R8G8B8A8_UNORM});
        EXPECT_GE(engine.live, 4) << "the matrices, lighting, coefficients and the image";
        EXPECT_EQ(dev.allocator().stats().blocks, 0u) << "hemi allocated memory of its own";
    }
    EXPECT_EQ(engine.live, 0) << "a range was not given back";
    EXPECT_GE(engine.total, 4);

    engine.forget_mapping = true;
    hemi::gpu::Device dev(external);
    try
    {
        (void)hemi::gpu::create_buffer(
            dev, {256, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, hemi::gpu::MemoryUsage::Upload});
        ADD_FAILURE() << "a range without a host pointer was taken for upload memory";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("no host pointer"), std::string::npos) << e.what();
    }
    EXPECT_EQ(engine.live, 0) << "the refused range was not given back";
}

// A budget (MemoryAllocator::set_budget) refuses the block that would exceed it, with an error that names
// the budget, before the driver is asked; within it, and without one, the same requests succeed.
TEST_F(Allocator, ABudgetRefusesTheBlockBeyondIt)
{
    hemi::test::HostVulkan host;
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    hemi::gpu::Device dev(host.external());
    const VkDeviceSize mib = VkDeviceSize(1) << 20;
    dev.allocator().set_budget(100 * mib);
    const hemi::gpu::Buffer small = hemi::gpu::create_buffer(dev, {4096, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    EXPECT_EQ(dev.allocator().stats().block_bytes, 64 * mib);
    try
    {
        (void)hemi::gpu::create_buffer(dev, {40 * mib, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        ADD_FAILURE() << "64 + 40 MiB of blocks under a budget of 100 MiB";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("budget of 100 MiB"), std::string::npos) << e.what();
    }
    EXPECT_EQ(dev.allocator().stats().blocks, 1u);
    // 30 MiB fits the block already held: no new block, within the budget.
    const hemi::gpu::Buffer fits =
        hemi::gpu::create_buffer(dev, {30 * mib, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    EXPECT_EQ(dev.allocator().stats().blocks, 1u);
    dev.allocator().set_budget(0);
    const hemi::gpu::Buffer unbounded =
        hemi::gpu::create_buffer(dev, {40 * mib, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    EXPECT_EQ(dev.allocator().stats().blocks, 2u);
}

namespace
{
// A driver that asks for dedicated allocations and reports heap budgets, as desktop drivers do and lavapipe
// does not: hemi gets its entry points through `fake_driver_proc_addr`, whose wrappers of
// vkGet{Buffer,Image}MemoryRequirements2 set prefersDedicatedAllocation for resources of at least
// `prefer_dedicated_from` bytes, whose vkAllocateMemory records which allocations name their resource
// (VkMemoryDedicatedAllocateInfo) and the bytes alive, and whose vkGetPhysicalDeviceMemoryProperties2
// reports VK_EXT_memory_budget's numbers (heapBudget = `heap_budget`, heapUsage = the bytes alive). The
// calls still reach lavapipe through the validation layer, so a malformed dedicated allocation (its size
// not the resource's) is reported.
struct FakeDriver
{
    VkDeviceSize prefer_dedicated_from = 0; // 0: never
    VkDeviceSize heap_budget = 0;
    VkDeviceSize live_bytes = 0;
    std::map<VkDeviceMemory, VkDeviceSize> sizes;
    std::vector<VkImage> dedicated_images;
    std::vector<VkBuffer> dedicated_buffers;
    PFN_vkGetInstanceProcAddr gipa = nullptr;
    PFN_vkGetBufferMemoryRequirements2 buffer_requirements = nullptr;
    PFN_vkGetImageMemoryRequirements2 image_requirements = nullptr;
    PFN_vkAllocateMemory allocate = nullptr;
    PFN_vkFreeMemory free = nullptr;
    PFN_vkGetPhysicalDeviceMemoryProperties2 memory_properties = nullptr;
};
FakeDriver& fake_driver()
{
    static FakeDriver driver;
    return driver;
}

void ask_for_dedicated(VkMemoryRequirements2* requirements)
{
    for (auto* s = static_cast<VkBaseOutStructure*>(requirements->pNext); s; s = s->pNext)
        if (s->sType == VK_STRUCTURE_TYPE_MEMORY_DEDICATED_REQUIREMENTS &&
            fake_driver().prefer_dedicated_from &&
            requirements->memoryRequirements.size >= fake_driver().prefer_dedicated_from)
            reinterpret_cast<VkMemoryDedicatedRequirements*>(s)->prefersDedicatedAllocation = VK_TRUE;
}

VKAPI_ATTR void VKAPI_CALL fake_buffer_requirements(VkDevice d, const VkBufferMemoryRequirementsInfo2* info,
                                                    VkMemoryRequirements2* requirements)
{
    fake_driver().buffer_requirements(d, info, requirements);
    ask_for_dedicated(requirements);
}

VKAPI_ATTR void VKAPI_CALL fake_image_requirements(VkDevice d, const VkImageMemoryRequirementsInfo2* info,
                                                   VkMemoryRequirements2* requirements)
{
    fake_driver().image_requirements(d, info, requirements);
    ask_for_dedicated(requirements);
}

VKAPI_ATTR VkResult VKAPI_CALL fake_allocate(VkDevice d, const VkMemoryAllocateInfo* info,
                                             const VkAllocationCallbacks* callbacks, VkDeviceMemory* memory)
{
    FakeDriver& f = fake_driver();
    const VkResult r = f.allocate(d, info, callbacks, memory);
    if (r != VK_SUCCESS)
        return r;
    f.sizes[*memory] = info->allocationSize;
    f.live_bytes += info->allocationSize;
    for (auto* s = static_cast<const VkBaseInStructure*>(info->pNext); s; s = s->pNext)
        if (s->sType == VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO)
        {
            const auto* dedicated = reinterpret_cast<const VkMemoryDedicatedAllocateInfo*>(s);
            if (dedicated->image)
                f.dedicated_images.push_back(dedicated->image);
            if (dedicated->buffer)
                f.dedicated_buffers.push_back(dedicated->buffer);
        }
    return r;
}

VKAPI_ATTR void VKAPI_CALL fake_free(VkDevice d, VkDeviceMemory memory,
                                     const VkAllocationCallbacks* callbacks)
{
    FakeDriver& f = fake_driver();
    if (auto it = f.sizes.find(memory); it != f.sizes.end())
    {
        f.live_bytes -= it->second;
        f.sizes.erase(it);
    }
    f.free(d, memory, callbacks);
}

VKAPI_ATTR void VKAPI_CALL fake_memory_properties(VkPhysicalDevice pd, VkPhysicalDeviceMemoryProperties2* p)
{
    // The budget structure is the fake's to fill: lavapipe (and the validation layer) do not know it.
    VkPhysicalDeviceMemoryBudgetPropertiesEXT* budget = nullptr;
    if (p->pNext && static_cast<VkBaseOutStructure*>(p->pNext)->sType ==
                        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MEMORY_BUDGET_PROPERTIES_EXT)
    {
        budget = static_cast<VkPhysicalDeviceMemoryBudgetPropertiesEXT*>(p->pNext);
        p->pNext = budget->pNext;
    }
    fake_driver().memory_properties(pd, p);
    if (budget)
    {
        p->pNext = budget;
        for (uint32_t h = 0; h < p->memoryProperties.memoryHeapCount; ++h)
        {
            budget->heapBudget[h] = fake_driver().heap_budget;
            budget->heapUsage[h] = fake_driver().live_bytes;
        }
    }
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL fake_driver_proc_addr(VkInstance instance, const char* name)
{
    FakeDriver& f = fake_driver();
    if (!f.gipa)
    {
        void* library = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        f.gipa = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(library, "vkGetInstanceProcAddr"));
    }
    const PFN_vkVoidFunction real = f.gipa(instance, name);
    auto hook = [&](auto& slot, auto wrapper)
    {
        slot = reinterpret_cast<std::remove_reference_t<decltype(slot)>>(real);
        return real ? reinterpret_cast<PFN_vkVoidFunction>(wrapper) : nullptr;
    };
    const std::string n = name;
    if (n == "vkGetBufferMemoryRequirements2")
        return hook(f.buffer_requirements, &fake_buffer_requirements);
    if (n == "vkGetImageMemoryRequirements2")
        return hook(f.image_requirements, &fake_image_requirements);
    if (n == "vkAllocateMemory")
        return hook(f.allocate, &fake_allocate);
    if (n == "vkFreeMemory")
        return hook(f.free, &fake_free);
    if (n == "vkGetPhysicalDeviceMemoryProperties2")
        return hook(f.memory_properties, &fake_memory_properties);
    return real;
}
} // namespace

// A resource the driver asks to have its own memory (VkMemoryDedicatedRequirements) gets a VkDeviceMemory of
// its own, allocated with VkMemoryDedicatedAllocateInfo naming it, and given back with it; small resources
// the driver does not ask about still share blocks. (An allocator that ignores the request sub-allocates the
// 4 MiB image from a 64 MiB block, and the fake driver sees no allocation naming it.)
TEST_F(Allocator, AResourceTheDriverAsksToHaveItsOwnMemoryGetsADedicatedAllocation)
{
    hemi::test::HostVulkan host;
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    FakeDriver& fake = fake_driver();
    fake.prefer_dedicated_from = VkDeviceSize(1) << 20;
    fake.dedicated_images.clear();
    fake.dedicated_buffers.clear();
    {
        hemi::gpu::Device dev(host.external(&fake_driver_proc_addr));
        const hemi::gpu::Image small = hemi::gpu::create_image(dev, {64, 64, VK_FORMAT_R8G8B8A8_UNORM});
        EXPECT_EQ(dev.allocator().stats().dedicated, 0u);
        {
            const hemi::gpu::Image large = hemi::gpu::create_image(
                dev, {1024, 1024, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT});
            const hemi::gpu::Buffer buffer =
                hemi::gpu::create_buffer(dev, {2u << 20, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
            EXPECT_EQ(dev.allocator().stats().dedicated, 2u);
            ASSERT_EQ(fake.dedicated_images.size(), 1u);
            EXPECT_EQ(fake.dedicated_images[0], large.handle());
            ASSERT_EQ(fake.dedicated_buffers.size(), 1u);
            EXPECT_EQ(fake.dedicated_buffers[0], buffer.handle());
            // Both are usable: the buffer round-trips (the validation layer checks the bindings).
            const uint32_t v = 0x600dcafe;
            hemi::gpu::write_buffer(dev, buffer, &v, 4, (2u << 20) - 4);
            uint32_t back = 0;
            hemi::gpu::read_buffer(dev, buffer, &back, 4, (2u << 20) - 4);
            EXPECT_EQ(back, v);
        }
        EXPECT_EQ(dev.allocator().stats().dedicated, 0u) << "a dedicated block outlived its resource";
        EXPECT_EQ(dev.allocator().stats().allocations, 1u);
    }
    fake.prefer_dedicated_from = 0;
    EXPECT_EQ(fake.live_bytes, 0u) << "memory not given back to the driver";
}

// Where the device has VK_EXT_memory_budget (ExternalDevice::memory_budget), a new block that would take its
// heap past the budget the driver reports is refused with an error naming the extension and the figures;
// once memory is given back, the same request succeeds. (An allocator that ignores the budget takes the
// third 40 MiB block under a budget of 100 MiB.)
TEST_F(Allocator, KeepsWithinTheHeapBudgetTheDriverReports)
{
    hemi::test::HostVulkan host;
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    FakeDriver& fake = fake_driver();
    const VkDeviceSize mib = VkDeviceSize(1) << 20;
    fake.heap_budget = 100 * mib;
    hemi::gpu::ExternalDevice external = host.external(&fake_driver_proc_addr);
    external.memory_budget = true;
    {
        hemi::gpu::Device dev(external);
        const uint32_t type = dev.memory_type(~0u, hemi::gpu::MemoryUsage::GpuOnly);
        ASSERT_TRUE(dev.heap_budget(type).has_value());
        EXPECT_EQ(dev.heap_budget(type)->budget, 100 * mib);
        std::vector<hemi::gpu::Buffer> buffers;
        for (int i = 0; i < 2; ++i)
            buffers.push_back(hemi::gpu::create_buffer(dev, {40 * mib, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT}));
        EXPECT_EQ(dev.heap_budget(type)->usage, 80 * mib);
        try
        {
            (void)hemi::gpu::create_buffer(dev, {40 * mib, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
            ADD_FAILURE() << "120 MiB taken from a heap whose budget is 100 MiB";
        }
        catch (const std::runtime_error& e)
        {
            const std::string why = e.what();
            EXPECT_NE(why.find("VK_EXT_memory_budget"), std::string::npos) << why;
            EXPECT_NE(why.find("budget of 100 MiB"), std::string::npos) << why;
            EXPECT_NE(why.find("80 MiB in use"), std::string::npos) << why;
        }
        buffers.pop_back();
        buffers.push_back(hemi::gpu::create_buffer(dev, {40 * mib, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT}));
        EXPECT_EQ(dev.allocator().stats().blocks, 2u);
    }
    fake.heap_budget = 0;
}
