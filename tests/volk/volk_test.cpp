// An engine as many are built: compiled with -fno-exceptions, loading Vulkan with volk (Debian's
// libvulkan-volk-dev: VK_NO_PROTOTYPES, volk's function pointers in place of the loader's prototypes),
// including every public header of hemi in one translation unit. It hands hemi its own device and volk's
// vkGetInstanceProcAddr, round-trips a buffer and an image, then loads through hemi/render/create.h (after
// five loads that must be refused by name, none of which may throw into this code) a lightmapped level, a PRT
// model of 4 objects and 16 probe-lit objects and draws frames the engine's way: 2 frames in flight,
// per-frame data written through mapped memory, the PRT transfer recorded with the barriers the engine makes
// from hemi's declared accesses, every draw through one sorted DrawQueue. The executable does not link the
// Vulkan loader (volk opens it; hemi loads through volk's entry point).
//
//   (no argument)         under the validation layer: any warning or error fails the program.
//   --count-allocations   without the layer (the layer allocates for what it tracks): a counting global
//                         operator new must read 0 over each steady-state frame, hemi's calls and the
//                         engine's recording of the frame alike (issue 42).
//
// Broken once to see it fail: DrawQueue::sort() on std::stable_sort (its temporary buffer) counts one
// allocation in each steady frame.
#include <volk.h>

#include "hemi_public_headers.h" // generated: every header of engine/include, baker/include, shaders/include

#include "../render/sphere_asset.h"
#include "../render/table_level.h"

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <vector>

#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
#error "this consumer is compiled with -fno-exceptions"
#endif

namespace
{
// Counted on the thread that records the frame (hemi's calls and the engine's recording), not on the
// driver's threads. hemi's frame-path calls run on their caller's thread (no TBB task on the frame path), so
// this thread sees every allocation they make.
thread_local bool counting = false;
thread_local uint64_t allocations = 0;

void* counted(size_t size, size_t align = 0)
{
    if (counting)
        ++allocations;
    void* p =
        align ? std::aligned_alloc(align, (size + align - 1) / align * align) : std::malloc(size ? size : 1);
    if (!p)
        std::abort();
    return p;
}

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

bool ok(VkResult r, const char* what)
{
    if (r != VK_SUCCESS)
        std::fprintf(stderr, "volk test: %s failed: %d\n", what, int(r));
    return r == VK_SUCCESS;
}

int fail(const char* what)
{
    std::fprintf(stderr, "volk test: %s\n", what);
    return 1;
}

// hemi's Vulkan objects on the engine's device: a buffer and an image round-tripped, then frames drawn.
// Returns the process's exit code.
int run_hemi(VkInstance instance, VkPhysicalDevice physical, VkDevice device, VkQueue queue, uint32_t family,
             bool count_allocations)
{
    using namespace hemi;
    gpu::ExternalDevice external;
    external.instance = instance;
    external.physical_device = physical;
    external.device = device;
    external.queue = queue;
    external.queue_family = family;
    external.get_instance_proc_addr = vkGetInstanceProcAddr; // volk's
    int hemi_errors = 0;
    external.log = [&hemi_errors](gpu::LogLevel level, bool, std::string_view message)
    {
        if (level == gpu::LogLevel::Error)
        {
            std::fprintf(stderr, "hemi: %.*s\n", int(message.size()), message.data());
            ++hemi_errors;
        }
    };
    // Loading through render/create.h: what hemi's constructors and readers throw stays inside hemi. First
    // what cannot load, each refused with a message naming the problem, and logged where a device is known.
    {
        gpu::ExternalDevice no_queue = external;
        no_queue.queue = VK_NULL_HANDLE;
        const Created<gpu::Device> refused = render::create_device(no_queue);
        if (refused || refused.error().find("queue") == std::string::npos)
            return fail("a device without a queue was not refused by name");
    }
    const Created<gpu::Device> made_device = render::create_device(external);
    if (!made_device)
        return fail(made_device.error().c_str());
    const gpu::Device& dev = *made_device;
    if (const Created<io::LightmapAsset> missing =
            render::read_lightmap_asset("/nonexistent/missing_level.hemi");
        missing || missing.error().find("missing_level.hemi") == std::string::npos)
        return fail("a missing asset was not refused with its file named");
    {
        const char* garbage = "volk_test_garbage.hemi";
        std::FILE* f = std::fopen(garbage, "wb");
        if (!f || std::fputs("not an asset at all", f) < 0 || std::fclose(f) != 0)
            return fail("could not write the garbage asset");
        const Created<io::PrtAsset> refused = render::read_prt_asset(garbage);
        std::remove(garbage);
        if (refused || refused.error().find(garbage) == std::string::npos)
            return fail("a file that is not an asset was not refused with its name");
    }
    {
        const Created<render::MaterialSystem> system = render::create_material_system(dev);
        if (!system)
            return fail(system.error().c_str());
        gpu::UploadBatch upload(dev);
        const io::LightmapAsset asset = test::table_level(io::Material{}, io::Material{}, {}, {"h4"});
        const Created<render::LightmapModel> unknown =
            render::create_lightmap_model(*system, asset, {"h9"}, upload);
        if (unknown || unknown.error().find("h9") == std::string::npos)
            return fail("a technique the asset does not hold was not refused by name");
        const Created<render::LightmapModel> level =
            render::create_lightmap_model(*system, asset, {"h4"}, upload);
        if (!level)
            return fail(level.error().c_str());
        render::PassDesc colourless; // a colour pass into a target without colour attachments
        colourless.target.color_attachments = 0;
        size_t index = 0;
        if (render::add_pass(*level, colourless, index))
            return fail("a colour pass without colour attachments was added");
        std::vector<render::LightmapDraw> entries(3);
        if (render::draw_list(*level, "h6", 0, entries) || !entries.empty())
            return fail("a draw list of a technique the level did not load was made");
        // The device (to the ExternalDevice's own callback), the model, the pass and the draw list were
        // logged; the files had no device to log to.
        if (hemi_errors != 4)
            return fail("the refusals with a device were not all logged");
        hemi_errors = 0;
    }
    {
        std::vector<float> values(256);
        for (size_t i = 0; i < values.size(); ++i)
            values[i] = float(i) * 0.5f;
        const gpu::Buffer buffer =
            gpu::create_buffer(dev, {values.size() * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                     gpu::MemoryUsage::GpuOnly});
        gpu::write_buffer(dev, buffer, values.data(), values.size() * sizeof(float));
        std::vector<float> back(values.size());
        gpu::read_buffer(dev, buffer, back.data(), back.size() * sizeof(float));
        if (back != values)
            return fail("a buffer written and read back through hemi differs");
        const gpu::Image image =
            gpu::create_image(dev, {4, 4, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT});
        std::vector<uint8_t> texels(64);
        for (size_t i = 0; i < texels.size(); ++i)
            texels[i] = uint8_t(i * 3);
        gpu::upload_image(dev, image, texels.data(), texels.size(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        const std::vector<std::byte> read =
            gpu::read_image(dev, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        if (read.size() != texels.size() || std::memcmp(read.data(), texels.data(), texels.size()) != 0)
            return fail("an image uploaded and read back through hemi differs");
    }

    // Loading.
    constexpr uint32_t kInFlight = 2, kPrtObjects = 4, kProbeObjects = 16, kFrames = 12, kWarmFrames = 4;
    render::OffscreenTarget target(dev, 64, 64);
    const Created<render::MaterialSystem> made_system = render::create_material_system(dev, target.desc());
    if (!made_system)
        return fail(made_system.error().c_str());
    render::MaterialSystem& system = *made_system;
    gpu::UploadBatch upload(dev);
    render::PrtModelDesc desc;
    desc.technique = "h4";
    desc.instances = kPrtObjects;
    desc.frames_in_flight = kInFlight;
    const Created<render::PrtModel> made_prt =
        render::create_prt_model(system, test::unshadowed_sphere_asset(12, 6, "h4", 4), desc, upload);
    const Created<render::LightmapModel> made_level = render::create_lightmap_model(
        system, test::table_level(io::Material{}, io::Material{}, {}, {"h4"}), {"h4"}, upload);
    const Created<render::ProbeObject> made_probes =
        render::create_probe_object(system, io::make_uv_sphere(0.2f, 8, 4), {}, std::vector<io::Material>(1),
                                    {}, kProbeObjects, upload, kInFlight);
    const Created<render::FrameSet> made_frame_set = render::create_frame_set(system, kInFlight);
    std::vector<render::LightmapDraw> level_draws;
    if (!made_prt || !made_level || !made_probes || !made_frame_set ||
        !render::draw_list(*made_level, "h4", 0, level_draws))
        return fail("loading failed (see hemi's messages)");
    render::PrtModel& prt = *made_prt;
    render::LightmapModel& level = *made_level;
    render::ProbeObject& probes = *made_probes;
    render::FrameSet& frame_set = *made_frame_set;

    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = family;
    VkCommandPool pool = VK_NULL_HANDLE;
    if (!ok(vkCreateCommandPool(device, &pi, nullptr, &pool), "vkCreateCommandPool"))
        return 1;
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = kInFlight;
    VkCommandBuffer cmds[kInFlight];
    VkFence fences[kInFlight];
    bool good = ok(vkAllocateCommandBuffers(device, &ai, cmds), "vkAllocateCommandBuffers");
    for (uint32_t i = 0; good && i < kInFlight; ++i)
    {
        VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        fi.flags = VK_FENCE_CREATE_SIGNALED_BIT;
        good = ok(vkCreateFence(device, &fi, nullptr, &fences[i]), "vkCreateFence");
    }
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    auto submit = [&](uint32_t slot)
    {
        VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        si.commandBufferCount = 1;
        si.pCommandBuffers = &cmds[slot];
        return ok(vkQueueSubmit(queue, 1, &si, fences[slot]), "vkQueueSubmit");
    };
    good = good && ok(vkWaitForFences(device, 1, &fences[0], VK_TRUE, UINT64_MAX), "vkWaitForFences") &&
           ok(vkResetFences(device, 1, &fences[0]), "vkResetFences") &&
           ok(vkBeginCommandBuffer(cmds[0], &bi), "vkBeginCommandBuffer");
    if (!good)
        return 1;
    if (!render::record_uploads(upload, cmds[0]))
        return fail("the uploads could not be recorded");
    if (!ok(vkEndCommandBuffer(cmds[0]), "vkEndCommandBuffer") || !submit(0))
        return 1;

    // The engine's per-frame state, made once: nothing below allocates once the queue has grown.
    render::FrameData view;
    view.view_projection = math::look_at_projection(glm::vec3(0, -4, 2), glm::vec3(0), 50.0f, 1.0f);
    std::array<glm::vec3, 9> light{};
    std::array<render::PrtInstance, kPrtObjects> objects;
    render::DrawQueue queue_of_draws;
    render::AccessList transfer, draws;
    uint64_t steady_allocations = 0;
    int failed_calls = 0;
    for (uint32_t frame = 0; frame < kFrames; ++frame)
    {
        const uint32_t slot = frame % kInFlight;
        const VkCommandBuffer cmd = cmds[slot];
        if (!ok(vkWaitForFences(device, 1, &fences[slot], VK_TRUE, UINT64_MAX), "vkWaitForFences") ||
            !ok(vkResetFences(device, 1, &fences[slot]), "vkResetFences"))
            return 1;
        counting = count_allocations && frame >= kWarmFrames;
        allocations = 0;
        float y[9];
        math::sh_eval(3, glm::normalize(glm::vec3(0.3f * float(frame), -1.0f, 1.0f)), y);
        for (int i = 0; i < 9; ++i)
            light[size_t(i)] = glm::vec3(y[i]);
        failed_calls += !frame_set.write(slot, view);
        for (uint32_t i = 0; i < kProbeObjects; ++i)
            failed_calls += !probes.write_lighting(i, light, slot);
        for (uint32_t i = 0; i < kPrtObjects; ++i)
            objects[i] = {glm::translate(glm::mat4(1.0f), glm::vec3(float(i) - 1.5f, 0.0f, 1.0f)), light,
                          10.0f * float(frame)};
        if (!ok(vkBeginCommandBuffer(cmd, &bi), "vkBeginCommandBuffer"))
            return 1;
        transfer.clear();
        draws.clear();
        failed_calls += !prt.record_transfer(cmd, objects, slot, transfer);
        failed_calls += !prt.draw_accesses(slot, draws);
        render::record_barrier(cmd, transfer.accesses(), draws.accesses());
        queue_of_draws.clear();
        for (const render::LightmapDraw& d : level_draws)
            failed_calls += !level.enqueue(queue_of_draws, frame_set.set(slot), d, glm::mat4(1.0f));
        for (uint32_t i = 0; i < kPrtObjects; ++i)
            failed_calls += !prt.enqueue(queue_of_draws, frame_set.set(slot), i, objects[i].model, 0, slot);
        for (uint32_t i = 0; i < kProbeObjects; ++i)
            failed_calls += !probes.enqueue(
                queue_of_draws, frame_set.set(slot), i,
                glm::translate(glm::mat4(1.0f), glm::vec3(float(i % 4) - 1.5f, float(i / 4) - 1.5f, 0.6f)),
                slot);
        queue_of_draws.sort();
        target.begin(cmd);
        const render::DrawStats stats = queue_of_draws.record(cmd);
        target.end(cmd);
        const bool ended = ok(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
        counting = false;
        if (!ended || !submit(slot))
            return 1;
        if (stats.draws < level_draws.size() + kPrtObjects + kProbeObjects)
            return fail("a frame drew fewer draws than it enqueued");
        if (count_allocations && frame >= kWarmFrames)
        {
            if (allocations)
                std::fprintf(stderr, "volk test: steady frame %u allocated %llu time(s)\n", frame,
                             (unsigned long long)allocations);
            steady_allocations += allocations;
        }
    }
    vkDeviceWaitIdle(device);
    // Something was drawn: the level and objects cover the view's centre.
    const io::ImageRgba aux = target.read_aux();
    const size_t centre = (size_t(32) * 64 + 32) * 4;
    vkDestroyCommandPool(device, pool, nullptr);
    for (VkFence f : fences)
        vkDestroyFence(device, f, nullptr);
    if (aux.pixels[centre + 3] != 1.0f)
        return fail("nothing was drawn at the centre of the view");
    if (failed_calls || hemi_errors)
        return fail("a frame call was refused (see hemi's messages)");
    if (steady_allocations)
        return fail("steady-state frames allocated");
    return 0;
}
} // namespace

void* operator new(size_t size)
{
    return counted(size);
}
void* operator new[](size_t size)
{
    return counted(size);
}
void* operator new(size_t size, const std::nothrow_t&) noexcept
{
    return counted(size);
}
void* operator new[](size_t size, const std::nothrow_t&) noexcept
{
    return counted(size);
}
void* operator new(size_t size, std::align_val_t align)
{
    return counted(size, size_t(align));
}
void* operator new[](size_t size, std::align_val_t align)
{
    return counted(size, size_t(align));
}
void operator delete(void* p) noexcept
{
    std::free(p);
}
void operator delete[](void* p) noexcept
{
    std::free(p);
}
void operator delete(void* p, size_t) noexcept
{
    std::free(p);
}
void operator delete[](void* p, size_t) noexcept
{
    std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept
{
    std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept
{
    std::free(p);
}
void operator delete(void* p, size_t, std::align_val_t) noexcept
{
    std::free(p);
}
void operator delete[](void* p, size_t, std::align_val_t) noexcept
{
    std::free(p);
}

int main(int argc, char** argv)
{
    const bool count_allocations = argc > 1 && std::strcmp(argv[1], "--count-allocations") == 0;
    if (!ok(volkInitialize(), "volkInitialize"))
        return 1;
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.apiVersion = VK_API_VERSION_1_1;
    const char* layer = "VK_LAYER_KHRONOS_validation";
    const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pApplicationInfo = &app;
    ici.enabledLayerCount = count_allocations ? 0 : 1;
    ici.ppEnabledLayerNames = &layer;
    ici.enabledExtensionCount = count_allocations ? 0 : 1;
    ici.ppEnabledExtensionNames = &extension;
    VkInstance instance;
    if (!ok(vkCreateInstance(&ici, nullptr, &instance), "vkCreateInstance"))
        return 1;
    volkLoadInstance(instance);
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
    if (!count_allocations)
    {
        VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        mci.messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                          VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                          VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
        mci.pfnUserCallback = on_message;
        if (!ok(vkCreateDebugUtilsMessengerEXT(instance, &mci, nullptr, &messenger),
                "vkCreateDebugUtilsMessengerEXT"))
            return 1;
    }

    uint32_t count = 0;
    vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::vector<VkPhysicalDevice> physicals(count);
    vkEnumeratePhysicalDevices(instance, &count, physicals.data());
    if (physicals.empty())
        return fail("no Vulkan device");
    const VkPhysicalDevice physical = physicals[0];
    uint32_t families = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, nullptr);
    std::vector<VkQueueFamilyProperties> props(families);
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, props.data());
    uint32_t family = 0;
    while (family < families && (props[family].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) !=
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
    if (!ok(vkCreateDevice(physical, &dci, nullptr, &device), "vkCreateDevice"))
        return 1;
    volkLoadDevice(device);
    VkQueue queue;
    vkGetDeviceQueue(device, family, 0, &queue);

    const int rc = run_hemi(instance, physical, device, queue, family, count_allocations);
    vkDeviceWaitIdle(device);
    vkDestroyDevice(device, nullptr);
    if (messenger)
        vkDestroyDebugUtilsMessengerEXT(instance, messenger, nullptr);
    vkDestroyInstance(instance, nullptr);
    if (rc)
        return rc;
    if (messages)
    {
        std::fprintf(stderr, "volk test: %d validation message(s)\n", messages);
        return 1;
    }
    if (count_allocations)
        std::printf("volk test: steady frames allocated nothing\n");
    else
        std::printf(
            "volk test: hemi ran on volk's entry points and drew its frames, 0 validation messages\n");
    return 0;
}
