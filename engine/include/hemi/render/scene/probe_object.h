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
    // The mesh, images and materials are uploaded or copied here (they may be freed afterwards). Each of
    // `instances` gets its probe in a buffer of `frames_in_flight` slots (ProbeBuffer). Throws
    // std::invalid_argument for no instances or frames. With `geometry` it draws from the engine's own vertex
    // and index buffers (EngineGeometry; `mesh` then only gives the bounds): hemi uploads no geometry.
    ProbeObject(MaterialSystem& system, const io::Mesh& mesh, const std::vector<io::EncodedImage>& images,
                const std::vector<io::Material>& materials, const std::vector<io::Primitive>& primitives,
                uint32_t instances, gpu::UploadBatch& upload, uint32_t frames_in_flight = 1,
                const EngineGeometry* geometry = nullptr);
    ~ProbeObject();

    // The calls below are on the frame path: none throws or allocates. A bad argument (an instance, frame
    // slot or pass out of range, lighting that is not 9 finite coefficients, a released frame set) is
    // reported through the device's log callback and the call writes and records nothing and returns false
    // (docs/engine.md, "Errors").

    // Instance `instance`'s world-space SH9 irradiance (9 RGB coefficients, e.g. probe_lighting() at its
    // position) in frame slot `frame`, through mapped memory (no command; ProbeBuffer::write's contract), and
    // its occlusion of the level's mixed lights (probe_lighting()'s; in [0, 1]): the frame's mixed lights
    // light it times their channel of it.
    bool write_lighting(uint32_t instance, std::span<const glm::vec3> sh9, uint32_t frame = 0,
                        const ProbeBuffer::Occlusion& occlusion = {1.0f, 1.0f, 1.0f, 1.0f}) noexcept;
    // Outside a render pass: the same, recorded in the command buffer (ProbeBuffer::record_update).
    bool record_lighting(VkCommandBuffer cmd, uint32_t instance, std::span<const glm::vec3> sh9,
                         uint32_t frame = 0,
                         const ProbeBuffer::Occlusion& occlusion = {1.0f, 1.0f, 1.0f, 1.0f}) const noexcept;
    // Another pass of the caller's frame (a depth prepass, a shadow map, a colour pass into another target;
    // SceneSurfaces::add_pass): its index for draw() and enqueue(). 0 is the system's default colour pass,
    // when it has one.
    size_t add_pass(const PassDesc& pass) { return surfaces_.add_pass(pass); }

    // Inside the caller's render pass: instance `instance` under `model` with its lighting of slot `frame`,
    // with the pipelines of `pass` (add_pass).
    bool draw(VkCommandBuffer cmd, VkDescriptorSet frame_set, uint32_t instance, const glm::mat4& model,
              uint32_t frame = 0, size_t pass = 0) const noexcept;

    // The same as draw packets (draw_queue.h), keyed by `layer` and `depth`.
    bool enqueue(DrawQueue& queue, VkDescriptorSet frame_set, uint32_t instance, const glm::mat4& model,
                 uint32_t frame = 0, uint32_t layer = 0, float depth = 0.0f, size_t pass = 0) const noexcept;

    // Instanced: instances.count copies in one draw per primitive, copy i with the frame set's record
    // instances.first + i (FrameSet::write_instances of instance_record()s).
    bool enqueue_instances(DrawQueue& queue, VkDescriptorSet frame_set, InstanceRange instances,
                           uint32_t layer = 0, float depth = 0.0f, size_t pass = 0) const noexcept;
    // The record of instance `instance` under `model`, lit by its probe of slot `frame` (refused: a zero
    // model matrix, which draws nothing).
    shared::DrawPush instance_record(uint32_t instance, const glm::mat4& model,
                                     uint32_t frame = 0) const noexcept;

    uint32_t instances() const { return probes_.probes(); }
    const ProbeBuffer& probes() const { return probes_; }
    const SceneSurfaces& surfaces() const { return surfaces_; }

  private:
    bool check(const char* call, uint32_t instance, uint32_t frame) const noexcept;
    bool check_sh9(const char* call, std::span<const glm::vec3> sh9,
                   const ProbeBuffer::Occlusion& occlusion) const noexcept;
    const gpu::Device* device_;
    SceneSurfaces surfaces_;
    ProbeBuffer probes_;
};

} // namespace hemi::render
