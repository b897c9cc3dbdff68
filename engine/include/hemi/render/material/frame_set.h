#pragma once
// Descriptor set 0 of the material system: what every draw of one view shares (camera, options, the
// separable basis's weights), updated once per frame.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/render/material/material_system.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <vector>

namespace hemi::render
{

// A dynamic light, added to the precomputed lighting by the techniques that take dynamic lights (rnm, rnm_ao
// and ssbump: Green 2007 projects them onto Valve's three directions). World space, z up.
struct DynamicLight
{
    bool point = false; // false: directional
    glm::vec3 position{0.0f, 0.0f,
                       1.0f}; // a point light's position, or the direction towards a directional one
    glm::vec3 irradiance{
        1.0f}; // on a surface facing it (a point light's at distance 1, falling off as 1 / d^2)
};

struct FrameData
{
    glm::mat4 view_projection{1.0f};  // Vulkan clip space (material_system.h)
    bool lighting_only = false;       // albedo 1 and no emissive: the "white" view of the lighting alone
    glm::vec3 eye{0.0f};              // the camera's position (world): the view direction of specular terms
    std::vector<DynamicLight> lights; // at most HEMI_MAX_LIGHTS (std::invalid_argument else)
    // The dynamic lights' specular term (normalised Blinn-Phong, (m + 8) / (8 pi) (n.h)^m (n.l) E, at the
    // technique's normal): exponent m and strength (0: none). A stand-in for per-material gloss.
    float specular_exponent = 32.0f; // > 0
    float specular_strength = 0.0f;
};

class FrameSet
{
  public:
    explicit FrameSet(const MaterialSystem& system);
    // Outside a render pass, once per frame: the previous frame's reads finish before the update, which
    // finishes before this frame's draws read it.
    void record_update(VkCommandBuffer cmd, const FrameData& frame) const;
    VkDescriptorSet set() const { return set_.get(); }

  private:
    gpu::Buffer uniforms_;
    gpu::DescriptorSet set_;
};

// The update-with-barriers of a small uniform block read by vertex and fragment shaders (vkCmdUpdateBuffer).
void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& uniforms, const void* data, size_t size);

} // namespace hemi::render
