#pragma once
// Descriptor set 0 of the material system: what every draw of one view shares (camera, options, the
// separable basis's weights), updated once per frame.

#include <hemi/gpu/resources.h>
#include <hemi/render/material/material_system.h>

#include <glm/mat4x4.hpp>

namespace hemi::render
{

struct FrameData
{
    glm::mat4 view_projection{1.0f}; // Vulkan clip space (material_system.h)
    bool lighting_only = false;      // albedo 1 and no emissive: the "white" view of the lighting alone
};

class FrameSet
{
public:
    explicit FrameSet(const MaterialSystem& system);
    // Outside a render pass, once per frame: the previous frame's reads finish before the update, which
    // finishes before this frame's draws read it.
    void record_update(VkCommandBuffer cmd, const FrameData& frame) const;
    VkDescriptorSet set() const { return set_; }

private:
    gpu::Buffer uniforms_;
    gpu::DescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

// The update-with-barriers of a small uniform block read by vertex and fragment shaders (vkCmdUpdateBuffer).
void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& uniforms, const void* data, size_t size);

} // namespace hemi::render
