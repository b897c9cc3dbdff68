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
// map in the normalised convention, Listing 2); "constant", the base colour factor alone (hemi-bench's
// baseline).
// Several techniques may be loaded at once and switched between per draw: the H6 -> H4 shader level of
// detail of Habel & Wimmer is technique("h6") near, technique("h4") far.

#include <hemi/gpu/upload.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/basis.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/scene_surfaces.h>

#include <glm/mat4x4.hpp>

#include <memory>
#include <string>
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
// irradiance coefficients a ProbeCoefficients source takes (technique "sh9" on the world frame: the object's
// normal-map normal in world space). Throws std::invalid_argument when the asset has no probes.
std::vector<glm::vec3> probe_lighting(const io::LightmapAsset& asset, const glm::vec3& world_position,
                                      const glm::mat4& model);

class LightmapModel
{
  public:
    // `asset` must outlive the model. Loads each of `techniques` (outputs of the asset). Uploads go into
    // `upload`. Throws std::invalid_argument naming a technique the asset lacks (and listing what it has).
    LightmapModel(MaterialSystem& system, const io::LightmapAsset& asset,
                  const std::vector<std::string>& techniques, gpu::UploadBatch& upload);
    ~LightmapModel();

    // Another pass of the caller's frame (a depth prepass, a shadow map; SceneSurfaces::add_pass): its
    // index for draw(). Pass 0 is the system's default colour pass.
    size_t add_pass(const PassDesc& pass) { return surfaces_->add_pass(pass); }

    // Inside the caller's render pass: every primitive with its material, lit by `technique` (one of those
    // loaded), under `model`, with the pipelines of `pass`. Depth and shadow passes ignore the technique's
    // lighting (any loaded technique will do).
    void draw(VkCommandBuffer cmd, VkDescriptorSet frame, const std::string& technique,
              const glm::mat4& model, size_t pass = 0) const;

    const io::LightmapAsset& asset() const { return *asset_; }

  private:
    const io::LightmapAsset* asset_;
    std::vector<std::string> names_;
    std::unique_ptr<SceneSurfaces> surfaces_; // variant i draws technique names_[i]
    std::vector<std::unique_ptr<TexelCoefficients>> coefficients_;
};

} // namespace hemi::render
