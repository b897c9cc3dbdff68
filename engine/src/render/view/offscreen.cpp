#include <hemi/gpu/vk_check.h>
#include <hemi/render/view/offscreen.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::render
{

OffscreenTarget::OffscreenTarget(const gpu::Device& device, uint32_t width, uint32_t height)
    : device_(&device), width_(width), height_(height)
{
    const VkImageUsageFlags color_usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
    const VkPhysicalDeviceLimits& limits = device.limits();
    const std::string size = std::to_string(width) + "x" + std::to_string(height);
    if (width > limits.maxFramebufferWidth || height > limits.maxFramebufferHeight)
        throw std::invalid_argument("hemi: a " + size + " render target exceeds device " +
                                    std::string(device.name()) + "'s maxFramebufferWidth/Height (" +
                                    std::to_string(limits.maxFramebufferWidth) + "x" +
                                    std::to_string(limits.maxFramebufferHeight) + ")");
    try
    {
        color_ = gpu::create_image(device, {width, height, VK_FORMAT_R32G32B32A32_SFLOAT, color_usage});
        aux_ = gpu::create_image(device, {width, height, VK_FORMAT_R32G32B32A32_SFLOAT, color_usage});
        depth_ = gpu::create_image(
            device, {width, height, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT});
    }
    catch (const std::invalid_argument& e)
    {
        std::string why = e.what();
        if (why.rfind("hemi: ", 0) == 0)
            why = why.substr(6);
        throw std::invalid_argument("hemi: a " + size +
                                    " render target (two RGBA32F attachments and D32): " + why);
    }

    VkAttachmentDescription attachments[3] = {};
    for (int i = 0; i < 2; ++i)
    {
        attachments[i].format = VK_FORMAT_R32G32B32A32_SFLOAT;
        attachments[i].samples = VK_SAMPLE_COUNT_1_BIT;
        attachments[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
        attachments[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        attachments[i].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        attachments[i].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        attachments[i].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        attachments[i].finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    }
    attachments[2] = attachments[0];
    attachments[2].format = VK_FORMAT_D32_SFLOAT;
    attachments[2].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    attachments[2].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;

    VkAttachmentReference color_refs[2] = {{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                                           {1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}};
    VkAttachmentReference depth_ref{2, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 2;
    subpass.pColorAttachments = color_refs;
    subpass.pDepthStencilAttachment = &depth_ref;

    // Writes before the pass (uniform updates, compute) are visible to it; its writes are visible after.
    VkSubpassDependency deps[2] = {};
    deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    deps[0].dstSubpass = 0;
    deps[0].srcStageMask = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
    deps[0].dstStageMask = VK_PIPELINE_STAGE_ALL_GRAPHICS_BIT;
    deps[0].srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    deps[0].dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    deps[1].srcSubpass = 0;
    deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    deps[1].srcStageMask = VK_PIPELINE_STAGE_ALL_GRAPHICS_BIT;
    deps[1].dstStageMask = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
    deps[1].srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    deps[1].dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;

    VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    rp.attachmentCount = 3;
    rp.pAttachments = attachments;
    rp.subpassCount = 1;
    rp.pSubpasses = &subpass;
    rp.dependencyCount = 2;
    rp.pDependencies = deps;
    VkRenderPass render_pass;
    HEMI_VK_CHECK(vkCreateRenderPass(device.device(), &rp, nullptr, &render_pass));
    render_pass_ = gpu::RenderPass(device.device(), render_pass);
    device.set_name(VK_OBJECT_TYPE_RENDER_PASS, render_pass, "hemi offscreen render pass");

    VkImageView views[3] = {color_.view(), aux_.view(), depth_.view()};
    VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fb.renderPass = render_pass;
    fb.attachmentCount = 3;
    fb.pAttachments = views;
    fb.width = width;
    fb.height = height;
    fb.layers = 1;
    VkFramebuffer framebuffer;
    HEMI_VK_CHECK(vkCreateFramebuffer(device.device(), &fb, nullptr, &framebuffer));
    framebuffer_ = gpu::Framebuffer(device.device(), framebuffer);
    device.set_name(VK_OBJECT_TYPE_FRAMEBUFFER, framebuffer, "hemi offscreen framebuffer");
}

void OffscreenTarget::begin(VkCommandBuffer cmd, const glm::vec4& clear) const
{
    VkClearValue clears[3];
    std::memcpy(clears[0].color.float32, &clear, sizeof(float) * 4);
    clears[1].color = {{0.0f, 0.0f, 0.0f, 0.0f}};
    clears[2].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    info.renderPass = render_pass_;
    info.framebuffer = framebuffer_;
    info.renderArea = {{0, 0}, {width_, height_}};
    info.clearValueCount = 3;
    info.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &info, VK_SUBPASS_CONTENTS_INLINE);
    VkViewport viewport{0.0f, 0.0f, float(width_), float(height_), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {width_, height_}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
}

void OffscreenTarget::end(VkCommandBuffer cmd) const
{
    vkCmdEndRenderPass(cmd);
}

io::ImageRgba OffscreenTarget::read(const gpu::Image& image) const
{
    std::vector<std::byte> bytes = gpu::read_image(*device_, image, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    io::ImageRgba out;
    out.width = width_;
    out.height = height_;
    out.pixels.resize(size_t(width_) * height_ * 4);
    std::memcpy(out.pixels.data(), bytes.data(), bytes.size());
    return out;
}

io::ImageRgba OffscreenTarget::read_color() const
{
    return read(color_);
}
io::ImageRgba OffscreenTarget::read_aux() const
{
    return read(aux_);
}

RenderTargetDesc OffscreenTarget::desc() const
{
    RenderTargetDesc d;
    d.render_pass = render_pass_;
    d.subpass = 0;
    d.color_attachments = kColorAttachments;
    d.aux_output = true;
    return d;
}

} // namespace hemi::render
