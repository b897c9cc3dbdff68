#include "../refuse.h"
#include <hemi/render/view/lightmap_view.h>

#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::render
{

LightmapView::LightmapView(const gpu::Device& device, const io::LightmapAsset& asset,
                           const std::vector<std::string>& techniques, uint32_t width, uint32_t height,
                           LightmapFilter filter)
    : asset_(&asset), view_(device, width, height)
{
    gpu::UploadBatch upload(device);
    model_ = std::make_unique<LightmapModel>(view_.system(), asset, techniques, upload,
                                             std::map<std::string, std::string>{}, nullptr, filter);
    upload.submit_and_wait();
}

LightmapView::~LightmapView() = default;

io::ImageRgba LightmapView::render(const LightmapFrame& frame)
{
    if (frame.spheres.size() > kMaxSpheres)
        throw std::invalid_argument("hemi: at most " + std::to_string(kMaxSpheres) + " spheres, got " +
                                    std::to_string(frame.spheres.size()));
    std::vector<std::array<glm::vec3, 9>> lighting(frame.spheres.size());
    std::vector<ProbeBuffer::Occlusion> occlusion(frame.spheres.size());
    for (size_t i = 0; i < frame.spheres.size(); ++i)
    {
        const glm::vec4& s = frame.spheres[i];
        if (!(s.w > 0.0f) || !std::isfinite(s.x + s.y + s.z + s.w))
            throw std::invalid_argument("hemi: a sphere needs a finite centre and a radius > 0");
        if (!probe_lighting(*asset_, glm::vec3(s), frame.model, lighting[i], &occlusion[i]))
            throw std::invalid_argument(
                asset_->probes.empty()
                    ? "hemi: the lightmap asset has no light probes (bake it with --probes)"
                    : "hemi: the level's model matrix is singular or not finite");
    }
    if (!frame.spheres.empty() && !spheres_)
    {
        sphere_mesh_ = io::make_uv_sphere(1.0f, 64, 32);
        io::Material grey;
        grey.name = "probe-lit sphere";
        grey.base_color_factor = glm::vec4(0.8f, 0.8f, 0.8f, 1.0f);
        sphere_material_ = {grey};
        gpu::UploadBatch upload(view_.device());
        spheres_ = std::make_unique<ProbeObject>(view_.system(), sphere_mesh_,
                                                 std::vector<io::EncodedImage>{}, sphere_material_,
                                                 std::vector<io::Primitive>{}, kMaxSpheres, upload);
        upload.submit_and_wait();
    }
    gpu::one_shot(view_.device(),
                  [&](VkCommandBuffer cmd)
                  {
                      FrameData dynamic;
                      dynamic.lights = frame.lights;
                      dynamic.specular_exponent = frame.specular_exponent;
                      dynamic.specular_strength = frame.specular_strength;
                      dynamic.glossy_roughness = frame.glossy_roughness;
                      dynamic.glossy_f0 = frame.glossy_f0;
                      view_.record_frame(cmd, frame.camera, asset_->mesh, frame.model, frame.white, dynamic);
                      // A tool's view: what the frame path refuses (and logs) throws here.
                      for (size_t i = 0; i < lighting.size(); ++i)
                          if (!spheres_->record_lighting(cmd, uint32_t(i), lighting[i], 0, occlusion[i]))
                              throw std::invalid_argument(detail::last_refusal());
                      view_.target().begin(cmd);
                      if (!model_->draw(cmd, view_.frame(), frame.technique, frame.model))
                          throw std::invalid_argument(detail::last_refusal());
                      for (size_t i = 0; i < frame.spheres.size(); ++i)
                      {
                          const glm::vec4& s = frame.spheres[i];
                          const glm::mat4 m =
                              glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(s)), glm::vec3(s.w));
                          if (!spheres_->draw(cmd, view_.frame(), uint32_t(i), m))
                              throw std::invalid_argument(detail::last_refusal());
                      }
                      view_.target().end(cmd);
                  });
    return view_.read();
}

} // namespace hemi::render
