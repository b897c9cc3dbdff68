// Two instances of one baked asset, drawn in one render pass of the caller's (their own VkRenderPass, and
// dynamic rendering), share the model's GPU data (mesh, textures, one copy of the matrices) and are each lit
// by the distant lighting rotated into their own frame by the library.
//
// The check: a sphere baked unshadowed (gold standard SH9, lighting order 3) lit by a single directional
// light d (SH coefficients y_lm(d)). Its irradiance peaks where the world-space normal is d, whatever the
// object's rotation. Instance A is unrotated, instance B is turned 90 degrees about world z; on each, the
// brightest pixel's UV (from the aux attachment) gives the object-space normal of the UV sphere, which its
// model matrix turns into world space: it must point along d. A library that relit B with the world
// lighting unrotated would put B's peak 90 degrees away.
#include "../gpu_fixture.h"
#include "engine_pass.h"
#include "sphere_asset.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/sh.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/scene/draw_queue.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/view/prt_view.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstring>

namespace
{

class Instances : public hemi::test::GpuTest
{
};

constexpr uint32_t W = 192, H = 96;

hemi::io::PrtAsset sphere_asset()
{
    return hemi::test::unshadowed_sphere_asset(64, 32, "gs", 9);
}

struct Placement
{
    glm::mat4 model;
    glm::mat3 rotation;
};

// A: unrotated, left; B: turned 90 degrees about z, right.
std::array<Placement, 2> placements()
{
    const glm::mat4 b_rot = glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(0, 0, 1));
    return {Placement{glm::translate(glm::mat4(1.0f), glm::vec3(-1.3f, 0, 0)), glm::mat3(1.0f)},
            Placement{glm::translate(glm::mat4(1.0f), glm::vec3(1.3f, 0, 0)) * b_rot, glm::mat3(b_rot)}};
}

const glm::vec3 kLight = glm::normalize(glm::vec3(0.45f, -1.0f, 0.5f));

std::vector<glm::vec3> directional_light()
{
    float y[9];
    hemi::math::sh_eval(3, kLight, y);
    std::vector<glm::vec3> l(9);
    for (int i = 0; i < 9; ++i)
        l[i] = glm::vec3(y[i]);
    return l;
}

// Where the brightest covered pixel of [x0, x1) lands on the UV sphere (object space), turned into world
// space.
glm::vec3 peak_normal(const std::vector<float>& color, const std::vector<float>& aux, uint32_t x0,
                      uint32_t x1, const glm::mat3& rotation)
{
    float best = -1.0f;
    glm::vec2 uv(0.0f);
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = x0; x < x1; ++x)
        {
            const size_t p = (size_t(y) * W + x) * 4;
            if (aux[p + 3] != 1.0f)
                continue;
            if (color[p] > best)
                best = color[p], uv = glm::vec2(aux[p], aux[p + 1]);
        }
    EXPECT_GT(best, 0.0f) << "nothing drawn in columns " << x0 << "-" << x1;
    const float phi = 2.0f * float(M_PI) * uv.x, theta = float(M_PI) * uv.y;
    const glm::vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    return rotation * n;
}

std::vector<float> floats(const std::vector<std::byte>& bytes)
{
    std::vector<float> f(bytes.size() / 4);
    std::memcpy(f.data(), bytes.data(), bytes.size());
    return f;
}

// Records both instances' transfer and frame update, then `draw_pass` records the caller's pass around
// `draw` (two draws, or with `instanced` one instanced draw of both); checks both peaks. Returns the colour
// and aux images.
std::vector<float> check_two_instances(
    hemi::render::MaterialSystem& system,
    const std::function<void(VkCommandBuffer, const std::function<void(VkCommandBuffer)>&)>& pass,
    const hemi::gpu::Image& color, const hemi::gpu::Image& aux, bool instanced = false)
{
    auto& dev = hemi::test::device();
    const hemi::io::PrtAsset asset = sphere_asset();
    hemi::gpu::UploadBatch upload(dev);
    hemi::render::PrtModel model(system, asset, {"gs", false, 2}, upload);
    hemi::render::FrameSet frame(system, 1, 2);
    const std::vector<glm::vec3> light = directional_light();
    const auto place = placements();
    const hemi::shared::DrawPush records[2] = {model.instance_record(0, place[0].model),
                                               model.instance_record(1, place[1].model)};
    frame.write_instances(0, records);
    hemi::render::DrawQueue queue;
    model.enqueue_instances(queue, frame.set(), {0, 2});
    hemi::render::PrtInstance instances[2];
    for (int i = 0; i < 2; ++i)
        instances[i] = {place[i].model, light, 0.0f};
    hemi::render::FrameData f;
    f.view_projection =
        hemi::render::look_at_projection(glm::vec3(0, -6.5f, 0), glm::vec3(0), 32.0f, float(W) / H);
    f.lighting_only = true;
    hemi::gpu::one_shot(dev,
                        [&](VkCommandBuffer cmd)
                        {
                            upload.record(cmd);
                            model.record_transfer(cmd, instances);
                            frame.record_update(cmd, f);
                            pass(cmd,
                                 [&](VkCommandBuffer c)
                                 {
                                     if (instanced)
                                         EXPECT_EQ(queue.record(c).draws, 1u);
                                     else
                                         for (uint32_t i = 0; i < 2; ++i)
                                             model.draw(c, frame.set(), i, place[i].model);
                                 });
                        });
    const auto c = floats(hemi::gpu::read_image(dev, color, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL));
    const auto a = floats(hemi::gpu::read_image(dev, aux, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL));
    for (int i = 0; i < 2; ++i)
    {
        const glm::vec3 n = peak_normal(c, a, i == 0 ? 0 : W / 2, i == 0 ? W / 2 : W, place[i].rotation);
        const float degrees = glm::degrees(std::acos(std::clamp(glm::dot(n, kLight), -1.0f, 1.0f)));
        EXPECT_LT(degrees, 6.0f) << "instance " << i << ": the lobe's peak is " << degrees
                                 << " degrees from the light";
        ::testing::Test::RecordProperty("peak_error_degrees_" + std::to_string(i), std::to_string(degrees));
    }
    EXPECT_EQ(system.type_count(), 1u) << "both instances draw with one material type";
    std::vector<float> both = c;
    both.insert(both.end(), a.begin(), a.end());
    return both;
}

hemi::gpu::Image attachment(VkFormat format, VkImageUsageFlags usage)
{
    return hemi::gpu::create_image(hemi::test::device(), {W, H, format, usage});
}

} // namespace

TEST_F(Instances, TwoInstancesInTheCallersRenderPassAreEachLitInTheirFrame)
{
    auto& dev = hemi::test::device();
    const hemi::test::EnginePass engine(W, H, {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT});
    hemi::render::RenderTargetDesc target;
    target.render_pass = engine.render_pass;
    target.color_attachments = 2;
    target.aux_output = true;
    hemi::render::MaterialSystem system(dev, target);
    check_two_instances(
        system,
        [&](VkCommandBuffer cmd, const std::function<void(VkCommandBuffer)>& draw)
        {
            const float clear[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            engine.begin(cmd, clear);
            draw(cmd);
            vkCmdEndRenderPass(cmd);
        },
        engine.colors[0], engine.colors[1]);
}

// Both instances in one instanced draw (PrtModel::enqueue_instances over the frame set's instance records):
// each instance takes its own placement and its own lit coefficients from its record, and the pixels equal
// the two separate draws' exactly (colour and aux). A shader that drew every instance with the push's values
// or record 0's puts both spheres in one place, lit alike.
TEST_F(Instances, OneInstancedDrawEqualsTheSeparateDraws)
{
    auto& dev = hemi::test::device();
    const hemi::test::EnginePass engine(W, H, {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT});
    hemi::render::RenderTargetDesc target;
    target.render_pass = engine.render_pass;
    target.color_attachments = 2;
    target.aux_output = true;
    hemi::render::MaterialSystem system(dev, target);
    auto pass = [&](VkCommandBuffer cmd, const std::function<void(VkCommandBuffer)>& draw)
    {
        const float clear[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        engine.begin(cmd, clear);
        draw(cmd);
        vkCmdEndRenderPass(cmd);
    };
    const std::vector<float> separate = check_two_instances(system, pass, engine.colors[0], engine.colors[1]);
    const std::vector<float> instanced =
        check_two_instances(system, pass, engine.colors[0], engine.colors[1], true);
    EXPECT_TRUE(separate == instanced) << "the instanced draw's pixels differ from the separate draws'";
}

TEST_F(Instances, TwoInstancesWithDynamicRenderingAndReverseZAreEachLitInTheirFrame)
{
    auto& dev = hemi::test::device();
    ASSERT_TRUE(dev.dynamic_rendering()) << "lavapipe supports Vulkan 1.3 dynamic rendering";
    hemi::gpu::Image color = attachment(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT);
    hemi::gpu::Image aux = attachment(VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT);
    hemi::gpu::Image depth = attachment(VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT);
    hemi::render::RenderTargetDesc target;
    target.color_formats = {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT};
    target.depth_format = VK_FORMAT_D32_SFLOAT;
    target.aux_output = true;
    // Reverse-Z as an engine would set it up: GREATER passes, depth cleared to 0. With the forward projection
    // of look_at_projection that keeps the *farther* surface, which on a closed sphere is the back half:
    // culling still removes it, so what is drawn is the same front half either way.
    target.depth_compare = VK_COMPARE_OP_GREATER_OR_EQUAL;
    hemi::render::MaterialSystem system(dev, target);
    check_two_instances(
        system,
        [&](VkCommandBuffer cmd, const std::function<void(VkCommandBuffer)>& draw)
        {
            hemi::gpu::transition_image(cmd, color, VK_IMAGE_LAYOUT_UNDEFINED,
                                        VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
            hemi::gpu::transition_image(cmd, aux, VK_IMAGE_LAYOUT_UNDEFINED,
                                        VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
            hemi::gpu::transition_image(cmd, depth, VK_IMAGE_LAYOUT_UNDEFINED,
                                        VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
            VkRenderingAttachmentInfo colors[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                                   {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
            const hemi::gpu::Image* images[2] = {&color, &aux};
            for (int i = 0; i < 2; ++i)
            {
                colors[i].imageView = images[i]->view();
                colors[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
                colors[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
                colors[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
            }
            VkRenderingAttachmentInfo depth_info{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
            depth_info.imageView = depth.view();
            depth_info.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
            depth_info.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
            depth_info.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
            depth_info.clearValue.depthStencil = {0.0f, 0};
            VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
            info.renderArea = {{0, 0}, {W, H}};
            info.layerCount = 1;
            info.colorAttachmentCount = 2;
            info.pColorAttachments = colors;
            info.pDepthAttachment = &depth_info;
            vkCmdBeginRendering(cmd, &info);
            hemi::test::EnginePass::set_viewport(cmd, W, H);
            draw(cmd);
            vkCmdEndRendering(cmd);
        },
        color, aux);
}
