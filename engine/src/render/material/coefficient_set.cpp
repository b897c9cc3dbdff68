#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>

#include <glm/vec4.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::render
{

VertexCoefficients::VertexCoefficients(const MaterialSystem& system, const gpu::Buffer& coefficients, uint64_t texels)
{
    const gpu::Device& device = system.device();
    if (texels == 0 || texels * 16 > coefficients.size())
        throw std::invalid_argument("hemi: " + std::to_string(texels) + " coefficient texels do not fit a buffer of " +
                                    std::to_string(coefficients.size()) + " bytes");
    if (texels > device.limits().maxTexelBufferElements)
        throw std::invalid_argument("hemi: " + std::to_string(texels) + " coefficient texels exceed the device's "
                                    "maxTexelBufferElements (" + std::to_string(device.limits().maxTexelBufferElements) + ")");
    view_ = gpu::create_buffer_view(device, coefficients, VK_FORMAT_R32G32B32A32_SFLOAT, 0, texels * 16);
    const auto bindings = MaterialSystem::source_bindings(CoefficientSourceKind::Vertex);
    pool_ = gpu::create_descriptor_pool(device, bindings, 1);
    set_ = gpu::allocate_descriptor_set(device, pool_, system.source_layout(CoefficientSourceKind::Vertex));
    gpu::DescriptorWrite write;
    write.binding = HEMI_SOURCE_BINDING_COEFFICIENTS;
    write.type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    write.texel_view = view_;
    gpu::write_descriptors(device, set_, {&write, 1});
}

ProbeCoefficients::ProbeCoefficients(const MaterialSystem& system)
{
    const gpu::Device& device = system.device();
    uniforms_ = gpu::create_buffer(device, {HEMI_BASIS_MAX_SIZE * 16, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    const auto bindings = MaterialSystem::source_bindings(CoefficientSourceKind::Uniform);
    pool_ = gpu::create_descriptor_pool(device, bindings, 1);
    set_ = gpu::allocate_descriptor_set(device, pool_, system.source_layout(CoefficientSourceKind::Uniform));
    gpu::DescriptorWrite write;
    write.binding = HEMI_SOURCE_BINDING_COEFFICIENTS;
    write.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    write.buffer = {uniforms_, 0, VK_WHOLE_SIZE};
    gpu::write_descriptors(device, set_, {&write, 1});
}

void ProbeCoefficients::record_update(VkCommandBuffer cmd, std::span<const glm::vec3> coefficients) const
{
    if (coefficients.size() > HEMI_BASIS_MAX_SIZE)
        throw std::invalid_argument("hemi: a probe holds at most " + std::to_string(HEMI_BASIS_MAX_SIZE) +
                                    " coefficients, got " + std::to_string(coefficients.size()));
    glm::vec4 packed[HEMI_BASIS_MAX_SIZE] = {};
    for (size_t i = 0; i < coefficients.size(); ++i)
    {
        const glm::vec3& c = coefficients[i];
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
            throw std::invalid_argument("hemi: probe coefficient " + std::to_string(i) + " is not finite");
        packed[i] = glm::vec4(c, 0.0f);
    }
    record_uniform_update(cmd, uniforms_, packed, sizeof packed);
}

} // namespace hemi::render
