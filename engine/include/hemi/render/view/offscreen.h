#pragma once
// An offscreen render target: colour (RGBA32F, linear radiance), an auxiliary RGBA32F attachment (what a
// pass chooses to expose, e.g. UVs and coverage for tests and tools) and depth (D32), with the render
// pass and framebuffer that draw into them. Headless: no swapchain anywhere.

#include <hemi/gpu/device.h>
#include <hemi/gpu/handle.h>
#include <hemi/gpu/resources.h>
#include <hemi/io/image.h>
#include <hemi/render/material/material_system.h>

#include <glm/vec4.hpp>

namespace hemi::render
{

class OffscreenTarget
{
  public:
    OffscreenTarget(const gpu::Device& device, uint32_t width, uint32_t height);

    // Begins the render pass (clearing colour to `clear`, aux to 0, depth to 1) and sets viewport/scissor.
    void begin(VkCommandBuffer cmd, const glm::vec4& clear = glm::vec4(0.0f)) const;
    void end(VkCommandBuffer cmd) const;

    VkRenderPass render_pass() const { return render_pass_; }
    // The target as the material system sees it: subpass 0, colour + aux attachments, depth LESS.
    RenderTargetDesc desc() const;
    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }
    static constexpr uint32_t kColorAttachments = 2;

    // Read back after a finished submission.
    io::ImageRgba read_color() const;
    io::ImageRgba read_aux() const;

  private:
    io::ImageRgba read(const gpu::Image& image) const;

    const gpu::Device* device_;
    uint32_t width_, height_;
    gpu::Image color_, aux_, depth_;
    gpu::RenderPass render_pass_;
    gpu::Framebuffer framebuffer_;
};

} // namespace hemi::render
