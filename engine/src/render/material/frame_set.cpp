#include <hemi/gpu/commands.h>
#include <hemi/math/separable_basis.h>
#include <hemi/render/material/frame_set.h>

namespace hemi::render
{

void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& uniforms, const void* data, size_t size)
{
    const VkPipelineStageFlags shaders = VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT;
    gpu::memory_barrier(cmd, shaders, VK_ACCESS_UNIFORM_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_TRANSFER_WRITE_BIT);
    vkCmdUpdateBuffer(cmd, uniforms, 0, size, data);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, shaders,
                        VK_ACCESS_UNIFORM_READ_BIT);
}

FrameSet::FrameSet(const MaterialSystem& system)
{
    const gpu::Device& device = system.device();
    uniforms_ = gpu::create_buffer(device, {sizeof(shared::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    const auto bindings = MaterialSystem::frame_bindings();
    pool_ = gpu::create_descriptor_pool(device, bindings, 1);
    set_ = gpu::allocate_descriptor_set(device, pool_, system.frame_layout());
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
    u.options = glm::vec4(frame.lighting_only ? 1.0f : 0.0f, 0.0f, 0.0f, 0.0f);
    const auto& w = math::sep4_weights();
    for (int j = 0; j < 9; ++j)
        u.sep4_weights[j] = glm::vec4(w[j * 4], w[j * 4 + 1], w[j * 4 + 2], w[j * 4 + 3]);
    record_uniform_update(cmd, uniforms_, &u, sizeof u);
}

} // namespace hemi::render
