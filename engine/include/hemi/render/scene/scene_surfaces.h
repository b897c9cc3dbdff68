#pragma once
// What every baked asset draws the same way: its mesh on the GPU, the scene's textures and one material
// instance per glTF material, and a draw per primitive with the material type of its key. PrtModel and
// LightmapModel differ only in where the coefficients come from (descriptor set 2) and which basis evaluates
// them.

#include <hemi/gpu/upload.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/draw_queue.h>
#include <hemi/render/scene/gpu_mesh.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <memory>
#include <vector>

namespace hemi::render
{

// One way of drawing the surfaces: the technique and the basis of its coefficients (the basis gives K).
struct SurfaceVariant
{
    Technique technique = Technique::Irradiance;
    int basis = HEMI_BASIS_SH9;
    ShadingFrame frame = ShadingFrame::Tangent; // World: coefficients in world space (an SH9 probe)
    LightmapFilter lightmap_filter = LightmapFilter::Linear;
};

class SceneSurfaces
{
  public:
    // The mesh, images and materials are uploaded or copied here (they may be freed afterwards). Compiles (or
    // finds in `system`) the material type of every primitive for `source` and each of `variants` (what a
    // draw picks from). No primitives draws the whole mesh with material 0; no materials uses glTF's default
    // one. Throws std::invalid_argument for a primitive whose material does not exist or no bases,
    // io::FormatError when an image is corrupt. A primitive past the mesh's indices is refused
    // (std::invalid_argument). With `geometry`, the surfaces draw from the engine's buffers in its layout
    // and `mesh` (the asset's, on the CPU) only gives the primitives' bounds: nothing of it is uploaded.
    SceneSurfaces(MaterialSystem& system, const io::Mesh& mesh, const std::vector<io::EncodedImage>& images,
                  const std::vector<io::Material>& materials, const std::vector<io::Primitive>& primitives,
                  CoefficientSourceKind source, const std::vector<SurfaceVariant>& variants,
                  gpu::UploadBatch& upload, const EngineGeometry* geometry = nullptr);
    ~SceneSurfaces();

    // Compiles every primitive's type for another pass of the caller's frame (a depth prepass, a shadow
    // map, a colour pass into another target) and returns its index for draw(). Pass 0 is the system's
    // default colour pass when the system has one (MaterialSystem::has_default_pass), otherwise the first
    // pass added: a system without one compiles nothing when surfaces load. The mesh, textures and materials
    // are shared by every pass.
    size_t add_pass(const PassDesc& pass);
    const MaterialSystem& system() const { return *system_; }
    size_t pass_count() const { return passes_.size(); }

    // The calls below are on the frame path: none throws. A bad argument (a pass that was not added, a
    // variant or primitive that does not exist, a frame or coefficient set that is VK_NULL_HANDLE because it
    // was released) is reported through the device's log callback (LogLevel::Error, naming the call) and the
    // call records nothing and returns false (docs/engine.md, "Errors").

    // What every draw below checks first, reported as `call`: the models built on the surfaces check their
    // arguments under their own names with it.
    bool check(const char* call, VkDescriptorSet frame, VkDescriptorSet source, size_t variant,
               size_t pass) const noexcept;

    // Inside the caller's render pass: every primitive with its material and variants[variant],
    // coefficients from `source` at `coefficient_offset` (the DrawPush field), under `model`, with the
    // pipelines of `pass` (add_pass). Primitive p is draw id p + 1. A depth pass (PassKind::Depth) skips
    // blended primitives; a shadow pass draws them alpha-tested at their alphaCutoff.
    bool draw(VkCommandBuffer cmd, VkDescriptorSet frame, VkDescriptorSet source, uint32_t coefficient_offset,
              const glm::mat4& model, size_t variant = 0, size_t pass = 0) const noexcept;

    // One primitive (draw() is every primitive in order), with this draw's lightmap rectangle
    // (shared::DrawPush::lightmap_scale_offset). Binds the mesh too.
    bool draw_primitive(VkCommandBuffer cmd, VkDescriptorSet frame, VkDescriptorSet source,
                        uint32_t coefficient_offset, const glm::mat4& model, size_t variant, size_t pass,
                        size_t primitive,
                        const glm::vec4& lightmap_scale_offset = {1.0f, 1.0f, 0.0f, 0.0f}) const noexcept;

    // Draw packets instead of draws (draw_queue.h): every primitive draw() would record, each keyed by
    // `layer` (< 256), its material type and sets, and `depth`; sorted and recorded with the rest of the
    // frame's. With `instances` (count > 0): each packet draws those instances, whose records (FrameSet::
    // write_instances) hold the model, coefficient offset and lightmap rectangle in place of these.
    bool enqueue(DrawQueue& queue, VkDescriptorSet frame, VkDescriptorSet source, uint32_t coefficient_offset,
                 const glm::mat4& model, size_t variant = 0, size_t pass = 0, uint32_t layer = 0,
                 float depth = 0.0f, InstanceRange instances = {}) const noexcept;
    // The packet of one primitive; false for a primitive the pass does not draw (blended, in a depth pass)
    // and for a refused argument (then also reported).
    bool packet(DrawPacket& out, VkDescriptorSet frame, VkDescriptorSet source, uint32_t coefficient_offset,
                const glm::mat4& model, size_t variant, size_t pass, size_t primitive,
                const glm::vec4& lightmap_scale_offset = {1.0f, 1.0f, 0.0f, 0.0f}) const noexcept;

    // What an engine's draw list needs of each primitive.
    struct Primitive
    {
        uint32_t first_index, index_count, material;
        glm::vec3 bounds_min, bounds_max; // of its vertices, in the model's space
    };
    size_t primitive_count() const { return draws_.size(); }
    Primitive primitive(size_t p) const;
    const MaterialType& type(size_t primitive, size_t variant, size_t pass) const;
    VkDescriptorSet material_set(size_t primitive) const;
    const io::Material& material(size_t primitive) const;

    // hemi's copy of the mesh (std::logic_error for surfaces drawn from the engine's geometry).
    const GpuMesh& mesh() const;
    // What draws bind: mesh().binding() or the engine's buffers.
    const MeshBinding& binding() const { return *binding_; }
    bool engine_geometry() const { return !mesh_; }
    // The scene's images on the GPU (an engine's own shaders sample them: image(material.normal.image, ...)).
    const TextureSet& textures() const { return textures_; }
    size_t material_count() const { return materials_.size(); }

  private:
    MaterialSystem* system_;
    std::unique_ptr<GpuMesh> mesh_; // null with the engine's geometry
    MeshBinding engine_buffers_;
    const MeshBinding* binding_ = nullptr;
    TextureSet textures_;
    std::vector<std::unique_ptr<MaterialInstance>> materials_;
    std::vector<io::Material> material_data_;
    struct Draw
    {
        uint32_t first_index, index_count, material;
        int32_t vertex_offset;
        glm::vec3 bounds_min, bounds_max;
        std::vector<MaterialKey> keys;                       // per variant
        std::vector<uint32_t> coefficient_shift;             // per variant: vertex_offset * K (vertex source)
        std::vector<std::vector<const MaterialType*>> types; // per pass, per variant
    };
    std::vector<Draw> draws_;
    std::vector<PassKind> passes_;
};

} // namespace hemi::render
