#include <hemi/gpu/commands.h>
#include <hemi/math/separable_basis.h>
#include <hemi/render/material/frame_set.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::render
{

void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& uniforms, const void* data, size_t size)
{
    const VkPipelineStageFlags shaders =
        VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT;
    gpu::memory_barrier(cmd, shaders, VK_ACCESS_UNIFORM_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_TRANSFER_WRITE_BIT);
    vkCmdUpdateBuffer(cmd, uniforms, 0, size, data);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, shaders,
                        VK_ACCESS_UNIFORM_READ_BIT);
}

FrameSet::FrameSet(const MaterialSystem& system)
{
    const gpu::Device& device = system.device();
    uniforms_ =
        gpu::create_buffer(device, {sizeof(shared::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    device.set_name(VK_OBJECT_TYPE_BUFFER, uniforms_.handle(), "hemi frame uniforms");
    const auto bindings = MaterialSystem::frame_bindings();
    set_ = system.descriptors().allocate(system.frame_layout(), bindings);
    gpu::DescriptorWrite write;
    write.binding = HEMI_FRAME_BINDING_UNIFORMS;
    write.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    write.buffer = {uniforms_, 0, VK_WHOLE_SIZE};
    gpu::write_descriptors(device, set_, {&write, 1});
}

void FrameSet::record_update(VkCommandBuffer cmd, const FrameData& frame) const
{
    shared::FrameUniforms u{};
    u.view_projection = frame.view_projection;
    if (frame.lights.size() > HEMI_MAX_LIGHTS)
        throw std::invalid_argument("hemi: at most " + std::to_string(HEMI_MAX_LIGHTS) +
                                    " dynamic lights, got " + std::to_string(frame.lights.size()));
    if (!(frame.specular_exponent > 0.0f) || !std::isfinite(frame.specular_exponent) ||
        !std::isfinite(frame.specular_strength))
        throw std::invalid_argument(
            "hemi: the specular exponent and strength must be finite, the exponent > 0");
    u.options = glm::vec4(frame.lighting_only ? 1.0f : 0.0f, float(frame.lights.size()),
                          frame.specular_exponent, frame.specular_strength);
    u.eye = glm::vec4(frame.eye, 1.0f);
    for (size_t i = 0; i < frame.lights.size(); ++i)
    {
        const DynamicLight& l = frame.lights[i];
        const bool finite = std::isfinite(l.position.x + l.position.y + l.position.z) &&
                            std::isfinite(l.irradiance.x + l.irradiance.y + l.irradiance.z);
        if (!finite || (!l.point && !(glm::length(l.position) > 0.0f)))
            throw std::invalid_argument("hemi: dynamic light " + std::to_string(i) +
                                        " is not finite or has no direction");
        u.light_position[i] =
            glm::vec4(l.point ? l.position : glm::normalize(l.position), l.point ? 1.0f : 0.0f);
        u.light_irradiance[i] = glm::vec4(l.irradiance, 0.0f);
    }
    const auto& w = math::sep4_weights();
    for (int j = 0; j < 9; ++j)
        u.sep4_weights[j] = glm::vec4(w[j * 4], w[j * 4 + 1], w[j * 4 + 2], w[j * 4 + 3]);
    record_uniform_update(cmd, uniforms_, &u, sizeof u);
}

} // namespace hemi::render
