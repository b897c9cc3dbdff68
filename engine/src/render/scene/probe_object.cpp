// A dynamic object lit by light probes (probe_object.h).
#include <hemi/render/scene/probe_object.h>

#include <stdexcept>
#include <string>

namespace hemi::render
{

ProbeObject::ProbeObject(MaterialSystem& system, const io::Mesh& mesh,
                         const std::vector<io::EncodedImage>& images,
                         const std::vector<io::Material>& materials,
                         const std::vector<io::Primitive>& primitives, uint32_t instances,
                         gpu::UploadBatch& upload)
    : surfaces_(system, mesh, images, materials, primitives, CoefficientSourceKind::Uniform,
                {SurfaceVariant{Technique::Irradiance, HEMI_BASIS_SH9, ShadingFrame::World}}, upload)
{
    if (instances == 0)
        throw std::invalid_argument("hemi: a probe-lit object needs at least one instance");
    for (uint32_t i = 0; i < instances; ++i)
        probes_.push_back(std::make_unique<ProbeCoefficients>(system));
}

ProbeObject::~ProbeObject() = default;

void ProbeObject::record_lighting(VkCommandBuffer cmd, uint32_t instance,
                                  std::span<const glm::vec3> sh9) const
{
    if (instance >= probes_.size())
        throw std::invalid_argument("hemi: probe-lit instance " + std::to_string(instance) + " of " +
                                    std::to_string(probes_.size()));
    if (sh9.size() != 9)
        throw std::invalid_argument("hemi: a probe-lit object takes 9 SH9 coefficients, got " +
                                    std::to_string(sh9.size()));
    probes_[instance]->record_update(cmd, sh9);
}

void ProbeObject::draw(VkCommandBuffer cmd, VkDescriptorSet frame, uint32_t instance,
                       const glm::mat4& model) const
{
    if (instance >= probes_.size())
        throw std::invalid_argument("hemi: probe-lit instance " + std::to_string(instance) + " of " +
                                    std::to_string(probes_.size()));
    surfaces_.draw(cmd, frame, probes_[instance]->set(), 0, model);
}

} // namespace hemi::render
