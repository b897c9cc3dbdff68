#pragma once
// A baked PRT asset on the GPU, drawn through the material system: the mesh, the scene's textures and
// material instances (one per glTF material), and one technique's transfer matrices (dense or CPCA), all
// shared by every instance of the model. Each instance is an object with its own transform: the library
// rotates the distant lighting into its object space, and the coefficient pass relights every instance
// from the one copy of the matrices.
//
// Conventions: hemi's world is z up; baked assets are in glTF's y-up scene space and are usually placed in
// the world by gltf_to_world() (glTF +y becomes world +z). Lighting is world-space SH
// (math/sh_environment.h).

#include <hemi/gpu/upload.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/basis.h>
#include <hemi/render/access.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/scene/scene_surfaces.h>
#include <hemi/render/transfer.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <hemi/math/camera.h>
#include <memory>

#include <span>
#include <string>
#include <vector>

namespace hemi::render
{

// The rotation placing glTF's y-up space in hemi's z-up world (math/camera.h).
using math::gltf_to_world;

// `world_lighting` (SH of order >= `order`, truncated) turned by `rotate_degrees` about world z, then seen
// in the object frame of `model` (a rotation, uniform scale and translation): what that object's transfer
// matrices multiply.
std::vector<glm::vec3> object_lighting(std::span<const glm::vec3> world_lighting, int order,
                                       const glm::mat4& model, float rotate_degrees = 0.0f);

struct PrtModelDesc
{
    std::string technique = "gs"; // math::technique() names: gs, prt, hl2, sal4, h4, h6, sep4, ...
    bool cpca = false;            // the technique's CPCA data instead of the dense matrices
    uint32_t instances = 1;       // objects relit per frame from this model
    // Frames the engine keeps in flight: each slot has its own lighting and coefficients of every instance,
    // so the transfer pass of frame N+1 never overwrites what frame N's draws read (the two overlap when the
    // transfer is recorded on a compute queue; on one queue its first barrier waits for earlier work).
    uint32_t frames_in_flight = 1;
    // Where the transfer pass writes the coefficients: a range of the engine's own buffer, so that its vertex
    // shaders read them as one more vertex stream (coefficient_stream()). It holds coefficient_bytes() from
    // an offset aligned to 16 and minTexelBufferOffsetAlignment; the buffer has STORAGE_TEXEL_BUFFER usage
    // (the pass writes it), UNIFORM_TEXEL_BUFFER when hemi's materials draw the model, VERTEX_BUFFER for the
    // engine's stream. Null (the default): a buffer of hemi's own.
    gpu::BufferRange coefficient_output;
    // The engine's own vertex and index buffers to draw from (EngineGeometry; kept alive by the caller while
    // the model draws): hemi then uploads no vertex or index data. Null: hemi's copy of the asset's mesh.
    const EngineGeometry* geometry = nullptr;
};

// One object drawn from a model, per frame.
struct PrtInstance
{
    glm::mat4 model = gltf_to_world();
    std::span<const glm::vec3> world_lighting; // world-space SH of the asset's order or higher
    float rotate_degrees = 0.0f;               // the environment turns about world z
};

class PrtModel
{
  public:
    // Everything the model draws is uploaded (or copied into `upload`) here: the asset may be freed once the
    // model is made. Compiles (or finds in `system`) the material type of every primitive.
    // Uploads go into `upload` (record it, or submit_and_wait(), before the first frame). Throws
    // std::invalid_argument when the asset lacks the technique (or its CPCA data), io::FormatError when one
    // of its images is corrupt.
    PrtModel(MaterialSystem& system, const io::PrtAsset& asset, const PrtModelDesc& desc,
             gpu::UploadBatch& upload);
    ~PrtModel();

    // The calls from here to instance_record() are on the frame path: none throws or allocates. A bad
    // argument (a frame slot or instance out of range, a pass that was not added, too little or non-finite
    // lighting, a singular model matrix, a released frame set) is reported through the device's log callback
    // and the call records and writes nothing and returns false (docs/engine.md, "Errors").

    // record_transfer uses a lighting buffer of the model's: one thread records a model's transfers at a
    // time.

    // The engine's path, outside a render pass: the lighting of instances.size() <= desc.instances objects
    // rotated into their frames and written through mapped memory into frame slot `frame` (< desc.
    // frames_in_flight; the GPU must be done with the frame that last used the slot), and the coefficient
    // pass recorded. hemi records no barrier (a CPCA model: one, inside its pass, access.h) and no buffer
    // update: `accesses` receives what the pass reads and writes on the device (the slot's coefficients
    // written by the compute stage, coefficient_range(frame)), and draw_accesses() what the slot's draws
    // read. The engine orders the pass after earlier uses of the slot's coefficients and before the draws
    // (its render graph's barriers, or a queue-family release to the graphics queue when the pass runs on
    // a compute queue: docs/integration.md).
    bool record_transfer(VkCommandBuffer cmd, std::span<const PrtInstance> instances, uint32_t frame,
                         AccessList& accesses) noexcept;
    // The same with object-space lighting the caller computed (L per instance, instance i's at i * L).
    bool record_transfer_object_space(VkCommandBuffer cmd, std::span<const glm::vec3> object_lighting,
                                      uint32_t frame, AccessList& accesses) noexcept;
    // What the draws of frame slot `frame` read on the device: the slot's coefficients, by the vertex shader
    // stage (hemi's materials), or with `as_stream` by the vertex input stage (the engine's own draws of
    // coefficient_stream()). Appended to `accesses`, or returned.
    bool draw_accesses(uint32_t frame, AccessList& accesses, bool as_stream = false) const noexcept;
    AccessList draw_accesses(uint32_t frame) const noexcept;
    // The same work with hemi's own barriers, for callers without a render graph (tools, tests, a frame
    // recorded and submitted at once): one before (earlier reads and writes of the slot's coefficients, any
    // stage of this queue) and, with `to_vertex_shaders`, one after (to the vertex shaders that read them).
    // On a compute-only queue the barrier after names the vertex stage, which such a queue does not have:
    // pass false there and release the coefficients to the graphics queue.
    bool record_transfer(VkCommandBuffer cmd, std::span<const PrtInstance> instances, uint32_t frame = 0,
                         bool to_vertex_shaders = true) noexcept;
    bool record_transfer_object_space(VkCommandBuffer cmd, std::span<const glm::vec3> object_lighting,
                                      uint32_t frame = 0, bool to_vertex_shaders = true) noexcept;
    // Inside the caller's render pass (viewport and scissor set): every primitive of instance `instance`
    // with its own material, under `model`, with the frame set of this view. Primitive p is draw id p + 1 in
    // the aux attachment. `pass`: an index from add_pass (0: the system's default colour pass, when it has
    // one). `frame_slot`: whose coefficients (record_transfer's `frame`).
    bool draw(VkCommandBuffer cmd, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model,
              size_t pass = 0, uint32_t frame_slot = 0) const noexcept;
    // The same as draw packets (draw_queue.h), keyed by `layer` and `depth`.
    bool enqueue(DrawQueue& queue, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model,
                 size_t pass = 0, uint32_t frame_slot = 0, uint32_t layer = 0,
                 float depth = 0.0f) const noexcept;
    // Instanced: instances.count instances of the model in one draw per primitive, instance i with the
    // frame set's record instances.first + i (FrameSet::write_instances of instance_record()s).
    bool enqueue_instances(DrawQueue& queue, VkDescriptorSet frame, InstanceRange instances, size_t pass = 0,
                           uint32_t layer = 0, float depth = 0.0f) const noexcept;
    // The instance record of instance `instance` under `model`, lit by frame slot `frame_slot`'s
    // coefficients: what an instanced draw reads where draw() would push. Refused: a record with a zero
    // model matrix, which draws nothing.
    shared::DrawPush instance_record(uint32_t instance, const glm::mat4& model,
                                     uint32_t frame_slot = 0) const noexcept;
    // The bytes of PrtModelDesc::coefficient_output a model of `asset` made with `desc` writes (every
    // instance of every frame slot) on `device`. Throws as the constructor does for a technique the asset
    // lacks.
    static VkDeviceSize coefficient_bytes(const gpu::Device& device, const io::PrtAsset& asset,
                                          const PrtModelDesc& desc);
    // Instance `instance`'s coefficients of frame slot `frame` as a vertex stream: vertex v's K RGBA32F
    // attributes (k = 0 .. K - 1, at byte k * 16) at `offset` + v * stride(), stride() = K * 16. Bind with
    // vkCmdBindVertexBuffers(buffer, offset) at input rate VERTEX. Its accesses are draw_accesses()'s, at the
    // VERTEX_INPUT stage with VERTEX_ATTRIBUTE_READ instead.
    gpu::BufferRange coefficient_stream(uint32_t instance, uint32_t frame = 0) const;
    uint32_t coefficient_stride() const { return uint32_t(basis_->size) * 16; }
    uint32_t frames_in_flight() const { return frames_; }
    uint32_t instances() const { return instances_; }
    // The coefficient buffer's range frame slot `frame` writes and draws read (bytes): what an engine's
    // render graph names in a buffer barrier or a queue-family ownership transfer.
    using BufferRange = gpu::BufferRange;
    BufferRange coefficient_range(uint32_t frame) const;
    // Another pass of the caller's frame (a depth prepass, a shadow map; SceneSurfaces::add_pass).
    size_t add_pass(const PassDesc& pass) { return surfaces_.add_pass(pass); }

    CoefficientSource& coefficients() { return *source_; }
    // The asset's lighting order and L = order^2 (what record_transfer_object_space takes per instance).
    uint32_t order() const { return order_; }
    uint32_t l() const { return order_ * order_; }
    const math::BasisDesc& basis() const { return *basis_; }
    // hemi's copy of the mesh (std::logic_error with PrtModelDesc::geometry).
    const GpuMesh& mesh() const { return surfaces_.mesh(); }
    // The primitives, materials and textures, for an engine's own shaders (docs/integration.md).
    const SceneSurfaces& surfaces() const { return surfaces_; }
    size_t material_count() const { return surfaces_.material_count(); }

  private:
    uint32_t first_instance(uint32_t frame) const;
    bool check_slot(const char* call, uint32_t frame) const noexcept;
    bool check_lighting(const char* call, std::span<const glm::vec3> lighting, uint32_t frame) const noexcept;
    bool check_instance(const char* call, uint32_t instance, uint32_t frame) const noexcept;
    bool lighting_of(std::span<const PrtInstance> instances) noexcept; // into lighting_
    void record_with_barriers(VkCommandBuffer cmd, std::span<const glm::vec3> lighting, uint32_t frame,
                              bool to_vertex_shaders) noexcept;
    MaterialSystem* system_;
    std::vector<glm::vec3> lighting_; // record_transfer's object-space lighting: desc.instances * L
    uint32_t instances_ = 1, frames_ = 1, order_ = 3;
    const math::BasisDesc* basis_;
    SceneSurfaces surfaces_;
    std::unique_ptr<CoefficientSource> source_;
    std::unique_ptr<VertexCoefficients> coefficient_set_;
};

} // namespace hemi::render
