#pragma once
// An engine's depth-only render pass (tests): one D32 attachment, cleared to 1 and stored, with a blanket
// external dependency: a shadow map, or a depth prepass read back.
#include "../gpu_fixture.h"
#include "engine_pass.h"

#include <hemi/gpu/resources.h>

#include <cstring>
#include <stdexcept>
#include <vector>

namespace hemi::test
{

struct DepthPass
{
    uint32_t size;
    gpu::Image depth;
    gpu::RenderPass render_pass;
    gpu::Framebuffer framebuffer;

    explicit DepthPass(uint32_t side = 64) : size(side)
    {
        const VkDevice d = device().device();
        depth = gpu::create_image(
            device(), {size, size, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT});
        VkAttachmentDescription a{};
        a.format = VK_FORMAT_D32_SFLOAT;
        a.samples = VK_SAMPLE_COUNT_1_BIT;
        a.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        a.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        a.finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
        const VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        VkSubpassDescription subpass{};
        subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        subpass.pDepthStencilAttachment = &ref;
        VkSubpassDependency dependency{};
        dependency.srcSubpass = VK_SUBPASS_EXTERNAL;
        dependency.srcStageMask = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
        dependency.dstStageMask = VK_PIPELINE_STAGE_ALL_GRAPHICS_BIT;
        dependency.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
        dependency.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
        VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        rp.attachmentCount = 1;
        rp.pAttachments = &a;
        rp.subpassCount = 1;
        rp.pSubpasses = &subpass;
        rp.dependencyCount = 1;
        rp.pDependencies = &dependency;
        VkRenderPass raw_pass;
        if (vkCreateRenderPass(d, &rp, nullptr, &raw_pass) != VK_SUCCESS)
            throw std::runtime_error("vkCreateRenderPass failed");
        render_pass = gpu::RenderPass(d, raw_pass);
        const VkImageView view = depth.view();
        VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
        fb.renderPass = render_pass;
        fb.attachmentCount = 1;
        fb.pAttachments = &view;
        fb.width = fb.height = size;
        fb.layers = 1;
        VkFramebuffer raw_fb;
        if (vkCreateFramebuffer(d, &fb, nullptr, &raw_fb) != VK_SUCCESS)
            throw std::runtime_error("vkCreateFramebuffer failed");
        framebuffer = gpu::Framebuffer(d, raw_fb);
    }
    void begin(VkCommandBuffer cmd) const
    {
        VkClearValue clear{};
        clear.depthStencil = {1.0f, 0};
        VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        begin.renderPass = render_pass;
        begin.framebuffer = framebuffer;
        begin.renderArea = {{0, 0}, {size, size}};
        begin.clearValueCount = 1;
        begin.pClearValues = &clear;
        vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
        EnginePass::set_viewport(cmd, size, size);
    }
    std::vector<float> read() const
    {
        const auto bytes = gpu::read_image(device(), depth, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
        std::vector<float> out(bytes.size() / 4);
        std::memcpy(out.data(), bytes.data(), bytes.size());
        return out;
    }
};

} // namespace hemi::test
