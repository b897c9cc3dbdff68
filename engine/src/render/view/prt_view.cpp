#include "../refuse.h"

#include <hemi/math/basis.h>
#include <hemi/math/sh.h>
#include <hemi/math/sh_environment.h>
#include <hemi/render/view/prt_view.h>

#include <hemi/gpu/commands.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hemi::render
{

std::vector<glm::vec3> environment_lighting(const std::string& environment, int order)
{
    if (order < 1 || order > math::kMaxShOrder)
        throw std::invalid_argument("hemi: environment SH order " + std::to_string(order) + " out of range");
    if (environment == "uniform")
    {
        std::vector<glm::vec3> l(size_t(order) * order, glm::vec3(0.0f));
        l[0] = glm::vec3(2.0f * std::sqrt(float(M_PI))); // radiance 1: the integral of y00 over the sphere
        return l;
    }
    if (environment == "sky")
    {
        const math::AnalyticSky sky;
        return math::project_sh(
            order, [&](const glm::vec3& d) { return sky.radiance(d); }, 256);
    }
    io::ImageRgba image = io::read_exr(environment);
    io::clamp_negative_radiance(image, environment); // small negatives (HDRI compression) read as 0
    return math::project_equirect(order, image.width, image.height, image.pixels);
}

ViewTarget::ViewTarget(const gpu::Device& device, uint32_t width, uint32_t height)
    : device_(&device), target_(device, width, height), system_(device, target_.desc()), frame_set_(system_)
{
}

void ViewTarget::record_frame(VkCommandBuffer cmd, const PrtCamera& camera, const io::Mesh& mesh,
                              const glm::mat4& model, bool white, const FrameData& lighting)
{
    const float aspect = float(target_.width()) / float(target_.height());
    // The bounds only change with the model matrix: no pass over the vertices per frame.
    if (!bounds_valid_ || model != bounds_model_)
    {
        const BoundingSphere b = bounding_sphere(mesh, model);
        bounds_centre_ = b.centre;
        bounds_radius_ = b.radius;
        bounds_model_ = model;
        bounds_valid_ = true;
    }
    FrameData f = lighting;
    f.view_projection = camera_matrix(camera, BoundingSphere{bounds_centre_, bounds_radius_}, aspect);
    f.lighting_only = white;
    f.eye = camera.eye;
    if (!frame_set_.record_update(cmd, f))
        throw std::invalid_argument(detail::last_refusal()); // a tool's view: bad input throws
}

io::ImageRgba ViewTarget::read() const
{
    io::ImageRgba color = target_.read_color();
    const io::ImageRgba aux = target_.read_aux();
    for (size_t i = 0; i < color.pixels.size(); i += 4)
        color.pixels[i + 3] = aux.pixels[i + 3];
    return color;
}

PrtView::PrtView(const gpu::Device& device, const io::PrtAsset& asset, const std::string& technique,
                 bool cpca, uint32_t width, uint32_t height)
    : asset_(&asset), view_(device, width, height)
{
    gpu::UploadBatch upload(device);
    model_ = std::make_unique<PrtModel>(view_.system(), asset, PrtModelDesc{technique, cpca, 1}, upload);
    upload.submit_and_wait();
}

PrtView::~PrtView() = default;

std::vector<glm::vec3> PrtView::object_lighting(const PrtFrame& frame) const
{
    return render::object_lighting(frame.world_lighting, int(asset_->order), frame.model,
                                   frame.rotate_degrees);
}

void PrtView::record_transfer(VkCommandBuffer cmd, const PrtFrame& frame)
{
    if (!model_->record_transfer_object_space(cmd, object_lighting(frame)))
        throw std::invalid_argument(detail::last_refusal());
    record_material(cmd, frame);
}

void PrtView::record_material(VkCommandBuffer cmd, const PrtFrame& frame)
{
    view_.record_frame(cmd, frame.camera, asset_->mesh, frame.model, frame.white);
    model_matrix_ = frame.model;
}

void PrtView::record_raster(VkCommandBuffer cmd) const
{
    view_.target().begin(cmd);
    if (!model_->draw(cmd, view_.frame(), 0, model_matrix_))
        throw std::invalid_argument(detail::last_refusal());
    view_.target().end(cmd);
}

io::ImageRgba PrtView::render(const PrtFrame& frame)
{
    gpu::one_shot(view_.device(),
                  [&](VkCommandBuffer cmd)
                  {
                      record_transfer(cmd, frame);
                      record_raster(cmd);
                  });
    return view_.read();
}

} // namespace hemi::render
