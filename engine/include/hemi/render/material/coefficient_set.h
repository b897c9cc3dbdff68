#pragma once
// Descriptor set 2 of the material system: where one object instance's coefficients come from.
//   VertexCoefficients: a transfer or CPCA pass's output buffer (per vertex; shared::DrawPush carries the
//                       instance's texel offset into it).
//   ProbeCoefficients:  one set of K RGB coefficients for the whole object (an SH9 irradiance probe in
//                       world space, say), updated per frame.

#include <hemi/gpu/resources.h>
#include <hemi/render/material/material_system.h>

#include <glm/vec3.hpp>

#include <span>

namespace hemi::render
{

class VertexCoefficients
{
public:
    // Views `texels` RGBA32F texels of `coefficients` from its start (every instance of a multi-instance
    // source; draws pick theirs by shared::DrawPush::coefficient_offset). The buffer must outlive this.
    VertexCoefficients(const MaterialSystem& system, const gpu::Buffer& coefficients, uint64_t texels);
    VkDescriptorSet set() const { return set_; }

private:
    gpu::BufferView view_;
    gpu::DescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

class ProbeCoefficients
{
public:
    explicit ProbeCoefficients(const MaterialSystem& system);
    // Outside a render pass: up to HEMI_BASIS_MAX_SIZE RGB coefficients (finite; std::invalid_argument else).
    void record_update(VkCommandBuffer cmd, std::span<const glm::vec3> coefficients) const;
    VkDescriptorSet set() const { return set_; }

private:
    gpu::Buffer uniforms_;
    gpu::DescriptorPool pool_;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

} // namespace hemi::render
