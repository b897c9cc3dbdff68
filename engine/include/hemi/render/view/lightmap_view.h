#pragma once
// A baked lightmap asset drawn into hemi's own offscreen target: the runtime half of Habel & Wimmer 2010
// behind hemi-render. An engine drawing into its own passes uses LightmapModel (scene/lightmap_model.h) with
// a MaterialSystem for its target; LightmapView is that plus a target. Conventions as PrtView's: hemi's world
// is z up, the asset is placed by gltf_to_world().

#include <hemi/gpu/device.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/probe_object.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/view/view_target.h>

#include <glm/mat4x4.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hemi::render
{

struct LightmapFrame
{
    std::string technique; // one of the view's techniques
    PrtCamera camera;
    glm::mat4 model = gltf_to_world();
    bool white = false; // albedo 1: the lighting-only view (E / pi)
    // Dynamic objects: grey spheres (albedo 0.8), centre xyz and radius w in world space, each lit by the
    // asset's light probes at its centre (render::probe_lighting) in the same render pass as the level. At
    // most LightmapView::kMaxSpheres; the asset must have probes. The view's depth range is the level's
    // bounds: a sphere outside them is clipped.
    std::vector<glm::vec4> spheres;
    // Dynamic lights (world space) for the techniques that take them (irradiance, rnm, ssbump), with their
    // specular term; the asset's mixed lights are render::mixed_lights(asset, model) (hemi-render adds them).
    std::vector<DynamicLight> lights;
    float specular_exponent = 32.0f, specular_strength = 0.0f;
    // The GGX coat over every surface (FrameData::glossy_roughness, glossy_f0; 0: none).
    float glossy_roughness = 0.0f, glossy_f0 = 0.04f;
};

class LightmapView
{
  public:
    // `asset` must outlive the view. Loads `techniques` (outputs of the asset; std::invalid_argument names
    // one it lacks), looked up with `filter`.
    LightmapView(const gpu::Device& device, const io::LightmapAsset& asset,
                 const std::vector<std::string>& techniques, uint32_t width, uint32_t height,
                 LightmapFilter filter = LightmapFilter::Linear);
    ~LightmapView();

    static constexpr uint32_t kMaxSpheres = 16;

    // Submitted and waited for; the colour with alpha = coverage.
    io::ImageRgba render(const LightmapFrame& frame);

    const OffscreenTarget& target() const { return view_.target(); }
    MaterialSystem& materials() { return view_.system(); }
    LightmapModel& model() { return *model_; }

  private:
    const io::LightmapAsset* asset_;
    ViewTarget view_;
    std::unique_ptr<LightmapModel> model_;
    io::Mesh sphere_mesh_;
    std::vector<io::Material> sphere_material_;
    std::unique_ptr<ProbeObject> spheres_; // made at the first frame with spheres
};

} // namespace hemi::render
