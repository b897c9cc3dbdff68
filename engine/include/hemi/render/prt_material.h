#pragma once
// The PRT material of Sloan 2006: per-vertex basis coefficients (the transfer pass's output, already in each
// vertex's tangent frame) interpolated across triangles, the basis evaluated per pixel at the normal-map
// normal, times albedo / pi. One material for every basis: the basis is a specialization constant; the
// coefficients come from any CoefficientSource (dense transfer pass or CPCA).

#include <hemi/gpu/device.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/math/basis.h>
#include <hemi/render/offscreen.h>
#include <hemi/render/surface.h>
#include <hemi/render/transfer.h>

#include <glm/mat4x4.hpp>

namespace hemi::render
{

struct PrtMaterialFrame
{
    glm::mat4 view_projection{1.0f};
    glm::mat4 model{1.0f};
    glm::vec3 albedo{1.0f};       // multiplies the base colour texture
    bool use_base_color = true;   // false (with albedo 1) for the lighting-only ("white") view
};

class PrtMaterialRenderer
{
public:
    // `coefficients` must come from matrices of `basis.size` rows over the same vertices as `mesh`; it must
    // outlive the renderer. `normal_map` is a tangent-space RGBA8 map (glTF convention); `base_color` an
    // sRGB RGBA8 texture, or null for white. Throws std::invalid_argument on a mismatch.
    // `pass` is where draw() will record: hemi's OffscreenTarget (surface_pass(target)) or a subpass of
    // the engine's own render pass (render/surface.h says what the material writes there).
    PrtMaterialRenderer(const gpu::Device& device, const SurfacePass& pass, const io::Mesh& mesh,
                        const io::ImageRgba8& normal_map, const io::ImageRgba8* base_color,
                        const math::BasisDesc& basis, const CoefficientSource& coefficients);
    PrtMaterialRenderer(const gpu::Device& device, const OffscreenTarget& target, const io::Mesh& mesh,
                        const io::ImageRgba8& normal_map, const io::ImageRgba8* base_color,
                        const math::BasisDesc& basis, const CoefficientSource& coefficients)
        : PrtMaterialRenderer(device, surface_pass(target), mesh, normal_map, base_color, basis, coefficients)
    {
    }

    // Outside the render pass: records the uniform update.
    void update(VkCommandBuffer cmd, const PrtMaterialFrame& frame) const;
    // Inside the render pass (target.begin()/end(), or the engine's pass with viewport and scissor set):
    // records the draw.
    void draw(VkCommandBuffer cmd) const;

private:
    GpuMesh mesh_;
    gpu::Image normal_map_, base_color_;
    gpu::Sampler sampler_;
    gpu::BufferView coefficient_view_;
    gpu::Buffer uniforms_;
    gpu::Program program_;
    gpu::DescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

} // namespace hemi::render
