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
                         gpu::UploadBatch& upload, uint32_t frames_in_flight, const EngineGeometry* geometry)
    : surfaces_(system, mesh, images, materials, primitives, CoefficientSourceKind::Uniform,
                {SurfaceVariant{Technique::Irradiance, HEMI_BASIS_SH9, ShadingFrame::World}}, upload,
                geometry),
      probes_(system, instances, frames_in_flight)
{
}

ProbeObject::~ProbeObject() = default;

void ProbeObject::check_sh9(std::span<const glm::vec3> sh9)
{
    if (sh9.size() != 9)
        throw std::invalid_argument("hemi: a probe-lit object takes 9 SH9 coefficients, got " +
                                    std::to_string(sh9.size()));
}

void ProbeObject::write_lighting(uint32_t instance, std::span<const glm::vec3> sh9, uint32_t frame)
{
    check_sh9(sh9);
    probes_.write(frame, instance, sh9);
}

void ProbeObject::record_lighting(VkCommandBuffer cmd, uint32_t instance, std::span<const glm::vec3> sh9,
                                  uint32_t frame) const
{
    check_sh9(sh9);
    probes_.record_update(cmd, frame, instance, sh9);
}

void ProbeObject::draw(VkCommandBuffer cmd, VkDescriptorSet frame_set, uint32_t instance,
                       const glm::mat4& model, uint32_t frame, size_t pass) const
{
    surfaces_.draw(cmd, frame_set, probes_.set(), probes_.offset(frame, instance), model, 0, pass);
}

void ProbeObject::enqueue(DrawQueue& queue, VkDescriptorSet frame_set, uint32_t instance,
                          const glm::mat4& model, uint32_t frame, uint32_t layer, float depth,
                          size_t pass) const
{
    surfaces_.enqueue(queue, frame_set, probes_.set(), probes_.offset(frame, instance), model, 0, pass, layer,
                      depth);
}

void ProbeObject::enqueue_instances(DrawQueue& queue, VkDescriptorSet frame_set, InstanceRange instances,
                                    uint32_t layer, float depth, size_t pass) const
{
    if (instances.count == 0)
        throw std::invalid_argument("hemi: an instanced draw of 0 instances");
    surfaces_.enqueue(queue, frame_set, probes_.set(), 0, glm::mat4(1.0f), 0, pass, layer, depth, instances);
}

shared::DrawPush ProbeObject::instance_record(uint32_t instance, const glm::mat4& model, uint32_t frame) const
{
    shared::DrawPush r{};
    r.model = model;
    r.coefficient_offset = probes_.offset(frame, instance);
    return r;
}

} // namespace hemi::render
