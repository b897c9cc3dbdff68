#pragma once
// An engine's own render pass, as the tests build one: colour attachments of the given formats and a D32
// depth buffer, one subpass, cleared on begin; the colour images end in COLOR_ATTACHMENT_OPTIMAL for
// readback. Independent of hemi's OffscreenTarget on purpose: materials must draw into passes hemi did not
// make. Its external dependency either orders every earlier write before the pass (as OffscreenTarget's
// does) or, with `attachments_only`, only earlier uses of its attachments, as an engine's render pass does:
// then nothing but the caller's barriers orders earlier work before the draws, and synchronisation
// validation sees a missing one.
#include "../gpu_fixture.h"

#include <hemi/gpu/handle.h>
#include <hemi/gpu/resources.h>

#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <vector>

namespace hemi::test
{

struct EnginePass
{
    const gpu::Device* dev;
    uint32_t width, height;
    std::vector<gpu::Image> colors;
    gpu::Image depth;
    gpu::RenderPass render_pass;
    gpu::Framebuffer framebuffer;

    EnginePass(uint32_t w, uint32_t h, const std::vector<VkFormat>& formats, const gpu::Device& on = device(),
               bool attachments_only = false)
        : dev(&on), width(w), height(h)
    {
        const VkDevice d = on.device();
        std::vector<VkAttachmentDescription> attachments;
        std::vector<VkAttachmentReference> refs;
        std::vector<VkImageView> views;
        for (VkFormat f : formats)
        {
            colors.push_back(gpu::create_image(on, {w, h, f, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT}));
            views.push_back(colors.back().view());
            refs.push_back({uint32_t(attachments.size()), VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL});
            attachments.push_back(
                attachment(f, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_ATTACHMENT_STORE_OP_STORE));
        }
        depth =
            gpu::create_image(on, {w, h, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT});
        views.push_back(depth.view());
        const VkAttachmentReference depth_ref{uint32_t(attachments.size()),
                                              VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        attachments.push_back(attachment(VK_FORMAT_D32_SFLOAT,
                                         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                                         VK_ATTACHMENT_STORE_OP_DONT_CARE));
        VkSubpassDescription subpass{};
        subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        subpass.colorAttachmentCount = uint32_t(refs.size());
        subpass.pColorAttachments = refs.data();
        subpass.pDepthStencilAttachment = &depth_ref;
        VkSubpassDependency dependency{};
        dependency.srcSubpass = VK_SUBPASS_EXTERNAL;
        dependency.srcStageMask = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
        dependency.dstStageMask = VK_PIPELINE_STAGE_ALL_GRAPHICS_BIT;
        dependency.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
        dependency.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
        if (attachments_only)
        {
            dependency.srcStageMask = dependency.dstStageMask =
                VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
            dependency.srcAccessMask = dependency.dstAccessMask =
                VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        }
        VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        rp.attachmentCount = uint32_t(attachments.size());
        rp.pAttachments = attachments.data();
        rp.subpassCount = 1;
        rp.pSubpasses = &subpass;
        rp.dependencyCount = 1;
        rp.pDependencies = &dependency;
        VkRenderPass raw_pass;
        if (vkCreateRenderPass(d, &rp, nullptr, &raw_pass) != VK_SUCCESS)
            throw std::runtime_error("vkCreateRenderPass failed");
        render_pass = gpu::RenderPass(d, raw_pass);
        VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
        fb.renderPass = render_pass;
        fb.attachmentCount = uint32_t(views.size());
        fb.pAttachments = views.data();
        fb.width = w;
        fb.height = h;
        fb.layers = 1;
        VkFramebuffer raw_fb;
        if (vkCreateFramebuffer(d, &fb, nullptr, &raw_fb) != VK_SUCCESS)
            throw std::runtime_error("vkCreateFramebuffer failed");
        framebuffer = gpu::Framebuffer(d, raw_fb);
    }

    // Begins the pass clearing every colour attachment to `clear` and depth to 1, and sets viewport and
    // scissor.
    void begin(VkCommandBuffer cmd, const float clear[4]) const
    {
        std::vector<VkClearValue> clears(colors.size() + 1);
        for (size_t i = 0; i < colors.size(); ++i)
            std::memcpy(clears[i].color.float32, clear, 4 * sizeof(float));
        clears.back().depthStencil = {1.0f, 0};
        VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        begin.renderPass = render_pass;
        begin.framebuffer = framebuffer;
        begin.renderArea = {{0, 0}, {width, height}};
        begin.clearValueCount = uint32_t(clears.size());
        begin.pClearValues = clears.data();
        vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
        set_viewport(cmd, width, height);
    }

    // Colour attachment `i` read back as floats (an RGBA32F attachment; after the pass has ended).
    std::vector<float> read_color(size_t i = 0) const
    {
        const auto bytes = gpu::read_image(*dev, colors.at(i), VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
        std::vector<float> out(bytes.size() / sizeof(float));
        std::memcpy(out.data(), bytes.data(), bytes.size());
        return out;
    }

    static void set_viewport(VkCommandBuffer cmd, uint32_t w, uint32_t h)
    {
        const VkViewport viewport{0.0f, 0.0f, float(w), float(h), 0.0f, 1.0f};
        const VkRect2D scissor{{0, 0}, {w, h}};
        vkCmdSetViewport(cmd, 0, 1, &viewport);
        vkCmdSetScissor(cmd, 0, 1, &scissor);
    }

  private:
    static VkAttachmentDescription attachment(VkFormat format, VkImageLayout final_layout,
                                              VkAttachmentStoreOp store)
    {
        VkAttachmentDescription a{};
        a.format = format;
        a.samples = VK_SAMPLE_COUNT_1_BIT;
        a.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        a.storeOp = store;
        a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        a.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        a.finalLayout = final_layout;
        return a;
    }
};

} // namespace hemi::test
