// A dynamic object lit by light probes (probe_object.h).
#include "../refuse.h"

#include <hemi/render/scene/probe_object.h>

#include <cmath>

#include <stdexcept>
#include <string>

namespace hemi::render
{

ProbeObject::ProbeObject(MaterialSystem& system, const io::Mesh& mesh,
                         const std::vector<io::EncodedImage>& images,
                         const std::vector<io::Material>& materials,
                         const std::vector<io::Primitive>& primitives, uint32_t instances,
                         gpu::UploadBatch& upload, uint32_t frames_in_flight, const EngineGeometry* geometry)
    : device_(&system.device()),
      surfaces_(system, mesh, images, materials, primitives, CoefficientSourceKind::Uniform,
                {SurfaceVariant{Technique::Irradiance, HEMI_BASIS_SH9, ShadingFrame::World}}, upload,
                geometry),
      probes_(system, instances, frames_in_flight)
{
}

ProbeObject::~ProbeObject() = default;

bool ProbeObject::check(const char* call, uint32_t instance, uint32_t frame) const noexcept
{
    if (instance >= probes_.probes() || frame >= probes_.frames_in_flight())
        return detail::refuse(*device_, call,
                              "instance %u of frame slot %u: the object has %u instance(s) and %u "
                              "frame(s) in flight",
                              instance, frame, probes_.probes(), probes_.frames_in_flight());
    return true;
}

bool ProbeObject::check_sh9(const char* call, std::span<const glm::vec3> sh9,
                            const ProbeBuffer::Occlusion& occlusion) const noexcept
{
    for (float o : occlusion)
        if (!(o >= 0.0f && o <= 1.0f))
            return detail::refuse(*device_, call, "the mixed lights' occlusion must be in [0, 1]");
    if (sh9.size() != 9)
        return detail::refuse(*device_, call, "a probe-lit object takes 9 SH9 coefficients, got %zu",
                              sh9.size());
    for (size_t i = 0; i < sh9.size(); ++i)
        if (!std::isfinite(sh9[i].x + sh9[i].y + sh9[i].z))
            return detail::refuse(*device_, call, "SH9 coefficient %zu is not finite", i);
    return true;
}

bool ProbeObject::write_lighting(uint32_t instance, std::span<const glm::vec3> sh9, uint32_t frame,
                                 const ProbeBuffer::Occlusion& occlusion) noexcept
{
    if (!check("ProbeObject::write_lighting", instance, frame) ||
        !check_sh9("ProbeObject::write_lighting", sh9, occlusion))
        return false;
    probes_.write(frame, instance, sh9, occlusion);
    return true;
}

bool ProbeObject::record_lighting(VkCommandBuffer cmd, uint32_t instance, std::span<const glm::vec3> sh9,
                                  uint32_t frame, const ProbeBuffer::Occlusion& occlusion) const noexcept
{
    if (!check("ProbeObject::record_lighting", instance, frame) ||
        !check_sh9("ProbeObject::record_lighting", sh9, occlusion))
        return false;
    probes_.record_update(cmd, frame, instance, sh9, occlusion);
    return true;
}

bool ProbeObject::draw(VkCommandBuffer cmd, VkDescriptorSet frame_set, uint32_t instance,
                       const glm::mat4& model, uint32_t frame, size_t pass) const noexcept
{
    if (!check("ProbeObject::draw", instance, frame) ||
        !surfaces_.check("ProbeObject::draw", frame_set, probes_.set(), 0, pass))
        return false;
    return surfaces_.draw(cmd, frame_set, probes_.set(), probes_.offset(frame, instance), model, 0, pass);
}

bool ProbeObject::enqueue(DrawQueue& queue, VkDescriptorSet frame_set, uint32_t instance,
                          const glm::mat4& model, uint32_t frame, uint32_t layer, float depth,
                          size_t pass) const noexcept
{
    if (!check("ProbeObject::enqueue", instance, frame) ||
        !surfaces_.check("ProbeObject::enqueue", frame_set, probes_.set(), 0, pass))
        return false;
    return surfaces_.enqueue(queue, frame_set, probes_.set(), probes_.offset(frame, instance), model, 0, pass,
                             layer, depth);
}

bool ProbeObject::enqueue_instances(DrawQueue& queue, VkDescriptorSet frame_set, InstanceRange instances,
                                    uint32_t layer, float depth, size_t pass) const noexcept
{
    if (instances.count == 0)
        return detail::refuse(*device_, "ProbeObject::enqueue_instances", "an instanced draw of 0 instances");
    if (!surfaces_.check("ProbeObject::enqueue_instances", frame_set, probes_.set(), 0, pass))
        return false;
    return surfaces_.enqueue(queue, frame_set, probes_.set(), 0, glm::mat4(1.0f), 0, pass, layer, depth,
                             instances);
}

shared::DrawPush ProbeObject::instance_record(uint32_t instance, const glm::mat4& model,
                                              uint32_t frame) const noexcept
{
    shared::DrawPush r{};
    r.model = glm::mat4(0.0f);
    if (!check("ProbeObject::instance_record", instance, frame))
        return r;
    r.model = model;
    r.coefficient_offset = probes_.offset(frame, instance);
    return r;
}

} // namespace hemi::render
