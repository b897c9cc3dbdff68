#pragma once
// A baked PRT asset drawn with one technique into hemi's own offscreen target: the runtime half of Sloan 2006
// behind hemi-render, the prt_normalmap sample and the benchmark. Each frame: rotate the world lighting into
// object space (SH rotation), run the coefficient source (dense transfer pass or CPCA), draw every primitive
// with its material through the material system. An engine drawing into its own passes uses PrtModel
// (scene/prt_model.h) and a MaterialSystem for its target directly; PrtView is that plus a target.
//
// Conventions: hemi's world is z up; glTF scenes (and so baked assets) are y up and are placed in the world
// by gltf_to_world() (glTF +y becomes world +z). Environments are world-space SH (math/sh_environment.h).

#include <hemi/gpu/device.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/transfer.h>
#include <hemi/render/view/offscreen.h>
#include <hemi/render/view/view_target.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hemi::render
{

// World-space lighting of SH order `order`: "uniform" (radiance 1 from every direction), "sky"
// (math::AnalyticSky) or the path of an equirectangular EXR (io::read_exr, math::project_equirect). Throws
// io::FormatError for a bad file, std::invalid_argument for a bad order.
std::vector<glm::vec3> environment_lighting(const std::string& environment, int order);

// The camera math (math/camera.h), shared with the reference tracer so that both frame a scene alike.
using math::auto_camera;
using math::bounding_sphere;
using math::BoundingSphere;
using math::camera_matrix;
using math::look_at_projection;

struct PrtFrame
{
    std::vector<glm::vec3> world_lighting; // SH of the asset's order (or higher: truncated)
    float rotate_degrees = 0.0f;           // the environment turns about world z
    PrtCamera camera;
    glm::mat4 model = gltf_to_world(); // a rotation; the lighting is rotated by its inverse
    bool white = false;                // albedo 1: the lighting-only view
};

class PrtView
{
  public:
    // `asset` must outlive the view; it is self-contained (its images travel inside it: a corrupt one is an
    // io::FormatError naming it). `cpca` selects the CPCA data of the technique (std::invalid_argument when
    // the asset has none).
    PrtView(const gpu::Device& device, const io::PrtAsset& asset, const std::string& technique, bool cpca,
            uint32_t width, uint32_t height);
    ~PrtView();

    // The object-space lighting the coefficient source receives for `frame`.
    std::vector<glm::vec3> object_lighting(const PrtFrame& frame) const;

    // Outside a render pass: the transfer (or CPCA) pass, then record_material().
    void record_transfer(VkCommandBuffer cmd, const PrtFrame& frame);
    // Outside a render pass: the frame set's update only (camera, lighting-only flag), for a frame whose
    // coefficients are already in place (e.g. uploaded by a host-side multiply).
    void record_material(VkCommandBuffer cmd, const PrtFrame& frame);
    // The raster pass into target(): begin, draw, end.
    void record_raster(VkCommandBuffer cmd) const;
    // Both, submitted and waited for; returns the colour with alpha = coverage (1 where the model is).
    io::ImageRgba render(const PrtFrame& frame);

    const OffscreenTarget& target() const { return view_.target(); }
    CoefficientSource& coefficients() { return model_->coefficients(); }
    const io::Mesh& mesh() const { return asset_->mesh; }
    MaterialSystem& materials() { return view_.system(); }
    PrtModel& model() { return *model_; }

  private:
    const io::PrtAsset* asset_;
    ViewTarget view_;
    std::unique_ptr<PrtModel> model_;
    glm::mat4 model_matrix_{1.0f};
};

} // namespace hemi::render
