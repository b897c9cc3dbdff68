// No library call on an engine's path submits to a queue or waits on the device: loading (models, textures,
// materials, probes, frame data: uploads recorded into the engine's command buffer through an UploadBatch)
// and every frame's recording (per-frame data written through mapped memory, the PRT transfer pass, draws
// through a sorted DrawQueue). hemi runs on the engine's own device, and gets its Vulkan entry points from a
// vkGetInstanceProcAddr that counts vkQueueSubmit, vkWaitForFences and vkDeviceWaitIdle
// (tests/vulkan_calls.h); the engine submits with its own loader. A library that kept a one-shot submit
// anywhere on this path (a staging copy submitted at once, a readback, a wait for idle before freeing)
// counts one here. The frame is then checked to have drawn something, so the path is not vacuous. The CPU
// assets are freed once the models are made: what hemi draws lives on the GPU.
#include "../gpu_fixture.h"
#include "../host_vulkan.h"
#include "../vulkan_calls.h"
#include "sphere_asset.h"
#include "table_level.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/camera.h>
#include <hemi/math/sh.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/scene/draw_queue.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/probe_object.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/view/offscreen.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <memory>
#include <vector>

namespace
{

class EnginePath : public hemi::test::GpuTest
{
};

hemi::io::PrtAsset sphere_asset()
{
    return hemi::test::unshadowed_sphere_asset(16, 8, "h4", 4);
}

} // namespace

TEST_F(EnginePath, NoLibraryCallSubmitsOrWaits)
{
    using namespace hemi;
    test::HostVulkan host(true);
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    test::VulkanCalls& calls = test::vulkan_calls();
    // The CPU assets are freed as soon as the models are made (before the upload is even recorded): the
    // models keep only what they draw (under AddressSanitizer, in CI, a reference kept would be a
    // use-after-free).
    auto prt_asset = std::make_unique<io::PrtAsset>(sphere_asset());
    auto level =
        std::make_unique<io::LightmapAsset>(test::table_level(io::Material{}, io::Material{}, {}, {"h4"}));
    auto probe_mesh = std::make_unique<io::Mesh>(io::make_uv_sphere(0.3f, 12, 6));
    auto probe_materials = std::make_unique<std::vector<io::Material>>(1);
    constexpr uint32_t kW = 64, kH = 64, kInFlight = 2;

    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = host.family;
    VkCommandPool pool = VK_NULL_HANDLE;
    ASSERT_EQ(vkCreateCommandPool(host.vk_device, &pi, nullptr, &pool), VK_SUCCESS);
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    ASSERT_EQ(vkAllocateCommandBuffers(host.vk_device, &ai, &cmd), VK_SUCCESS);
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence = VK_NULL_HANDLE;
    ASSERT_EQ(vkCreateFence(host.vk_device, &fi, nullptr, &fence), VK_SUCCESS);
    // The engine's own submission, with its own loader's entry points (not counted).
    auto submit = [&]
    {
        VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        si.commandBufferCount = 1;
        si.pCommandBuffers = &cmd;
        ASSERT_EQ(vkQueueSubmit(host.queue, 1, &si, fence), VK_SUCCESS);
        ASSERT_EQ(vkWaitForFences(host.vk_device, 1, &fence, VK_TRUE, UINT64_MAX), VK_SUCCESS);
        ASSERT_EQ(vkResetFences(host.vk_device, 1, &fence), VK_SUCCESS);
    };
    auto begin = [&]
    {
        VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        ASSERT_EQ(vkBeginCommandBuffer(cmd, &bi), VK_SUCCESS);
    };

    {
        calls.reset();
        test::created_objects().clear();
        gpu::Device dev(host.external(test::counting_proc_addr));
        render::OffscreenTarget target(dev, kW, kH);
        render::MaterialSystem system(dev, target.desc());
        // Loading: everything uploads through the batch the engine records.
        gpu::UploadBatch upload(dev);
        render::PrtModelDesc desc;
        desc.technique = "h4";
        desc.frames_in_flight = kInFlight;
        render::PrtModel prt(system, *prt_asset, desc, upload);
        render::LightmapModel lightmap(system, *level, {"h4"}, upload);
        render::ProbeObject probes(system, *probe_mesh, {}, *probe_materials, {}, 4, upload, kInFlight);
        render::FrameSet frame_set(system, kInFlight);
        prt_asset.reset();
        level.reset();
        probe_mesh.reset();
        probe_materials.reset();
        begin();
        upload.record(cmd);
        ASSERT_EQ(vkEndCommandBuffer(cmd), VK_SUCCESS);
        EXPECT_EQ(calls.queue_work(), 0u) << "loading submitted or waited";
        submit();

        // Two frames, each recorded into the engine's command buffer.
        const glm::mat4 view = math::look_at_projection(glm::vec3(0, -4, 2), glm::vec3(0), 50.0f, 1.0f);
        std::vector<glm::vec3> light(9, glm::vec3(0.0f));
        render::DrawQueue queue;
        for (uint32_t frame = 0; frame < 2 * kInFlight; ++frame)
        {
            const uint32_t slot = frame % kInFlight;
            calls.reset();
            render::FrameData data;
            data.view_projection = view;
            frame_set.write(slot, data);
            float y[9];
            math::sh_eval(3, glm::normalize(glm::vec3(0.3f * float(frame), -1.0f, 1.0f)), y);
            for (int i = 0; i < 9; ++i)
                light[i] = glm::vec3(y[i]);
            for (uint32_t i = 0; i < probes.instances(); ++i)
                probes.write_lighting(i, light, slot);
            begin();
            const render::PrtInstance instance{glm::mat4(1.0f), light, 0.0f};
            prt.record_transfer(cmd, {&instance, 1}, slot);
            queue.clear();
            for (const render::LightmapDraw& d : lightmap.draw_list("h4"))
                lightmap.enqueue(queue, frame_set.set(slot), d, glm::mat4(1.0f));
            prt.enqueue(queue, frame_set.set(slot), 0, glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, 1)), 0,
                        slot);
            for (uint32_t i = 0; i < probes.instances(); ++i)
                probes.enqueue(queue, frame_set.set(slot), i,
                               glm::translate(glm::mat4(1.0f), glm::vec3(float(i) - 1.5f, -1.0f, 0.5f)),
                               slot);
            queue.sort();
            target.begin(cmd);
            const render::DrawStats stats = queue.record(cmd);
            target.end(cmd);
            ASSERT_EQ(vkEndCommandBuffer(cmd), VK_SUCCESS);
            EXPECT_EQ(calls.queue_work(), 0u) << "frame " << frame << " submitted or waited";
            EXPECT_GT(stats.draws, 5u);
            EXPECT_EQ(calls.draws, stats.draws);
            submit();
        }
        // Something was drawn (read back by the test, which may submit). The readback is a tool's one-shot
        // submit: the counter must see it, or it would see nothing at all.
        const io::ImageRgba aux = target.read_aux();
        EXPECT_GT(calls.queue_work(), 0u) << "the counting entry points missed hemi's own readback";
        size_t covered = 0;
        for (size_t p = 0; p < size_t(kW) * kH; ++p)
            covered += aux.pixels[p * 4 + 3] == 1.0f ? 1 : 0;
        EXPECT_GT(covered, size_t(kW) * kH / 10);
        // Every Vulkan object hemi made on the engine's device has a debug-utils name (issue 42), so a
        // capture or a validation message shows whose it is.
        const std::vector<std::string> unnamed = test::created_objects().unnamed();
        std::string list;
        for (size_t i = 0; i < unnamed.size() && i < 30; ++i)
            list += "\n  " + unnamed[i];
        EXPECT_TRUE(unnamed.empty()) << unnamed.size() << " objects without a name of "
                                     << test::created_objects().created.size() << ":" << list;
        ASSERT_EQ(vkDeviceWaitIdle(host.vk_device), VK_SUCCESS);
        calls.reset();
    }
    EXPECT_EQ(calls.queue_work(), 0u) << "destroying hemi's objects submitted or waited";
    vkDestroyFence(host.vk_device, fence, nullptr);
    vkDestroyCommandPool(host.vk_device, pool, nullptr);
}

// The README's sorted frame (hemi-bench's scale/frame at the same scale): 1,000 probe-lit objects of 10
// primitives alternating two material types (single- and double-sided), 10,000 draws, their lighting
// written every frame through mapped memory. Counted by the adopted device's entry points
// (tests/vulkan_calls.h), as a capture would show them: the sorted frame records 2 pipeline binds (the same
// packets in the order they were made, 10,000), and neither the lighting writes nor the frame's command
// buffer record a barrier or a buffer update. Fails when DrawQueue::sort() leaves the order as made, or when
// the per-frame data goes through vkCmdUpdateBuffer or needs a barrier.
TEST_F(EnginePath, ASortedFrameOfTenThousandDrawsBindsEachMaterialTypeOnce)
{
    using namespace hemi;
    gpu::Device& base = test::device();
    gpu::ExternalDevice adopt{base.instance(), base.physical_device(), base.device(),
                              base.queue(),    base.queue_family(),    {}};
    adopt.get_instance_proc_addr = test::counting_proc_addr;
    gpu::Device dev(adopt);
    test::VulkanCalls& calls = test::vulkan_calls();
    constexpr uint32_t kObjects = 1000, kPrimitives = 10, kInFlight = 2;
    render::OffscreenTarget target(dev, 16, 16);
    render::MaterialSystem system(dev, target.desc());
    gpu::UploadBatch upload(dev);
    const io::Mesh mesh = io::make_uv_sphere(1.0f, 10, 5);
    std::vector<io::Material> materials(2);
    materials[1].double_sided = true;
    std::vector<io::Primitive> parts;
    const uint32_t triangles = uint32_t(mesh.indices.size() / 3);
    for (uint32_t p = 0; p < kPrimitives; ++p)
    {
        const uint32_t first = triangles * p / kPrimitives, last = triangles * (p + 1) / kPrimitives;
        parts.push_back({first * 3, (last - first) * 3, p % 2});
    }
    render::ProbeObject spheres(system, mesh, {}, materials, parts, kObjects, upload, kInFlight);
    render::FrameSet frame_set(system, kInFlight, kObjects);
    upload.submit_and_wait();

    std::vector<glm::vec3> sh(9, glm::vec3(0.0f));
    render::DrawQueue queue;
    for (uint32_t frame = 0; frame < 2; ++frame)
    {
        const uint32_t slot = frame % kInFlight;
        calls.reset();
        render::FrameData f;
        f.view_projection = glm::scale(glm::mat4(1.0f), glm::vec3(0.02f, 0.02f, 0.5f));
        frame_set.write(slot, f);
        for (uint32_t i = 0; i < kObjects; ++i)
        {
            sh[0] = glm::vec3(1.0f + 0.5f * std::sin(0.1f * float(frame + i)));
            spheres.write_lighting(i, sh, slot);
        }
        EXPECT_EQ(calls.pipeline_barriers, 0u) << "the lighting writes";
        EXPECT_EQ(calls.buffer_updates, 0u) << "the lighting writes";
        queue.clear();
        for (uint32_t i = 0; i < kObjects; ++i)
            spheres.enqueue(queue, frame_set.set(slot), i,
                            glm::translate(glm::mat4(1.0f),
                                           glm::vec3(float(i % 40) - 20.0f, float(i / 40) - 12.0f, 0.0f)),
                            slot, 0, float(i) / float(kObjects));
        queue.sort();
        render::DrawStats stats;
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          target.begin(cmd);
                          calls.reset();
                          stats = queue.record(cmd);
                          EXPECT_EQ(calls.pipeline_binds, 2u) << "frame " << frame;
                          EXPECT_EQ(calls.draws, uint64_t(kObjects) * kPrimitives);
                          EXPECT_EQ(calls.pipeline_barriers, 0u);
                          EXPECT_EQ(calls.buffer_updates, 0u);
                          target.end(cmd);
                      });
        EXPECT_EQ(stats.pipeline_binds, 2u);
    }
    // The same draws in the order they were made (each object's primitives in turn): a bind per draw.
    render::DrawQueue made;
    for (uint32_t i = 0; i < kObjects; ++i)
        spheres.enqueue(made, frame_set.set(0), i, glm::mat4(1.0f), 0);
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      target.begin(cmd);
                      calls.reset();
                      render::record_packets(cmd, made.packets());
                      EXPECT_EQ(calls.pipeline_binds, uint64_t(kObjects) * kPrimitives);
                      target.end(cmd);
                  });
}
