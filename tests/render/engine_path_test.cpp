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
#include "depth_pass.h"
#include "engine_pass.h"
#include "packed_mesh.h"
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

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <vector>

namespace
{

class EnginePath : public hemi::test::GpuTest
{
};

// An engine's own render target (tests/render/engine_pass.h): colour and aux RGBA32F, D32 depth, and a render
// pass whose external dependency orders its attachments only. hemi's OffscreenTarget depends on all earlier
// commands' writes, which would order the transfers before the draws by itself: a barrier the engine forgot
// would go unseen by synchronisation validation there.
std::unique_ptr<hemi::test::EnginePass> engine_target(const hemi::gpu::Device& dev, uint32_t w, uint32_t h)
{
    return std::make_unique<hemi::test::EnginePass>(
        w, h, std::vector<VkFormat>{VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT}, dev, true);
}

hemi::render::RenderTargetDesc target_desc(const hemi::test::EnginePass& pass)
{
    hemi::render::RenderTargetDesc d;
    d.render_pass = pass.render_pass;
    d.color_attachments = 2;
    d.aux_output = true;
    return d;
}

constexpr float kBlack[4] = {0.0f, 0.0f, 0.0f, 0.0f};

// Frame `frame`'s lighting: one directional light as SH9, turning a little each frame.
void frame_light(uint32_t frame, std::vector<glm::vec3>& light)
{
    float y[9];
    hemi::math::sh_eval(3, glm::normalize(glm::vec3(0.3f * float(frame), -1.0f, 1.0f)), y);
    for (int i = 0; i < 9; ++i)
        light[i] = glm::vec3(y[i]);
}

hemi::io::PrtAsset sphere_asset()
{
    return hemi::test::unshadowed_sphere_asset(16, 8, "h4", 4);
}

using namespace hemi;

// The three models of the engine tests drawn from the engine's own buffers: the tests' table level, a PRT
// sphere and a probe-lit sphere, their meshes packed as an engine packs them (test::PackedMesh: fp16
// positions in stream 0, snorm normals and tangents and float UVs in stream 1, 16-bit indices) into one pair
// of vertex buffers and one index buffer, one mesh after another; the assets hold the packed values widened
// back, so that hemi's own path (its copy of each mesh) draws the same values. The buffers are made on the
// tests' shared device, before any counting device adopts it.
struct EngineScene
{
    io::LightmapAsset level = test::table_level(io::Material{}, io::Material{}, {}, {"h4"});
    io::PrtAsset prt = test::unshadowed_sphere_asset(16, 8, "h4", 4);
    io::Mesh probe_mesh = io::make_uv_sphere(0.3f, 12, 6);
    gpu::Buffer stream0, stream1, index_buffer;
    render::EngineGeometry level_geometry, prt_geometry, probe_geometry;

    EngineScene()
    {
        const test::PackedMesh packed[3] = {test::pack_mesh(level.mesh), test::pack_mesh(prt.mesh),
                                            test::pack_mesh(probe_mesh)};
        level.mesh = packed[0].widened;
        prt.mesh = packed[1].widened;
        probe_mesh = packed[2].widened;
        std::vector<uint16_t> positions, indices;
        std::vector<test::PackedAttributes> attributes;
        uint32_t base_vertex[3], base_index[3];
        for (int i = 0; i < 3; ++i)
        {
            base_vertex[i] = uint32_t(attributes.size());
            base_index[i] = uint32_t(indices.size());
            positions.insert(positions.end(), packed[i].positions.begin(), packed[i].positions.end());
            attributes.insert(attributes.end(), packed[i].attributes.begin(), packed[i].attributes.end());
            indices.insert(indices.end(), packed[i].indices.begin(), packed[i].indices.end());
        }
        gpu::Device& base = test::device();
        stream0 = gpu::create_buffer(base, {positions.size() * 2, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
        stream1 = gpu::create_buffer(
            base, {attributes.size() * sizeof(test::PackedAttributes), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
        index_buffer = gpu::create_buffer(base, {indices.size() * 2, VK_BUFFER_USAGE_INDEX_BUFFER_BIT});
        gpu::write_buffer(base, stream0, positions.data(), stream0.size());
        gpu::write_buffer(base, stream1, attributes.data(), stream1.size());
        gpu::write_buffer(base, index_buffer, indices.data(), index_buffer.size());
        auto geometry_of = [&](int mesh, const std::vector<io::Primitive>& primitives, size_t index_count)
        {
            render::EngineGeometry g;
            g.layout = test::PackedMesh::layout();
            g.buffers.streams = 2;
            g.buffers.vertex_buffers[0] = stream0.handle();
            g.buffers.vertex_buffers[1] = stream1.handle();
            g.buffers.index_buffer = index_buffer.handle();
            g.buffers.index_type = VK_INDEX_TYPE_UINT16;
            if (primitives.empty())
                g.primitives.push_back({base_index[mesh], uint32_t(index_count), int32_t(base_vertex[mesh])});
            for (const io::Primitive& p : primitives)
                g.primitives.push_back(
                    {base_index[mesh] + p.first_index, p.index_count, int32_t(base_vertex[mesh])});
            return g;
        };
        level_geometry = geometry_of(0, level.primitives, level.mesh.indices.size());
        prt_geometry = geometry_of(1, prt.primitives, prt.mesh.indices.size());
        probe_geometry = geometry_of(2, {}, probe_mesh.indices.size());
    }
};

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
            frame_light(frame, light);
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

// Issue 42, "synchronisation declared, not recorded": an engine's steady frame of 1,000 probe-lit objects and
// 16 PRT objects (8 models of 2 instances) relit every frame, 2 frames in flight, each with its own command
// buffer, fence and target. hemi writes the per-frame lighting through mapped memory and records only
// dispatches and draws: 0 barriers and 0 vkCmdUpdateBuffer of its own per frame (counted through the entry
// points hemi was given). The engine places the barriers itself from what hemi declares (the transfers'
// AccessLists and PrtModel::draw_accesses), as buffer barriers over exactly the declared ranges, with its own
// loader's vkCmdPipelineBarrier; the engine's instance runs synchronisation validation and any message fails
// the test. One descriptor pool (the MaterialSystem's) serves every material, probe buffer, frame set and all
// 8 transfer passes.
// The engine draws into its own target (EngineTarget: subpass dependencies on the attachments only), so
// nothing but its barriers orders the transfers before the draws: in a last frame its graph leaves out model
// 0's declared coefficient write, and synchronisation validation reports the read-after-write hazard of that
// model's vertex shaders. A final frame records the transfers with hemi's own barriers instead
// (render::record_barrier, 2 per model) and none of the engine's: silent too.
// Fails when a transfer pass updates its lighting with vkCmdUpdateBuffer or records its own barrier (the
// frame without the declared write then passes validation), or makes a descriptor pool of its own.
TEST_F(EnginePath, ASteadyFrameRecordsNoBarrierAndTheEnginesBarriersFromDeclaredAccessesAreClean)
{
    using namespace hemi;
    test::HostVulkan host(true);
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    test::VulkanCalls& calls = test::vulkan_calls();
    constexpr uint32_t kW = 48, kH = 48, kInFlight = 2, kProbeObjects = 1000, kModels = 8, kPerModel = 2,
                       kFrames = 6;

    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = host.family;
    VkCommandPool pool = VK_NULL_HANDLE;
    ASSERT_EQ(vkCreateCommandPool(host.vk_device, &pi, nullptr, &pool), VK_SUCCESS);
    VkCommandBuffer cmds[kInFlight];
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = kInFlight;
    ASSERT_EQ(vkAllocateCommandBuffers(host.vk_device, &ai, cmds), VK_SUCCESS);
    VkFence fences[kInFlight];
    for (VkFence& f : fences)
    {
        VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        fi.flags = VK_FENCE_CREATE_SIGNALED_BIT;
        ASSERT_EQ(vkCreateFence(host.vk_device, &fi, nullptr, &f), VK_SUCCESS);
    }
    // The engine's render graph, reduced to what this frame needs: a buffer barrier for each declared access
    // that follows a declared write to the same bytes (or a declared read, before a write), over their common
    // range, recorded with the engine's own entry point.
    auto engine_barriers = [&](VkCommandBuffer cmd, std::span<const render::BufferAccess> before,
                               std::span<const render::BufferAccess> after)
    {
        std::vector<VkBufferMemoryBarrier> barriers;
        VkPipelineStageFlags src = 0, dst = 0;
        for (const render::BufferAccess& a : before)
            for (const render::BufferAccess& b : after)
                if ((a.writes() || b.writes()) && a.overlaps(b))
                {
                    VkBufferMemoryBarrier m{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
                    m.srcAccessMask = a.writes() ? a.access : 0;
                    m.dstAccessMask = b.access;
                    m.srcQueueFamilyIndex = m.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
                    m.buffer = b.buffer;
                    m.offset = std::max(a.offset, b.offset);
                    m.size = std::min(a.offset + a.size, b.offset + b.size) - m.offset;
                    barriers.push_back(m);
                    src |= a.stages;
                    dst |= b.stages;
                }
        if (!barriers.empty())
            vkCmdPipelineBarrier(cmd, src, dst, 0, 0, nullptr, uint32_t(barriers.size()), barriers.data(), 0,
                                 nullptr);
        return barriers.size();
    };

    {
        test::created_objects().clear();
        gpu::Device dev(host.external(test::counting_proc_addr));
        std::vector<std::unique_ptr<test::EnginePass>> targets;
        for (uint32_t i = 0; i < kInFlight; ++i)
            targets.push_back(engine_target(dev, kW, kH));
        render::MaterialSystem system(dev, target_desc(*targets[0]));
        gpu::UploadBatch upload(dev);
        std::vector<std::unique_ptr<render::PrtModel>> models;
        {
            const io::PrtAsset asset = test::unshadowed_sphere_asset(16, 8, "gs", 9);
            render::PrtModelDesc desc;
            desc.technique = "gs";
            desc.instances = kPerModel;
            desc.frames_in_flight = kInFlight;
            for (uint32_t m = 0; m < kModels; ++m)
                models.push_back(std::make_unique<render::PrtModel>(system, asset, desc, upload));
        }
        const io::Mesh probe_mesh = io::make_uv_sphere(0.05f, 8, 4);
        render::ProbeObject probes(system, probe_mesh, {}, std::vector<io::Material>(1), {}, kProbeObjects,
                                   upload, kInFlight);
        render::FrameSet frame_set(system, kInFlight);
        size_t pools = 0;
        for (const auto& [handle, type] : test::created_objects().created)
            pools += type == VK_OBJECT_TYPE_DESCRIPTOR_POOL ? 1 : 0;
        EXPECT_EQ(pools, 1u)
            << "descriptor pools made for 8 PRT models, 1,000 probe-lit objects and a frame set";
        EXPECT_EQ(system.descriptors().pool_count(), 1u);
        {
            VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
            bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
            ASSERT_EQ(vkWaitForFences(host.vk_device, 1, &fences[0], VK_TRUE, UINT64_MAX), VK_SUCCESS);
            ASSERT_EQ(vkResetFences(host.vk_device, 1, &fences[0]), VK_SUCCESS);
            ASSERT_EQ(vkBeginCommandBuffer(cmds[0], &bi), VK_SUCCESS);
            upload.record(cmds[0]);
            ASSERT_EQ(vkEndCommandBuffer(cmds[0]), VK_SUCCESS);
            VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
            si.commandBufferCount = 1;
            si.pCommandBuffers = &cmds[0];
            ASSERT_EQ(vkQueueSubmit(host.queue, 1, &si, fences[0]), VK_SUCCESS);
        }

        const glm::mat4 view = math::look_at_projection(glm::vec3(0, -6, 2), glm::vec3(0), 50.0f, 1.0f);
        std::vector<glm::vec3> light(9, glm::vec3(0.0f));
        render::DrawQueue queue;
        render::AccessList transfer_accesses[kModels], draw_accesses[kModels]; // one per recording call
        // Frame kFrames: the engine's graph leaves out model 0's declared coefficient write, so no barrier
        // orders its transfer before its draws. Frame kFrames + 1: hemi's own barriers (record_transfer
        // without a list, render::record_barrier) and none of the engine's.
        for (uint32_t frame = 0; frame <= kFrames + 1; ++frame)
        {
            const bool drop = frame == kFrames, own = frame == kFrames + 1;
            const uint32_t slot = frame % kInFlight;
            VkCommandBuffer cmd = cmds[slot];
            // The engine's fence: the GPU is done with the frame that last used this slot.
            ASSERT_EQ(vkWaitForFences(host.vk_device, 1, &fences[slot], VK_TRUE, UINT64_MAX), VK_SUCCESS);
            ASSERT_EQ(vkResetFences(host.vk_device, 1, &fences[slot]), VK_SUCCESS);
            ASSERT_EQ(vkResetCommandBuffer(cmd, 0), VK_SUCCESS);
            calls.reset();
            render::FrameData data;
            data.view_projection = view;
            frame_set.write(slot, data);
            frame_light(frame, light);
            for (uint32_t i = 0; i < kProbeObjects; ++i)
                probes.write_lighting(i, light, slot);
            VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
            bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
            ASSERT_EQ(vkBeginCommandBuffer(cmd, &bi), VK_SUCCESS);
            size_t engine_barrier_count = 0;
            for (uint32_t m = 0; m < kModels; ++m)
            {
                const render::PrtInstance objects[kPerModel] = {
                    {glm::translate(glm::mat4(1.0f), glm::vec3(float(m) - 3.5f, 0.0f, 0.5f)), light, 0.0f},
                    {glm::translate(glm::mat4(1.0f), glm::vec3(float(m) - 3.5f, 0.0f, -0.5f)), light, 30.0f}};
                transfer_accesses[m].clear();
                draw_accesses[m].clear();
                if (own)
                {
                    models[m]->record_transfer(cmd, objects, slot);
                    continue;
                }
                models[m]->record_transfer(cmd, objects, slot, transfer_accesses[m]);
                models[m]->draw_accesses(slot, draw_accesses[m]);
                EXPECT_EQ(transfer_accesses[m].size(), 3u) << "matrices, lighting, coefficients";
            }
            // Every model's coefficients of this slot: written by the compute stage, then read by the vertex
            // shaders.
            for (uint32_t m = drop ? 1 : 0; m < kModels; ++m)
                engine_barrier_count +=
                    engine_barriers(cmd, transfer_accesses[m].accesses(), draw_accesses[m].accesses());
            EXPECT_EQ(engine_barrier_count, own ? 0 : drop ? kModels - 1 : kModels);
            queue.clear();
            for (uint32_t m = 0; m < kModels; ++m)
                for (uint32_t i = 0; i < kPerModel; ++i)
                    models[m]->enqueue(
                        queue, frame_set.set(slot), i,
                        glm::translate(glm::mat4(1.0f), glm::vec3(float(m) - 3.5f, 0.0f, i ? -0.5f : 0.5f)),
                        0, slot);
            for (uint32_t i = 0; i < kProbeObjects; ++i)
                probes.enqueue(queue, frame_set.set(slot), i,
                               glm::translate(glm::mat4(1.0f), glm::vec3(float(i % 40) * 0.2f - 4.0f, -1.0f,
                                                                         float(i / 40) * 0.2f - 2.5f)),
                               slot);
            queue.sort();
            targets[slot]->begin(cmd, kBlack);
            const render::DrawStats stats = queue.record(cmd);
            vkCmdEndRenderPass(cmd);
            ASSERT_EQ(vkEndCommandBuffer(cmd), VK_SUCCESS);
            EXPECT_EQ(calls.pipeline_barriers, own ? 2u * kModels : 0u)
                << "frame " << frame << ": barriers hemi recorded";
            EXPECT_EQ(calls.buffer_updates, 0u) << "frame " << frame << ": vkCmdUpdateBuffer hemi recorded";
            EXPECT_EQ(calls.dispatches, uint64_t(kModels) * kPerModel) << "frame " << frame;
            EXPECT_EQ(calls.queue_work(), 0u);
            EXPECT_EQ(stats.draws, uint64_t(kModels) * kPerModel + kProbeObjects);
            VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
            si.commandBufferCount = 1;
            si.pCommandBuffers = &cmd;
            ASSERT_EQ(vkQueueSubmit(host.queue, 1, &si, fences[slot]), VK_SUCCESS);
            if (drop)
            {
                size_t hazards = 0;
                for (const std::string& m : test::validation_log().take())
                    hazards += m.find("SYNC-HAZARD-READ-AFTER-WRITE") != std::string::npos ? 1 : 0;
                EXPECT_GT(hazards, 0u) << "a frame without model 0's declared write passed synchronisation "
                                          "validation";
            }
            if (frame + 1 == kFrames)
            {
                EXPECT_TRUE(test::validation_log().take().empty())
                    << "the engine's barriers from hemi's declared accesses";
                ASSERT_EQ(vkWaitForFences(host.vk_device, 1, &fences[slot], VK_TRUE, UINT64_MAX), VK_SUCCESS);
                const std::vector<float> aux = targets[slot]->read_color(1);
                size_t covered = 0;
                for (size_t p = 0; p < size_t(kW) * kH; ++p)
                    covered += aux[p * 4 + 3] == 1.0f ? 1 : 0;
                EXPECT_GT(covered, size_t(kW) * kH / 10);
            }
        }
        ASSERT_EQ(vkWaitForFences(host.vk_device, kInFlight, fences, VK_TRUE, UINT64_MAX), VK_SUCCESS);
        EXPECT_TRUE(test::validation_log().take().empty()) << "the frame with hemi's own barriers";
        ASSERT_EQ(vkDeviceWaitIdle(host.vk_device), VK_SUCCESS);
    }
    for (VkFence f : fences)
        vkDestroyFence(host.vk_device, f, nullptr);
    vkDestroyCommandPool(host.vk_device, pool, nullptr);
}

// Issue 42: the PRT transfer writes its coefficients into a range of the engine's own buffer, which the
// engine's vertex shader reads as one more vertex stream (PrtModel::coefficient_stream), and the barrier
// between the two is the engine's, made from what hemi declares (the transfer's AccessList, the stream's
// draw_accesses). Under synchronisation validation: with every declared access the frame is silent; with the
// transfer's declared coefficient write left out of the engine's graph (so no barrier), the layer reports the
// read-after-write hazard on the engine's buffer. The coefficients hemi writes at the range's offset equal
// those a model of hemi's own buffer writes, and the engine's stream draws the sphere.
TEST_F(EnginePath, CoefficientsInTheEnginesStreamNeedTheBarrierItsDeclaredAccessesMake)
{
    using namespace hemi;
    test::HostVulkan host(true);
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    gpu::Device dev(host.external());
    constexpr uint32_t kW = 48, kH = 48;
    const std::unique_ptr<test::EnginePass> target = engine_target(dev, kW, kH);
    render::MaterialSystem system(dev, target_desc(*target));
    const io::PrtAsset asset = test::unshadowed_sphere_asset(24, 12, "h4", 4);
    render::PrtModelDesc desc;
    desc.technique = "h4";
    desc.instances = 2;
    desc.frames_in_flight = 2;
    // The engine's buffer: its own data first, hemi's coefficients from an aligned offset past them.
    const VkDeviceSize align =
        std::lcm<VkDeviceSize>(16, std::max<VkDeviceSize>(1, dev.limits().minTexelBufferOffsetAlignment));
    const VkDeviceSize offset = 3 * align, bytes = render::PrtModel::coefficient_bytes(dev, asset, desc);
    const gpu::Buffer engine_buffer =
        gpu::create_buffer(dev, {offset + bytes, VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT |
                                                     VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
                                                     VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    const gpu::Buffer positions = gpu::create_buffer(
        dev, {asset.mesh.positions.size() * sizeof(glm::vec3), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    gpu::write_buffer(dev, positions, asset.mesh.positions.data(), positions.size());
    const gpu::Buffer indices =
        gpu::create_buffer(dev, {asset.mesh.indices.size() * 4, VK_BUFFER_USAGE_INDEX_BUFFER_BIT});
    gpu::write_buffer(dev, indices, asset.mesh.indices.data(), indices.size());
    gpu::UploadBatch upload(dev);
    render::PrtModelDesc own_desc = desc;
    render::PrtModel own(system, asset, own_desc, upload);
    desc.coefficient_output = {engine_buffer.handle(), offset, bytes};
    render::PrtModel model(system, asset, desc, upload);
    upload.submit_and_wait();
    EXPECT_EQ(model.coefficient_range(1).buffer, engine_buffer.handle());
    EXPECT_EQ(model.coefficient_range(1).offset, offset + bytes / 2);
    EXPECT_EQ(model.coefficient_stride(), 4u * 16u);

    gpu::GraphicsProgramDesc pd;
    pd.vertex_shader = test::test_spirv("engine_stream.vert");
    pd.fragment_shader = test::test_spirv("engine_stream.frag");
    pd.push_constant_size = 2 * sizeof(glm::mat4);
    pd.vertex_bindings = {{0, sizeof(glm::vec3), VK_VERTEX_INPUT_RATE_VERTEX},
                          {1, model.coefficient_stride(), VK_VERTEX_INPUT_RATE_VERTEX}};
    pd.vertex_attributes = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0}};
    for (uint32_t k = 0; k < 4; ++k)
        pd.vertex_attributes.push_back({1 + k, 1, VK_FORMAT_R32G32B32A32_SFLOAT, 16 * k});
    pd.render_pass = target->render_pass;
    pd.color_attachments = 2;
    pd.cull_mode = VK_CULL_MODE_NONE;
    const gpu::Program program = gpu::create_graphics_program(dev, pd);
    const glm::mat4 view_projection =
        math::look_at_projection(glm::vec3(0, -4, 0), glm::vec3(0), 40.0f, 1.0f);
    // The engine's push constants: the view, and the object's model matrix (a turn and a shift, so that the
    // order of the products shows in the rounding).
    const glm::mat4 pushed[2] = {view_projection,
                                 glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0.1f, 0.3f, -0.2f)),
                                             0.7f, glm::normalize(glm::vec3(0.3f, 0.9f, 0.2f)))};

    std::vector<glm::vec3> light(9, glm::vec3(0.0f));
    light[0] = glm::vec3(1.0f, 0.5f, 0.25f);
    light[2] = glm::vec3(0.5f);
    const render::PrtInstance objects[2] = {{glm::mat4(1.0f), light, 0.0f}, {glm::mat4(1.0f), light, 90.0f}};
    // The engine's draw of instance 1 of slot 1 from its streams, with `program`.
    auto engine_draw = [&](VkCommandBuffer cmd, const gpu::Program& pipeline)
    {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline.pipeline);
        vkCmdPushConstants(cmd, pipeline.layout, VK_SHADER_STAGE_ALL, 0, sizeof pushed, pushed);
        const gpu::BufferRange stream = model.coefficient_stream(1, 1);
        const VkBuffer buffers[2] = {positions.handle(), stream.buffer};
        const VkDeviceSize offsets[2] = {0, stream.offset};
        vkCmdBindVertexBuffers(cmd, 0, 2, buffers, offsets);
        vkCmdBindIndexBuffer(cmd, indices.handle(), 0, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(cmd, uint32_t(asset.mesh.indices.size()), 1, 0, 0, 0);
    };
    // One frame of the engine's, into slot 1 (instance 1 drawn from its stream), its graph's barrier made
    // from the declared accesses, all of them or all but the coefficient write.
    auto frame = [&](bool drop_the_write)
    {
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          render::AccessList transfer, draws;
                          model.record_transfer(cmd, objects, 1, transfer);
                          model.draw_accesses(1, draws, true);
                          VkPipelineStageFlags src = 0, dst = 0;
                          std::vector<VkBufferMemoryBarrier> barriers;
                          for (const render::BufferAccess& a : transfer.accesses())
                              for (const render::BufferAccess& b : draws.accesses())
                              {
                                  if (drop_the_write && a.writes())
                                      continue;
                                  if (!(a.writes() || b.writes()) || !a.overlaps(b))
                                      continue;
                                  VkBufferMemoryBarrier m{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
                                  m.srcAccessMask = a.access;
                                  m.dstAccessMask = b.access;
                                  m.srcQueueFamilyIndex = m.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
                                  m.buffer = b.buffer;
                                  m.offset = b.offset;
                                  m.size = b.size;
                                  barriers.push_back(m);
                                  src |= a.stages;
                                  dst |= b.stages;
                              }
                          EXPECT_EQ(barriers.size(), drop_the_write ? 0u : 1u);
                          if (!barriers.empty())
                              vkCmdPipelineBarrier(cmd, src, dst, 0, 0, nullptr, uint32_t(barriers.size()),
                                                   barriers.data(), 0, nullptr);
                          target->begin(cmd, kBlack);
                          engine_draw(cmd, program);
                          vkCmdEndRenderPass(cmd);
                      });
    };
    frame(false);
    EXPECT_TRUE(test::validation_log().take().empty()) << "the engine's barriers from hemi's accesses";
    const std::vector<float> color = target->read_color(0);
    frame(true);
    size_t hazards = 0;
    for (const std::string& m : test::validation_log().take())
        hazards += m.find("SYNC-HAZARD-READ-AFTER-WRITE") != std::string::npos ? 1 : 0;
    EXPECT_GT(hazards, 0u) << "without the declared write's barrier, synchronisation validation is silent";

    // The engine's stream drew the sphere, lit.
    size_t lit = 0;
    for (size_t p = 0; p < size_t(kW) * kH; ++p)
        lit += color[p * 4 + 3] == 1.0f && color[p * 4] > 0.01f ? 1 : 0;
    EXPECT_GT(lit, size_t(kW) * kH / 8);
    // The engine's view data and hemi's depth: hemi's depth prepass of the model, reading the view from the
    // engine's own camera buffer (a FrameSet over it), then the engine's pipeline testing EQUAL without depth
    // writes (its position from hemi_clip_position): every pixel the prepass covered is drawn.
    const VkDeviceSize ubo_align = std::max<VkDeviceSize>(64, dev.limits().minUniformBufferOffsetAlignment);
    const gpu::Buffer camera = gpu::create_buffer(
        dev, {ubo_align + sizeof(shared::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    render::FrameData view;
    view.view_projection = view_projection;
    shared::FrameUniforms uniforms{};
    ASSERT_TRUE(render::frame_uniforms(system, view, uniforms));
    gpu::write_buffer(dev, camera, &uniforms, sizeof uniforms, ubo_align);
    const gpu::BufferRange camera_range{camera.handle(), ubo_align, sizeof(shared::FrameUniforms)};
    const render::FrameSet engine_view(system, {&camera_range, 1});
    render::PassDesc depth_pass;
    depth_pass.kind = render::PassKind::Depth;
    depth_pass.target = target_desc(*target);
    const size_t prepass = model.add_pass(depth_pass);
    gpu::GraphicsProgramDesc equal_desc = pd;
    equal_desc.depth_compare = VK_COMPARE_OP_EQUAL;
    equal_desc.depth_write = false;
    const gpu::Program equal = gpu::create_graphics_program(dev, equal_desc);
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      target->begin(cmd, kBlack); // (the coefficients are the frames' above)
                      model.draw(cmd, engine_view.set(), 1, pushed[1], prepass, 1);
                      engine_draw(cmd, equal);
                      vkCmdEndRenderPass(cmd);
                  });
    const std::vector<float> after_prepass = target->read_color(0);
    size_t drawn = 0, missed = 0;
    for (size_t p = 0; p < size_t(kW) * kH; ++p)
    {
        const bool was = color[p * 4 + 3] == 1.0f, is = after_prepass[p * 4 + 3] == 1.0f;
        drawn += is ? 1 : 0;
        missed += was != is ? 1 : 0;
    }
    EXPECT_GT(drawn, size_t(kW) * kH / 8);
    EXPECT_EQ(missed, 0u) << "pixels where the engine's depth differs from hemi's prepass";

    // The same coefficients as a model writing into hemi's own buffer, at the engine's offset.
    gpu::one_shot(dev, [&](VkCommandBuffer cmd) { own.record_transfer(cmd, objects, 1); });
    const gpu::BufferRange mine = model.coefficient_range(1), hemis = own.coefficient_range(1);
    ASSERT_EQ(mine.size, hemis.size);
    std::vector<float> a(mine.size / 4), b(hemis.size / 4);
    gpu::read_buffer(dev, mine, a.data());
    gpu::read_buffer(dev, hemis, b.data());
    EXPECT_EQ(a, b);
    EXPECT_GT(std::abs(a[0]) + std::abs(a[1]) + std::abs(a[2]), 0.0f);
}

// Issue 42, "draw from the engine's geometry": a lightmapped level, a PRT object and 4 instanced probe-lit
// objects drawn by hemi's materials from the engine's own vertex and index buffers, in its own layout
// (packed_mesh.h: fp16 positions in stream 0, snorm16 normals and tangents and fp32 UVs in stream 1, 16-bit
// indices), all three meshes in one pair of streams and one index buffer (so each model's primitives have
// their own index ranges and vertex offsets; the PRT model's coefficients are still read at its own vertex
// indices). The frame equals hemi's own path (its fp32 copy of the same values, widened) within 0.5% at every
// covered pixel, with the same coverage; hemi makes no vertex or index buffer for the engine's models
// (counted through its entry points) where its own path makes one of each per model.
// Fails when a model uploads its mesh regardless, when the engine's vertex offset is not taken out of the PRT
// coefficient index (the sphere is lit by another vertex's coefficients), or when a draw binds hemi's
// buffers.
TEST_F(EnginePath, ModelsDrawFromTheEnginesOwnBuffersAsFromHemisCopy)
{
    using namespace hemi;
    constexpr uint32_t kW = 64, kH = 64, kProbes = 4;
    const EngineScene scene;
    const io::LightmapAsset& level = scene.level;
    const io::PrtAsset& prt = scene.prt;
    const io::Mesh& probe_mesh = scene.probe_mesh;
    const render::EngineGeometry &level_geometry = scene.level_geometry, &prt_geometry = scene.prt_geometry,
                                 &probe_geometry = scene.probe_geometry;
    gpu::Device& base = test::device();
    gpu::ExternalDevice adopt{base.instance(), base.physical_device(), base.device(),
                              base.queue(),    base.queue_family(),    {}};
    adopt.get_instance_proc_addr = test::counting_proc_addr;
    gpu::Device dev(adopt);
    const glm::mat4 view = math::look_at_projection(glm::vec3(0, -4, 2), glm::vec3(0), 50.0f, 1.0f);
    std::vector<glm::vec3> light(9, glm::vec3(0.0f));
    frame_light(3, light);
    // One frame of the three models, from the engine's buffers or from hemi's copy: colour and aux.
    auto frame = [&](bool engine, std::vector<float>& color, std::vector<float>& aux)
    {
        const std::unique_ptr<test::EnginePass> target = engine_target(dev, kW, kH);
        render::MaterialSystem system(dev, target_desc(*target));
        gpu::UploadBatch upload(dev);
        test::created_objects().clear();
        render::PrtModelDesc desc;
        desc.technique = "h4";
        desc.geometry = engine ? &prt_geometry : nullptr;
        render::PrtModel prt_model(system, prt, desc, upload);
        render::LightmapModel level_model(system, level, {"h4"}, upload, {},
                                          engine ? &level_geometry : nullptr);
        render::ProbeObject probes(system, probe_mesh, {}, std::vector<io::Material>(1), {}, kProbes, upload,
                                   1, engine ? &probe_geometry : nullptr);
        const size_t geometry_buffers = test::created_objects().buffers_with(
            VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
        if (engine)
        {
            EXPECT_EQ(geometry_buffers, 0u) << "vertex or index buffers hemi made for the engine's models";
            EXPECT_THROW(prt_model.mesh(), std::logic_error);
        }
        else
            EXPECT_EQ(geometry_buffers, 6u) << "hemi's own path: a vertex and an index buffer per model";
        render::FrameSet frame_set(system, 1, kProbes);
        upload.submit_and_wait();
        render::FrameData data;
        data.view_projection = view;
        frame_set.write(0, data);
        shared::DrawPush records[kProbes];
        for (uint32_t i = 0; i < kProbes; ++i)
        {
            probes.write_lighting(i, light, 0);
            records[i] = probes.instance_record(
                i, glm::translate(glm::mat4(1.0f), glm::vec3(float(i) - 1.5f, -1.0f, 0.5f)), 0);
        }
        frame_set.write_instances(0, records);
        render::DrawQueue queue;
        for (const render::LightmapDraw& d : level_model.draw_list("h4"))
            level_model.enqueue(queue, frame_set.set(), d, glm::mat4(1.0f));
        prt_model.enqueue(queue, frame_set.set(), 0,
                          glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0.0f, 1.0f)));
        probes.enqueue_instances(queue, frame_set.set(), {0, kProbes});
        queue.sort();
        const render::PrtInstance instance{glm::mat4(1.0f), light, 0.0f};
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          prt_model.record_transfer(cmd, {&instance, 1});
                          target->begin(cmd, kBlack);
                          queue.record(cmd);
                          vkCmdEndRenderPass(cmd);
                      });
        color = target->read_color(0);
        aux = target->read_color(1);
    };
    std::vector<float> engine_color, engine_aux, own_color, own_aux;
    frame(true, engine_color, engine_aux);
    frame(false, own_color, own_aux);
    size_t covered = 0, coverage_differs = 0, outside = 0;
    float worst = 0.0f;
    for (size_t p = 0; p < size_t(kW) * kH; ++p)
    {
        const bool a = engine_aux[p * 4 + 3] == 1.0f, b = own_aux[p * 4 + 3] == 1.0f;
        coverage_differs += a != b ? 1 : 0;
        if (!a || !b)
            continue;
        ++covered;
        for (int c = 0; c < 3; ++c)
        {
            const float e = engine_color[p * 4 + c], o = own_color[p * 4 + c], d = std::abs(e - o);
            worst = std::max(worst, d / (std::abs(o) + 1e-3f));
            outside += d > 0.005f * std::abs(o) + 1e-4f ? 1 : 0;
        }
    }
    EXPECT_GT(covered, size_t(kW) * kH / 4);
    EXPECT_EQ(coverage_differs, 0u);
    EXPECT_EQ(outside, 0u) << "worst relative difference " << worst;
    // Geometry that cannot draw the asset is refused when the model is made, naming what is wrong.
    const std::unique_ptr<test::EnginePass> target = engine_target(dev, 8, 8);
    render::MaterialSystem system(dev, target_desc(*target));
    gpu::UploadBatch upload(dev);
    auto refusal = [&](const render::EngineGeometry& g)
    {
        try
        {
            render::ProbeObject(system, probe_mesh, {}, std::vector<io::Material>(1), {}, 1, upload, 1, &g);
        }
        catch (const std::invalid_argument& e)
        {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    render::EngineGeometry one_stream = probe_geometry;
    one_stream.buffers.streams = 1;
    EXPECT_NE(refusal(one_stream).find("reads stream 1, but its geometry binds 1 stream"), std::string::npos)
        << refusal(one_stream);
    render::EngineGeometry two_ranges = probe_geometry;
    two_ranges.primitives.push_back(two_ranges.primitives[0]);
    EXPECT_NE(refusal(two_ranges).find("maps 2 primitives, the asset has 1"), std::string::npos)
        << refusal(two_ranges);
    render::EngineGeometry no_indices = probe_geometry;
    no_indices.buffers.index_buffer = VK_NULL_HANDLE;
    EXPECT_NE(refusal(no_indices).find("an index buffer"), std::string::npos) << refusal(no_indices);
}

// Issue 42's consumer: an engine that draws a lightmapped level, a PRT object and 4 instanced probe-lit
// objects from its own vertex and index buffers (EngineScene: two streams of fp16, snorm and float
// attributes, 16-bit indices), with its own view: no FrameSet, but descriptor sets of the system's frame
// layout that it allocates from its own pool and points at its own camera and instance buffers (the light's
// view for the shadow map, the camera's for the rest; their uniforms packed by render::frame_uniforms). Its
// frame: the PRT transfer with the barrier it makes from hemi's declared accesses; a shadow map from above
// (hemi's shadow pipelines, its own depth-only render pass); then its main pass with a depth prepass (hemi's
// depth pipelines) and the colour pass testing EQUAL against it. The same frame drawn hemi's own way (hemi's
// copy of every mesh, FrameSets, the colour pass testing LESS, the shadow map alike) is the reference: the
// colour agrees within 0.5% at every covered pixel, coverage is the same, and so is every texel of the
// shadow map. hemi makes no vertex or index buffer for the engine's models (counted through the entry points
// it was given), under the validation layer (any message fails the test). The device is the tests' own,
// created with the loader; an engine loading Vulkan with volk is tests/volk/volk_test.cpp.
// Broken once to see it fail: the engine's camera set pointed at the light's uniforms draws the main view
// from above (coverage and colour differ); without the prepass the EQUAL pass draws nothing.
TEST_F(EnginePath, AConsumerDrawsEveryPassFromItsOwnBuffersAndViewAsHemisOwnPathDoes)
{
    constexpr uint32_t kW = 64, kH = 64, kProbes = 4;
    const EngineScene scene;
    gpu::Device& base = test::device();
    // The engine's view data: a camera and a light uniform block each at an offset of their own buffer, and
    // its instance records (made before hemi's counting device adopts the device).
    const VkDeviceSize ubo_align = std::max<VkDeviceSize>(256, base.limits().minUniformBufferOffsetAlignment);
    const gpu::Buffer views = gpu::create_buffer(
        base, {2 * ubo_align + sizeof(shared::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    const gpu::Buffer records_buffer =
        gpu::create_buffer(base, {kProbes * sizeof(shared::DrawPush), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    const test::DepthPass shadow_map(kW);

    gpu::ExternalDevice adopt{base.instance(), base.physical_device(), base.device(),
                              base.queue(),    base.queue_family(),    {}};
    adopt.get_instance_proc_addr = test::counting_proc_addr;
    gpu::Device dev(adopt);
    const std::unique_ptr<test::EnginePass> target = engine_target(dev, kW, kH);
    const render::RenderTargetDesc main_target = target_desc(*target);
    render::MaterialSystem system(dev, main_target);
    render::PassDesc prepass, equal, shadow;
    prepass.kind = render::PassKind::Depth;
    prepass.target = main_target;
    equal.target = main_target;
    equal.target.depth_compare = VK_COMPARE_OP_EQUAL;
    equal.target.depth_write = false;
    shadow.kind = render::PassKind::Shadow;
    shadow.target.render_pass = shadow_map.render_pass;
    shadow.target.color_attachments = 0;

    render::FrameData camera, light_view;
    camera.eye = glm::vec3(0.8f, -3.2f, 2.4f);
    camera.view_projection = math::look_at_projection(camera.eye, glm::vec3(0.0f, 0.0f, 0.4f), 50.0f, 1.0f);
    light_view.view_projection =
        math::look_at_projection(glm::vec3(0.3f, -0.2f, 4.0f), glm::vec3(0.0f), 50.0f, 1.0f);
    std::vector<glm::vec3> light(9, glm::vec3(0.0f));
    frame_light(3, light);
    const glm::mat4 prt_place = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0.0f, 1.0f));

    struct Frame
    {
        std::vector<float> color, aux, shadow;
    };
    auto frame = [&](bool engine)
    {
        gpu::UploadBatch upload(dev);
        test::created_objects().clear();
        render::PrtModelDesc desc;
        desc.technique = "h4";
        desc.geometry = engine ? &scene.prt_geometry : nullptr;
        render::PrtModel prt(system, scene.prt, desc, upload);
        render::LightmapModel level(system, scene.level, {"h4"}, upload, {},
                                    engine ? &scene.level_geometry : nullptr);
        render::ProbeObject probes(system, scene.probe_mesh, {}, std::vector<io::Material>(1), {}, kProbes,
                                   upload, 1, engine ? &scene.probe_geometry : nullptr);
        const size_t hemi_geometry = test::created_objects().buffers_with(VK_BUFFER_USAGE_VERTEX_BUFFER_BIT |
                                                                          VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
        EXPECT_EQ(hemi_geometry, engine ? 0u : 6u) << (engine ? "engine" : "hemi's") << " path";
        // Each model's pass indices: 0 colour (LESS), then these, in the same order for all three.
        size_t prepass_index = 0, equal_index = 0, shadow_index = 0;
        for (size_t m = 0; m < 3; ++m)
        {
            auto add = [&](const render::PassDesc& p) {
                return m == 0 ? prt.add_pass(p) : m == 1 ? level.add_pass(p) : probes.add_pass(p);
            };
            prepass_index = add(prepass);
            equal_index = add(equal);
            shadow_index = add(shadow);
        }
        shared::DrawPush records[kProbes];
        for (uint32_t i = 0; i < kProbes; ++i)
        {
            EXPECT_TRUE(probes.write_lighting(i, light, 0));
            records[i] = probes.instance_record(
                i, glm::translate(glm::mat4(1.0f), glm::vec3(float(i) - 1.5f, -1.0f, 0.5f)), 0);
        }
        // The view: the engine's own sets over its own buffers, or hemi's FrameSets.
        VkDescriptorPool pool = VK_NULL_HANDLE;
        VkDescriptorSet camera_set = VK_NULL_HANDLE, light_set = VK_NULL_HANDLE;
        std::unique_ptr<render::FrameSet> camera_frames, light_frames;
        if (engine)
        {
            shared::FrameUniforms u{};
            EXPECT_TRUE(render::frame_uniforms(system, camera, u));
            gpu::write_buffer(base, views, &u, sizeof u, 0);
            EXPECT_TRUE(render::frame_uniforms(system, light_view, u));
            gpu::write_buffer(base, views, &u, sizeof u, ubo_align);
            gpu::write_buffer(base, records_buffer, records, sizeof records);
            const VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 2},
                                                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 2}};
            VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
            pi.maxSets = 2;
            pi.poolSizeCount = 2;
            pi.pPoolSizes = sizes;
            EXPECT_EQ(vkCreateDescriptorPool(base.device(), &pi, nullptr, &pool), VK_SUCCESS);
            const VkDescriptorSetLayout layouts[2] = {system.frame_layout(), system.frame_layout()};
            VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
            ai.descriptorPool = pool;
            ai.descriptorSetCount = 2;
            ai.pSetLayouts = layouts;
            VkDescriptorSet sets[2];
            EXPECT_EQ(vkAllocateDescriptorSets(base.device(), &ai, sets), VK_SUCCESS);
            camera_set = sets[0];
            light_set = sets[1];
            const VkDescriptorBufferInfo infos[3] = {
                {views.handle(), 0, sizeof(shared::FrameUniforms)},
                {views.handle(), ubo_align, sizeof(shared::FrameUniforms)},
                {records_buffer.handle(), 0, VK_WHOLE_SIZE}};
            VkWriteDescriptorSet writes[4]{};
            for (int w = 0; w < 4; ++w)
            {
                writes[w].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
                writes[w].dstSet = sets[w / 2];
                writes[w].descriptorCount = 1;
                const bool uniforms = w % 2 == 0;
                writes[w].dstBinding = uniforms ? HEMI_FRAME_BINDING_UNIFORMS : HEMI_FRAME_BINDING_INSTANCES;
                writes[w].descriptorType =
                    uniforms ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
                writes[w].pBufferInfo = uniforms ? &infos[w / 2] : &infos[2];
            }
            vkUpdateDescriptorSets(base.device(), 4, writes, 0, nullptr);
        }
        else
        {
            camera_frames = std::make_unique<render::FrameSet>(system, 1, kProbes);
            light_frames = std::make_unique<render::FrameSet>(system, 1, kProbes);
            EXPECT_TRUE(camera_frames->write(0, camera));
            EXPECT_TRUE(light_frames->write(0, light_view));
            EXPECT_TRUE(camera_frames->write_instances(0, records));
            EXPECT_TRUE(light_frames->write_instances(0, records));
            camera_set = camera_frames->set();
            light_set = light_frames->set();
        }
        upload.submit_and_wait();
        // Every model with the pipelines of `pass`, through one sorted queue.
        render::DrawQueue queue;
        auto draw_all = [&](VkCommandBuffer cmd, VkDescriptorSet view, size_t pass)
        {
            queue.clear();
            for (const render::LightmapDraw& d : level.draw_list("h4", pass))
                EXPECT_TRUE(level.enqueue(queue, view, d, glm::mat4(1.0f), pass));
            EXPECT_TRUE(prt.enqueue(queue, view, 0, prt_place, pass));
            EXPECT_TRUE(probes.enqueue_instances(queue, view, {0, kProbes}, 0, 0.0f, pass));
            queue.sort();
            const render::DrawStats stats = queue.record(cmd);
            EXPECT_EQ(stats.refused, 0u);
        };
        const render::PrtInstance instance{prt_place, light, 0.0f};
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          if (engine)
                          {
                              render::AccessList transfer, reads;
                              EXPECT_TRUE(prt.record_transfer(cmd, {&instance, 1}, 0, transfer));
                              EXPECT_TRUE(prt.draw_accesses(0, reads));
                              render::record_barrier(cmd, transfer.accesses(), reads.accesses());
                          }
                          else
                              EXPECT_TRUE(prt.record_transfer(cmd, {&instance, 1}, 0));
                          shadow_map.begin(cmd);
                          draw_all(cmd, light_set, shadow_index);
                          vkCmdEndRenderPass(cmd);
                          target->begin(cmd, kBlack);
                          if (engine)
                          {
                              draw_all(cmd, camera_set, prepass_index);
                              draw_all(cmd, camera_set, equal_index);
                          }
                          else
                              draw_all(cmd, camera_set, 0);
                          vkCmdEndRenderPass(cmd);
                      });
        Frame f{target->read_color(0), target->read_color(1), shadow_map.read()};
        if (pool)
            vkDestroyDescriptorPool(base.device(), pool, nullptr);
        return f;
    };
    const Frame engine = frame(true), own = frame(false);
    size_t covered = 0, coverage_differs = 0, outside = 0;
    float worst = 0.0f;
    for (size_t p = 0; p < size_t(kW) * kH; ++p)
    {
        const bool a = engine.aux[p * 4 + 3] == 1.0f, b = own.aux[p * 4 + 3] == 1.0f;
        coverage_differs += a != b ? 1 : 0;
        if (!a || !b)
            continue;
        ++covered;
        for (int c = 0; c < 3; ++c)
        {
            const float e = engine.color[p * 4 + c], o = own.color[p * 4 + c], d = std::abs(e - o);
            worst = std::max(worst, d / (std::abs(o) + 1e-3f));
            outside += d > 0.005f * std::abs(o) + 1e-4f ? 1 : 0;
        }
    }
    EXPECT_GT(covered, size_t(kW) * kH / 4);
    EXPECT_EQ(coverage_differs, 0u);
    EXPECT_EQ(outside, 0u) << "worst relative difference " << worst;
    size_t shadowed = 0, shadow_differs = 0;
    for (size_t t = 0; t < engine.shadow.size(); ++t)
    {
        shadowed += own.shadow[t] < 1.0f ? 1 : 0;
        shadow_differs += std::abs(engine.shadow[t] - own.shadow[t]) > 1e-6f ? 1 : 0;
    }
    EXPECT_GT(shadowed, engine.shadow.size() / 4) << "the shadow map saw too little of the scene";
    EXPECT_EQ(shadow_differs, 0u);
}
