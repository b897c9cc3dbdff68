#pragma once
// A normal-mapped mesh lit per pixel by SH9 irradiance (the foundation's raster pass and the seed of every
// technique's material): colour = albedo * E(n) / pi with n the normal-map normal in world space.

#include <hemi/gpu/device.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>
#include <hemi/io/mesh.h>
#include <hemi/math/sh.h>
#include <hemi/render/offscreen.h>
#include <hemi/render/surface.h>

#include <glm/mat4x4.hpp>

#include <cstdint>
#include <span>

namespace hemi::render
{

struct ShNormalMapFrame
{
    glm::mat4 view_projection{1.0f}; // Vulkan clip space (y down, depth 0..1)
    glm::mat4 model{1.0f};           // rotation, uniform scale, translation
    glm::vec3 albedo{1.0f};
    math::Sh9Rgb irradiance{};       // world-space SH9 irradiance coefficients (math::convolve_cosine output)
};

class ShNormalMapRenderer
{
public:
    // `normal_map` is RGBA8 (tangent-space, glTF convention), `map_width` x `map_height`. The mesh needs
    // normals, tangents and UVs for every vertex. Throws std::invalid_argument on inconsistent input.
    ShNormalMapRenderer(const gpu::Device& device, const OffscreenTarget& target, const io::Mesh& mesh,
                        std::span<const uint8_t> normal_map, uint32_t map_width, uint32_t map_height);

    // Records the uniform update; call outside the render pass, before target.begin().
    void update(VkCommandBuffer cmd, const ShNormalMapFrame& frame) const;
    // Records the draw; call inside target.begin()/end().
    void draw(VkCommandBuffer cmd) const;

private:
    GpuMesh mesh_;
    gpu::Image normal_map_;
    gpu::Program program_;
    gpu::Buffer uniforms_;
    gpu::Sampler sampler_;
    gpu::DescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

// A view-projection matrix (Vulkan clip space) looking from `eye` at `target`, z up.
glm::mat4 look_at_projection(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees, float aspect);

} // namespace hemi::render
