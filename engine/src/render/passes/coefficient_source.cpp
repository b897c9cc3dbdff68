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

std::vector<float> CoefficientSource::read_coefficients() const
{
    std::vector<float> out(size_t(vertex_count()) * k() * 4);
    gpu::read_buffer(device(), coefficients(), out.data(), out.size() * sizeof(float));
    return out;
}

} // namespace hemi::render
