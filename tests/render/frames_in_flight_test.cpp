// Three frames in flight of a PRT object whose lighting changes every frame, scheduled as an engine with
// async compute would: the transfer pass of frame k runs one frame ahead, in the same submission as the
// draws of frame k - 1, and the CPU writes frame k's view (FrameSet::write) while frames k - 1 and k - 2 are
// still on the GPU. The engine's instance runs the validation layer with synchronisation validation; any
// message fails the test. (The frames draw into hemi's OffscreenTarget, whose render pass depends on every
// earlier write, so within a submission that dependency alone orders the transfer before the draws; the
// image check is what catches a frame drawn from the wrong coefficients. tests/render/engine_path_test.cpp
// draws into an engine's own render pass, where a missing barrier is a hazard the layer reports.)
//
// The check, for every frame: an unshadowed SH9 sphere lit by one directional light of direction d_k (SH
// coefficients y_lm(d_k)), which turns by 50 degrees a frame. Each covered pixel's exit radiance (albedo 1,
// lighting only) must be the CPU's (1/pi) sum_l A_l (2l+1)/(4 pi) P_l(n . d_k) (Ramamoorthi & Hanrahan's
// clamped-cosine convolution of the band-limited light) at the pixel's normal n, from the aux attachment's
// UV. A model whose transfer output is single-buffered (frames_in_flight = 1) draws frame k - 1 with frame
// k's coefficients: the same schedule with it must fail the same check, and does (asserted below).
#include "../gpu_fixture.h"
#include "../host_vulkan.h"
#include "sphere_asset.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/camera.h>
#include <hemi/math/sh.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/view/offscreen.h>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

namespace
{

constexpr uint32_t W = 96, H = 96, kFrames = 9, kInFlight = 3;

hemi::io::PrtAsset sphere_asset()
{
    return hemi::test::unshadowed_sphere_asset(64, 32, "gs", 9);
}

glm::vec3 light_direction(uint32_t frame)
{
    const float a = glm::radians(50.0f * float(frame));
    return glm::normalize(glm::vec3(std::cos(a), -0.8f, std::sin(a)));
}

// The CPU's exit radiance at normal n under frame `frame`'s light (independent of hemi's SH code: Legendre
// polynomials of n . d).
float expected(const glm::vec3& n, uint32_t frame)
{
    const float pi = float(M_PI), x = glm::dot(n, light_direction(frame));
    const float p[3] = {1.0f, x, 0.5f * (3.0f * x * x - 1.0f)};
    const float a[3] = {pi, 2.0f * pi / 3.0f, pi / 4.0f};
    float e = 0.0f;
    for (int l = 0; l < 3; ++l)
        e += a[l] * float(2 * l + 1) / (4.0f * pi) * p[l];
    return e / pi;
}

struct Result
{
    uint32_t covered = 0, wrong = 0;
    float worst = 0.0f;
    float centre_error =
        0.0f; // pixels between the sphere's covered centroid and where the frame's camera puts it
};

// Each frame's camera is its own (moved sideways per frame), written to the frame's FrameSet slot: a frame
// drawn with another slot's view lands ~10 pixels away.
glm::mat4 view_projection(uint32_t frame)
{
    const float dx = 0.3f * float(frame % 3) - 0.3f;
    return hemi::math::look_at_projection(glm::vec3(dx, -4.0f, 0), glm::vec3(dx, 0, 0), 40.0f, float(W) / H);
}

// Frame `frame`'s image against the CPU: covered pixels (aux alpha 1) within 2% of the brightest value.
Result check(const hemi::io::ImageRgba& color, const hemi::io::ImageRgba& aux, uint32_t frame)
{
    Result r;
    double cx = 0.0;
    for (size_t p = 0; p < size_t(W) * H; ++p)
    {
        if (aux.pixels[p * 4 + 3] != 1.0f)
            continue;
        cx += double(p % W) + 0.5;
        const float u = aux.pixels[p * 4], v = aux.pixels[p * 4 + 1];
        const float phi = 2.0f * float(M_PI) * u, theta = float(M_PI) * v;
        const glm::vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        const float error = std::abs(color.pixels[p * 4] - expected(n, frame));
        ++r.covered;
        r.worst = std::max(r.worst, error);
        if (error > 0.02f * expected(light_direction(frame), frame))
            ++r.wrong;
    }
    const glm::vec4 clip = view_projection(frame) * glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    const float centre = (clip.x / clip.w * 0.5f + 0.5f) * float(W);
    r.centre_error = r.covered ? std::abs(float(cx / r.covered) - centre) : float(W);
    return r;
}

// Runs kFrames frames with the schedule above on the host's device and checks each frame's image.
std::vector<Result> run_frames(hemi::test::HostVulkan& host, uint32_t model_frames)
{
    hemi::gpu::Device dev(host.external());
    std::vector<std::unique_ptr<hemi::render::OffscreenTarget>> targets;
    for (uint32_t i = 0; i < kInFlight; ++i)
        targets.push_back(std::make_unique<hemi::render::OffscreenTarget>(dev, W, H));
    hemi::render::MaterialSystem system(dev, targets[0]->desc());
    const hemi::io::PrtAsset asset = sphere_asset();
    hemi::gpu::UploadBatch upload(dev);
    hemi::render::PrtModelDesc desc;
    desc.frames_in_flight = model_frames;
    hemi::render::PrtModel model(system, asset, desc, upload);
    hemi::render::FrameSet frame_set(system, kInFlight);
    upload.submit_and_wait(); // loading, before the first frame

    // The engine's own command buffers and fences, one per frame in flight.
    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = host.family;
    VkCommandPool pool = VK_NULL_HANDLE;
    EXPECT_EQ(vkCreateCommandPool(host.vk_device, &pi, nullptr, &pool), VK_SUCCESS);
    std::array<VkCommandBuffer, kInFlight> cmds{};
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = kInFlight;
    EXPECT_EQ(vkAllocateCommandBuffers(host.vk_device, &ai, cmds.data()), VK_SUCCESS);
    std::array<VkFence, kInFlight> fences{};
    for (VkFence& f : fences)
    {
        VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        fi.flags = VK_FENCE_CREATE_SIGNALED_BIT;
        EXPECT_EQ(vkCreateFence(host.vk_device, &fi, nullptr, &f), VK_SUCCESS);
    }

    const glm::mat4 identity(1.0f);
    std::vector<glm::vec3> light(9);
    std::vector<Result> results(kFrames);
    auto read_frame = [&](uint32_t frame)
    {
        const hemi::render::OffscreenTarget& t = *targets[frame % kInFlight];
        results[frame] = check(t.read_color(), t.read_aux(), frame);
    };
    // Submission k: the transfer pass of frame k (k < kFrames), then the draws of frame k - 1.
    for (uint32_t k = 0; k <= kFrames; ++k)
    {
        const uint32_t slot = k % kInFlight;
        EXPECT_EQ(vkWaitForFences(host.vk_device, 1, &fences[slot], VK_TRUE, UINT64_MAX), VK_SUCCESS);
        EXPECT_EQ(vkResetFences(host.vk_device, 1, &fences[slot]), VK_SUCCESS);
        if (k >= kInFlight + 1)
            read_frame(k - kInFlight - 1); // drawn by submission k - kInFlight, which the fence retired
        VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        vkResetCommandBuffer(cmds[slot], 0);
        vkBeginCommandBuffer(cmds[slot], &bi);
        if (k < kFrames)
        {
            float y[9];
            hemi::math::sh_eval(3, light_direction(k), y);
            for (int i = 0; i < 9; ++i)
                light[i] = glm::vec3(y[i]);
            const hemi::render::PrtInstance instance{identity, light, 0.0f};
            model.record_transfer(cmds[slot], {&instance, 1}, k % model_frames);
        }
        if (k >= 1)
        {
            const uint32_t f = k - 1;
            hemi::render::FrameData data;
            data.view_projection = view_projection(f);
            data.lighting_only = true;
            frame_set.write(f % kInFlight, data);
            targets[f % kInFlight]->begin(cmds[slot]);
            model.draw(cmds[slot], frame_set.set(f % kInFlight), 0, identity, 0, f % model_frames);
            targets[f % kInFlight]->end(cmds[slot]);
        }
        vkEndCommandBuffer(cmds[slot]);
        VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        si.commandBufferCount = 1;
        si.pCommandBuffers = &cmds[slot];
        EXPECT_EQ(vkQueueSubmit(host.queue, 1, &si, fences[slot]), VK_SUCCESS);
    }
    EXPECT_EQ(vkWaitForFences(host.vk_device, kInFlight, fences.data(), VK_TRUE, UINT64_MAX), VK_SUCCESS);
    for (uint32_t f = kFrames - kInFlight; f < kFrames; ++f)
        read_frame(f);
    for (VkFence f : fences)
        vkDestroyFence(host.vk_device, f, nullptr);
    vkDestroyCommandPool(host.vk_device, pool, nullptr);
    return results;
}

class FramesInFlight : public hemi::test::GpuTest
{
};

} // namespace

TEST_F(FramesInFlight, ThreePrtFramesEachShowTheirOwnLightingUnderSynchronisationValidation)
{
    hemi::test::HostVulkan host(true);
    ASSERT_NE(host.queue, VK_NULL_HANDLE);
    const std::vector<Result> results = run_frames(host, kInFlight);
    for (uint32_t f = 0; f < kFrames; ++f)
    {
        EXPECT_GT(results[f].covered, W * H / 4) << "frame " << f << " drew too little";
        EXPECT_LT(results[f].centre_error, 1.5f) << "frame " << f << " was drawn with another frame's view";
        EXPECT_EQ(results[f].wrong, 0u)
            << "frame " << f << ": " << results[f].wrong << " of " << results[f].covered
            << " pixels differ from the CPU by more than 2% "
            << "of the peak (worst " << results[f].worst << ")";
    }
    // The check catches a single-buffered output: every frame but the last then shows the next frame's light.
    const std::vector<Result> single = run_frames(host, 1);
    for (uint32_t f = 0; f + 1 < kFrames; ++f)
        EXPECT_GT(single[f].wrong, single[f].covered / 4)
            << "frame " << f << " passed with a single-buffered transfer output";
    EXPECT_EQ(single[kFrames - 1].wrong, 0u);
}
