// Calls on the frame path never throw (issue 42): a bad argument is reported through the device's log
// callback, at LogLevel::Error and naming the call and the argument, and the call records nothing and returns
// false. One test for each kind of bad argument the issue names: an unknown technique, a pass index out of
// range, too many lights, a released object. Each runs the call with a good argument too, on the same
// objects, and sees it record: the refusal is not a call that never records. The commands are counted
// through the entry points hemi was given (tests/vulkan_calls.h); the calls are made inside the engine's
// render pass on its own device, under the validation layer.
//
// Broken once to see them fail: LightmapModel::draw falling back to the first loaded technique for a name it
// does not know returns true, records the level's draws and logs nothing (the unknown-technique test fails
// on all three).
#include "../gpu_fixture.h"
#include "../host_vulkan.h"
#include "../vulkan_calls.h"
#include "sphere_asset.h"
#include "table_level.h"

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/camera.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/scene/draw_queue.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/probe_object.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/view/offscreen.h>

#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace
{
using namespace hemi;

// An engine's device (hemi's entry points counted) whose log callback keeps hemi's errors; models of the
// three kinds loaded on it, a frame set, and a command buffer recording inside the engine's render pass.
struct Frame
{
    test::HostVulkan host{false};
    std::mutex mutex;
    std::vector<std::string> errors;
    std::unique_ptr<gpu::Device> dev;
    std::unique_ptr<render::OffscreenTarget> target;
    std::unique_ptr<render::MaterialSystem> system;
    std::unique_ptr<render::PrtModel> prt;
    std::unique_ptr<render::LightmapModel> level;
    std::unique_ptr<render::ProbeObject> probes;
    std::unique_ptr<render::FrameSet> frame_set;
    std::unique_ptr<gpu::UploadBatch> upload; // its staging buffers live while the command buffer records
    VkCommandPool pool = VK_NULL_HANDLE;
    VkCommandBuffer cmd = VK_NULL_HANDLE;

    Frame()
    {
        gpu::ExternalDevice external = host.external(test::counting_proc_addr);
        external.log = [this](gpu::LogLevel severity, bool validation, std::string_view message)
        {
            if (validation)
                test::validation_log().add(std::string(message));
            else if (severity == gpu::LogLevel::Error)
            {
                const std::lock_guard<std::mutex> lock(mutex);
                errors.emplace_back(message);
            }
        };
        dev = std::make_unique<gpu::Device>(external);
        target = std::make_unique<render::OffscreenTarget>(*dev, 32, 32);
        system = std::make_unique<render::MaterialSystem>(*dev, target->desc());
        upload = std::make_unique<gpu::UploadBatch>(*dev);
        render::PrtModelDesc desc;
        desc.technique = "h4";
        desc.instances = 2;
        prt = std::make_unique<render::PrtModel>(*system, test::unshadowed_sphere_asset(12, 6, "h4", 4), desc,
                                                 *upload);
        level = std::make_unique<render::LightmapModel>(
            *system, test::table_level(io::Material{}, io::Material{}, {}, {"h4"}),
            std::vector<std::string>{"h4"}, *upload);
        const io::Mesh sphere = io::make_uv_sphere(0.3f, 8, 4);
        probes = std::make_unique<render::ProbeObject>(*system, sphere, std::vector<io::EncodedImage>{},
                                                       std::vector<io::Material>(1),
                                                       std::vector<io::Primitive>{}, 2, *upload);
        frame_set = std::make_unique<render::FrameSet>(*system);
        VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
        pi.queueFamilyIndex = host.family;
        EXPECT_EQ(vkCreateCommandPool(host.vk_device, &pi, nullptr, &pool), VK_SUCCESS);
        VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        ai.commandPool = pool;
        ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        ai.commandBufferCount = 1;
        EXPECT_EQ(vkAllocateCommandBuffers(host.vk_device, &ai, &cmd), VK_SUCCESS);
        VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        EXPECT_EQ(vkBeginCommandBuffer(cmd, &bi), VK_SUCCESS);
        upload->record(cmd);
        render::FrameData data;
        data.view_projection = math::look_at_projection(glm::vec3(0, -4, 2), glm::vec3(0), 50.0f, 1.0f);
        EXPECT_TRUE(frame_set->write(0, data));
        std::vector<glm::vec3> light(9, glm::vec3(0.1f));
        const render::PrtInstance instance{glm::mat4(1.0f), light, 0.0f};
        EXPECT_TRUE(prt->record_transfer(cmd, {&instance, 1}, 0));
        target->begin(cmd);
    }
    ~Frame()
    {
        target->end(cmd);
        vkEndCommandBuffer(cmd);
        vkDestroyCommandPool(host.vk_device, pool, nullptr);
        upload.reset();
        // Nothing was submitted: hemi's objects go before the engine's device.
        frame_set.reset();
        probes.reset();
        level.reset();
        prt.reset();
        system.reset();
        target.reset();
        dev.reset();
    }
    std::vector<std::string> take_errors()
    {
        const std::lock_guard<std::mutex> lock(mutex);
        return std::exchange(errors, {});
    }
};

// The call refused: false returned, nothing recorded, and exactly one error logged that names `call` and
// contains `what`.
void expect_refused(Frame& f, bool returned, const char* call, const std::string& what)
{
    EXPECT_FALSE(returned) << call;
    EXPECT_EQ(test::vulkan_calls().commands(), 0u) << call << " recorded commands for a refused argument";
    const std::vector<std::string> errors = f.take_errors();
    ASSERT_EQ(errors.size(), 1u) << call << ": one error logged";
    EXPECT_NE(errors[0].find(call), std::string::npos) << errors[0];
    EXPECT_NE(errors[0].find(what), std::string::npos) << errors[0];
}

// The same call with good arguments: true, commands recorded, no error.
void expect_recorded(Frame& f, bool returned, const char* call)
{
    EXPECT_TRUE(returned) << call;
    EXPECT_GT(test::vulkan_calls().commands(), 0u) << call << " recorded nothing for good arguments";
    EXPECT_TRUE(f.take_errors().empty()) << call;
}

class FramePathErrors : public test::GpuTest
{
};

TEST_F(FramePathErrors, AnUnknownTechniqueIsLoggedAndRecordsNothing)
{
    Frame f;
    ASSERT_TRUE(f.host.queue);
    test::vulkan_calls().reset();
    expect_refused(f, f.level->draw(f.cmd, f.frame_set->set(), "h6", glm::mat4(1.0f)), "LightmapModel::draw",
                   "technique 'h6' is not loaded");
    test::vulkan_calls().reset();
    expect_recorded(f, f.level->draw(f.cmd, f.frame_set->set(), "h4", glm::mat4(1.0f)),
                    "LightmapModel::draw");
}

TEST_F(FramePathErrors, APassIndexOutOfRangeIsLoggedAndRecordsNothing)
{
    Frame f;
    ASSERT_TRUE(f.host.queue);
    const VkDescriptorSet view = f.frame_set->set();
    test::vulkan_calls().reset();
    expect_refused(f, f.prt->draw(f.cmd, view, 0, glm::mat4(1.0f), 7), "PrtModel::draw",
                   "pass 7 was not added");
    expect_refused(f, f.probes->draw(f.cmd, view, 0, glm::mat4(1.0f), 0, 3), "ProbeObject::draw",
                   "pass 3 was not added");
    render::DrawQueue queue;
    expect_refused(f, f.prt->enqueue(queue, view, 1, glm::mat4(1.0f), 2), "PrtModel::enqueue",
                   "pass 2 was not added");
    EXPECT_EQ(queue.size(), 0u) << "a refused enqueue added packets";
    const std::vector<render::LightmapDraw> list = f.level->draw_list("h4");
    ASSERT_FALSE(list.empty());
    expect_refused(f, f.level->enqueue(queue, view, list[0], glm::mat4(1.0f), 1), "LightmapModel::enqueue",
                   "pass 1 was not added");
    EXPECT_EQ(queue.size(), 0u);
    // An instance and a frame slot out of range are refused the same way.
    expect_refused(f, f.prt->draw(f.cmd, view, 2, glm::mat4(1.0f)), "PrtModel::draw", "instance 2");
    expect_refused(f, f.probes->draw(f.cmd, view, 0, glm::mat4(1.0f), 1), "ProbeObject::draw",
                   "frame slot 1");
    test::vulkan_calls().reset();
    expect_recorded(f, f.prt->draw(f.cmd, view, 1, glm::mat4(1.0f), 0), "PrtModel::draw");
    test::vulkan_calls().reset();
    expect_recorded(f, f.probes->draw(f.cmd, view, 1, glm::mat4(1.0f), 0, 0), "ProbeObject::draw");
}

TEST_F(FramePathErrors, TooManyLightsAreLoggedAndWriteOrRecordNothing)
{
    Frame f;
    ASSERT_TRUE(f.host.queue);
    render::FrameData data;
    data.lights.resize(HEMI_MAX_LIGHTS + 1);
    test::vulkan_calls().reset();
    expect_refused(f, f.frame_set->write(0, data), "FrameSet::write", "at most");
    // Recorded outside the render pass in an engine; refused before any command here.
    expect_refused(f, f.frame_set->record_update(f.cmd, data, 0), "FrameSet::record_update", "at most");
    // The engine's own uniforms: what the refusal leaves is what the caller had.
    shared::FrameUniforms out{};
    out.options.x = 42.0f;
    expect_refused(f, render::frame_uniforms(*f.system, data, out), "frame_uniforms", "at most");
    EXPECT_EQ(out.options.x, 42.0f) << "refused uniforms were written";
    data.lights.resize(HEMI_MAX_LIGHTS);
    EXPECT_TRUE(render::frame_uniforms(*f.system, data, out));
    EXPECT_EQ(out.options.y, float(HEMI_MAX_LIGHTS));
    EXPECT_TRUE(f.frame_set->write(0, data));
    EXPECT_TRUE(f.take_errors().empty());
}

TEST_F(FramePathErrors, AReleasedObjectIsLoggedAndRecordsNothing)
{
    Frame f;
    ASSERT_TRUE(f.host.queue);
    // A frame set the engine released (what is left of a moved-from set: VK_NULL_HANDLE), and one from a slot
    // that does not exist.
    gpu::DescriptorSet released =
        f.system->descriptors().allocate(f.system->frame_layout(), render::MaterialSystem::frame_bindings());
    {
        const gpu::DescriptorSet taken = std::move(released);
    }
    ASSERT_EQ(released.get(), VK_NULL_HANDLE);
    test::vulkan_calls().reset();
    expect_refused(f, f.prt->draw(f.cmd, released.get(), 0, glm::mat4(1.0f)), "PrtModel::draw",
                   "frame set is VK_NULL_HANDLE");
    expect_refused(f, f.level->draw(f.cmd, released.get(), "h4", glm::mat4(1.0f)), "LightmapModel::draw",
                   "frame set is VK_NULL_HANDLE");
    expect_refused(f, f.frame_set->set(1) != VK_NULL_HANDLE, "FrameSet::set", "frame slot 1");
    // A packet list holding a packet whose mesh was released: the whole list is refused.
    render::DrawQueue queue;
    ASSERT_TRUE(f.probes->enqueue(queue, f.frame_set->set(), 0, glm::mat4(1.0f)));
    ASSERT_TRUE(f.prt->enqueue(queue, f.frame_set->set(), 0, glm::mat4(1.0f)));
    std::vector<render::DrawPacket> packets(queue.packets().begin(), queue.packets().end());
    packets.back().mesh = nullptr;
    test::vulkan_calls().reset();
    render::DrawStats stats = render::record_packets(f.cmd, packets);
    expect_refused(f, stats.draws != 0 || stats.refused == 0, "record_packets", "mesh null");
    EXPECT_EQ(stats.refused, 1u);
    packets.pop_back();
    test::vulkan_calls().reset();
    stats = render::record_packets(f.cmd, packets);
    expect_recorded(f, stats.draws == packets.size(), "record_packets");
}

// Lighting and matrices an object cannot be lit by: refused with a message, nothing recorded or written, and
// never a throw out of the noexcept call (a finite matrix far from a rotation overflows once its scale is
// divided out: it is refused before an SH rotation is made of it).
TEST_F(FramePathErrors, ValuesThatCannotLightAnObjectAreLoggedAndRecordNothing)
{
    Frame f;
    ASSERT_TRUE(f.host.queue);
    std::vector<glm::vec3> light(9, glm::vec3(0.1f));
    glm::mat4 far_from_rotation(1.0f);
    far_from_rotation[0][0] = 3e38f;
    far_from_rotation[1][1] = far_from_rotation[2][2] = 1e-20f;
    render::AccessList accesses;
    test::vulkan_calls().reset();
    for (const glm::mat4& m : {glm::mat4(0.0f), far_from_rotation})
    {
        const render::PrtInstance instance{m, light, 0.0f};
        expect_refused(f, f.prt->record_transfer(f.cmd, {&instance, 1}, 0, accesses),
                       "PrtModel::record_transfer", "singular or not finite");
    }
    EXPECT_EQ(accesses.size(), 0u) << "a refused transfer declared accesses";
    light[4].y = std::nanf("");
    const render::PrtInstance lit_by_nan{glm::mat4(1.0f), light, 0.0f};
    expect_refused(f, f.prt->record_transfer(f.cmd, {&lit_by_nan, 1}, 0, accesses),
                   "PrtModel::record_transfer", "not finite");
    expect_refused(f, f.probes->write_lighting(0, light, 0), "ProbeObject::write_lighting", "not finite");
    const shared::DrawPush records[2] = {};
    expect_refused(f, f.frame_set->write_instances(0, records), "FrameSet::write_instances",
                   "past a frame set");
    std::array<glm::vec3, 9> sh;
    glm::mat4 nan_translation(1.0f);
    nan_translation[3].x = std::nanf("");
    EXPECT_FALSE(render::probe_lighting(io::LightmapAsset{}, glm::vec3(0.0f), glm::mat4(1.0f), sh));
    io::LightmapAsset with_probes;
    with_probes.probes.count = glm::uvec3(1);
    with_probes.probes.irradiance.assign(1, std::array<glm::vec3, 9>{});
    with_probes.probes.valid.assign(1, 1);
    EXPECT_TRUE(render::probe_lighting(with_probes, glm::vec3(0.0f), glm::mat4(1.0f), sh));
    EXPECT_FALSE(render::probe_lighting(with_probes, glm::vec3(0.0f), nan_translation, sh));
    EXPECT_FALSE(render::probe_lighting(with_probes, glm::vec3(0.0f), far_from_rotation, sh));
}

} // namespace
