#include <hemi/gpu/commands.h>
#include <hemi/render/passes/coefficient_source.h>

namespace hemi::render
{

void CoefficientSource::run(std::span<const glm::vec3> lighting)
{
    gpu::one_shot(device(),
                  [&](VkCommandBuffer cmd)
                  {
                      record(cmd, lighting);
                      // A fence wait alone does not make device writes visible to the host.
                      gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                          VK_ACCESS_SHADER_WRITE_BIT,
                                          VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                          VK_ACCESS_HOST_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT);
                  });
}

BufferAccess CoefficientSource::coefficient_access(uint32_t first, uint32_t count,
                                                   VkPipelineStageFlags stages, VkAccessFlags access) const
{
    const VkDeviceSize stride = instance_stride() * 16;
    const gpu::BufferRange range = coefficients();
    return {range.buffer, range.offset + first * stride, count * stride, stages, access};
}

std::vector<float> CoefficientSource::read_coefficients() const
{
    std::vector<float> out(size_t(vertex_count()) * k() * 4);
    const gpu::BufferRange range = coefficients();
    gpu::read_buffer(device(), {range.buffer, range.offset, out.size() * sizeof(float)}, out.data());
    return out;
}

} // namespace hemi::render
