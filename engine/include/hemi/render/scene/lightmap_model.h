#pragma once
// A baked lightmap asset (io/lightmap_asset.h) on the GPU, drawn through the material system: the mesh, the
// scene's materials, and one output's coefficient maps as the per-texel coefficient source (sampled at
// TEXCOORD_1, evaluated by the basis at the normal-map normal in the tangent frame). Static lighting: nothing
// to update per frame.
//
// Techniques: the bases of math::bases() the asset holds (sh9, hl2, h4, h6, sal4, ...); "plain", the
// non-directional lightmap (the irradiance at the surface normal; the normal map does not change it); and,
// from the asset's "rnm" output (Valve's three lightmap colours), "rnm" (radiosity normal mapping with the
// material's normal map, Green 2007 Listing 1) and "ssbump" (the material's normal-map slot holds an SSBump
// map in the normalised convention, Listing 2); "constant", the base colour factor alone, and "lambert", the
// material's textures lit by the frame's dynamic lights alone (hemi-bench's baselines).
// Several techniques may be loaded at once and switched between per draw: the H6 -> H4 shader level of
// detail of Habel & Wimmer is technique("h6") near, technique("h4") far.

#include <hemi/gpu/upload.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/basis.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/scene_surfaces.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace hemi::render
{

// The basis that draws a lightmap output: math::basis(name), or for "plain" the constant function of
// math::vertex_irradiance_basis(). Throws std::invalid_argument for "rnm" (drawn by the SSBump and radiosity
// normal mapping materials, not a basis) and unknown names.
const math::BasisDesc& lightmap_basis(const std::string& output);

// The light of the asset's probes (io::LightProbes, hemi-bake lightmap --probes) for a dynamic object at
// `world_position` in a level placed by `model` (a rotation, uniform scale and translation): the probes'
// interpolation at the position in the level's space, rotated into the world, as the 9 world-space SH9
// irradiance coefficients a ProbeBuffer takes (technique "sh9" on the world frame: the object's
// normal-map normal in world space), into `out`; with `occlusion`, the probes' occlusion of the level's mixed
// lights there (io::LightProbes::occlusion_at: all 1 without mixed lights), for ProbeObject::write_lighting.
// On the frame path: allocates and throws nothing; false (and `out` zero) when the asset has no probes, the
// position is not finite or the model matrix is singular.
bool probe_lighting(const io::LightmapAsset& asset, const glm::vec3& world_position, const glm::mat4& model,
                    std::array<glm::vec3, 9>& out, std::array<float, 4>* occlusion = nullptr) noexcept;

// The asset's mixed lights (io::LightmapLight with mode Mixed) as the frame's dynamic lights of a level
// placed by `model` (a rotation, uniform scale and translation), each with its shadowmask channel and glTF's
// falloffs (range, spot cone): what lights them at run time (the lightmap holds only their bounces). A point
// or spot light's intensity is times the model's scale squared and its range times the scale, so it gives
// the light the bake gave at the same place. Throws std::invalid_argument for a singular model matrix. A
// level may hold more mixed lights than a frame takes (HEMI_MAX_LIGHTS: lights far apart share a channel);
// FrameData refuses more, naming the count, so an engine picks the ones near the view.
std::vector<DynamicLight> mixed_lights(const io::LightmapAsset& asset, const glm::mat4& model);

// One entry of a level's draw list: a primitive with its material and the technique that lights it, the
// pipeline it binds and its bounds, for an engine to cull, sort and draw (LightmapModel::draw(cmd, frame,
// entry, ...)).
struct LightmapDraw
{
    size_t primitive = 0;
    uint32_t first_index = 0, index_count = 0;
    const io::Material* material = nullptr;
    const std::string* technique = nullptr;       // the material's own, or the level's default
    const MaterialType* type = nullptr;           // the pipeline (its key and pass): equal pointers share one
    glm::vec3 bounds_min{0.0f}, bounds_max{0.0f}; // of the primitive's vertices, in the model's space
    size_t variant = 0;                           // which loaded technique (internal)
};

class LightmapModel
{
  public:
    // Everything the model draws is uploaded (or copied into `upload`) here: the asset may be freed once the
    // model is made. Loads each of `techniques` (outputs of the asset) and every technique
    // a material asks for (io::Material::technique, e.g. an SSBump wall's "ssbump"), overridden by
    // `material_techniques` (material name -> technique; "" = the level's default). Uploads go into
    // `upload`. Throws std::invalid_argument naming a technique the asset lacks (and listing what it has).
    // With `geometry` the level draws from the engine's own vertex and index buffers (EngineGeometry):
    // hemi uploads no vertex or index data. `filter`: how every technique's colour pipelines look the
    // lightmaps up (LightmapFilter::Bicubic: the cubic B-spline, no creases in gradients, four fetches per
    // packed layer).
    LightmapModel(MaterialSystem& system, const io::LightmapAsset& asset,
                  const std::vector<std::string>& techniques, gpu::UploadBatch& upload,
                  const std::map<std::string, std::string>& material_techniques = {},
                  const EngineGeometry* geometry = nullptr, LightmapFilter filter = LightmapFilter::Linear);
    ~LightmapModel();

    // The level's draw list for `technique` (its default: materials with their own technique keep it) in
    // `pass`: no per-primitive decision is left to the caller.
    std::vector<LightmapDraw> draw_list(const std::string& technique, size_t pass = 0) const;
    // The calls from here to the draw of a technique are on the frame path: none throws or allocates. A bad
    // argument (an entry of another model, a pass that was not added, a technique that is not loaded, a
    // released frame set) is reported through the device's log callback and the call records nothing and
    // returns false (docs/engine.md, "Errors").

    // Inside the caller's render pass: one entry, under `model`, with this draw's lightmap rectangle
    // (TEXCOORD_1 * xy + zw: several objects sharing one atlas).
    bool draw(VkCommandBuffer cmd, VkDescriptorSet frame, const LightmapDraw& entry, const glm::mat4& model,
              size_t pass = 0,
              const glm::vec4& lightmap_scale_offset = {1.0f, 1.0f, 0.0f, 0.0f}) const noexcept;
    // The same as a draw packet (draw_queue.h), keyed by `layer` and `depth`. The entry must come from
    // draw_list(..., pass).
    bool enqueue(DrawQueue& queue, VkDescriptorSet frame, const LightmapDraw& entry, const glm::mat4& model,
                 size_t pass = 0, const glm::vec4& lightmap_scale_offset = {1.0f, 1.0f, 0.0f, 0.0f},
                 uint32_t layer = 0, float depth = 0.0f) const noexcept;

    // Instanced: instances.count copies of the entry in one draw, copy i placed by the frame set's record
    // instances.first + i (FrameSet::write_instances of instance_record()s): many instances of one asset.
    bool enqueue_instances(DrawQueue& queue, VkDescriptorSet frame, const LightmapDraw& entry,
                           InstanceRange instances, size_t pass = 0, uint32_t layer = 0,
                           float depth = 0.0f) const noexcept;
    // The record of one instance: its model matrix and lightmap rectangle (TEXCOORD_1 * xy + zw), and its
    // draw id for the aux attachment (0: the primitive's).
    static shared::DrawPush instance_record(const glm::mat4& model,
                                            const glm::vec4& lightmap_scale_offset = {1.0f, 1.0f, 0.0f, 0.0f},
                                            uint32_t draw_id = 0) noexcept;

    // Another pass of the caller's frame (a depth prepass, a shadow map; SceneSurfaces::add_pass): its
    // index for draw(). Pass 0 is the system's default colour pass, when it has one.
    size_t add_pass(const PassDesc& pass) { return surfaces_->add_pass(pass); }

    // Inside the caller's render pass: every entry of draw_list(technique, pass), under `model`. Depth and
    // shadow passes ignore the technique's lighting (any loaded technique will do).
    bool draw(VkCommandBuffer cmd, VkDescriptorSet frame, std::string_view technique, const glm::mat4& model,
              size_t pass = 0) const noexcept;

    // hemi's data for an engine's own shaders (its main pass including hemi's GLSL library, docs/
    // integration.md): the mesh (GpuMesh::layout(), bound by surfaces().mesh().bind()), the materials'
    // textures (surfaces().textures()) and the coefficient maps of each loaded technique (an entry's own,
    // or by name; std::invalid_argument names a technique that is not loaded).
    const SceneSurfaces& surfaces() const { return *surfaces_; }
    const TexelCoefficients& coefficients(const LightmapDraw& entry) const
    {
        return *coefficients_.at(entry.variant);
    }
    const TexelCoefficients& coefficients(const std::string& technique) const;

  private:
    bool check(const char* call, const LightmapDraw& entry) const noexcept;
    const gpu::Device* device_;
    std::vector<std::string> names_;
    std::vector<int> primitive_variant_;      // per primitive: its material's technique, or -1 (the default)
    std::unique_ptr<SceneSurfaces> surfaces_; // variant i draws technique names_[i]
    std::vector<std::unique_ptr<TexelCoefficients>> coefficients_;
};

} // namespace hemi::render
