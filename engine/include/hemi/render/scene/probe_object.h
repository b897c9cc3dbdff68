#pragma once
// A dynamic object lit by light probes: what a lightmapped level's moving objects need, since the lightmap
// lights only the static level (io::LightProbes, render::probe_lighting). The object's mesh and materials
// are drawn through the material system with the uniform coefficient source: SH9 irradiance in world space,
// evaluated at the normal-map normal turned into world space (the "SH9 probe" material). Each of
// `instances` has its own lighting, so several copies of the object at different places can be drawn in one
// render pass.

#include <hemi/gpu/upload.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/scene_surfaces.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <memory>
#include <span>
#include <vector>

namespace hemi::render
{

class ProbeObject
{
  public:
    // The mesh, images and materials must outlive the object. Throws std::invalid_argument for no instances.
    ProbeObject(MaterialSystem& system, const io::Mesh& mesh, const std::vector<io::EncodedImage>& images,
                const std::vector<io::Material>& materials, const std::vector<io::Primitive>& primitives,
                uint32_t instances, gpu::UploadBatch& upload);
    ~ProbeObject();

    // Outside a render pass: instance `instance`'s world-space SH9 irradiance (9 RGB coefficients, e.g.
    // probe_lighting() at its position) for the draws that follow.
    void record_lighting(VkCommandBuffer cmd, uint32_t instance, std::span<const glm::vec3> sh9) const;
    // Inside the caller's render pass: instance `instance` under `model`.
    void draw(VkCommandBuffer cmd, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model) const;

    uint32_t instances() const { return uint32_t(probes_.size()); }

  private:
    SceneSurfaces surfaces_;
    std::vector<std::unique_ptr<ProbeCoefficients>> probes_;
};

} // namespace hemi::render
