#pragma once
// What every view of a baked asset into hemi's own target shares (PrtView, LightmapView): the offscreen
// target, a material system for it, the frame set (camera and lighting-only flag), the camera's framing of
// the asset's bounds, and the read-back of a frame with alpha = coverage.

#include <hemi/gpu/device.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/math/camera.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/view/offscreen.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace hemi::render
{

using PrtCamera = math::Camera; // math/camera.h

class ViewTarget
{
  public:
    ViewTarget(const gpu::Device& device, uint32_t width, uint32_t height);

    // Outside a render pass: the frame set for `camera` looking at `mesh` under `model` (near and far planes
    // around its bounds, which are recomputed only when `model` changes), albedo 1 when `white`.
    // `lighting` carries the dynamic lights and their specular term (its view_projection, eye and
    // lighting_only are set here).
    void record_frame(VkCommandBuffer cmd, const PrtCamera& camera, const io::Mesh& mesh,
                      const glm::mat4& model, bool white, const FrameData& lighting = {});
    // The target's colour with alpha = coverage (1 where the asset is), after a submitted frame.
    io::ImageRgba read() const;

    const OffscreenTarget& target() const { return target_; }
    MaterialSystem& system() { return system_; }
    VkDescriptorSet frame() const { return frame_set_.set(); }
    const gpu::Device& device() const { return *device_; }

  private:
    const gpu::Device* device_;
    OffscreenTarget target_;
    MaterialSystem system_;
    FrameSet frame_set_;
    glm::vec3 bounds_centre_{0.0f};
    float bounds_radius_ = 1.0f;
    glm::mat4 bounds_model_{1.0f};
    bool bounds_valid_ = false;
};

} // namespace hemi::render
