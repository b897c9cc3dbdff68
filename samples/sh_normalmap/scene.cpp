#include "scene.h"

#include <hemi/bake/normal_map.h>
#include <hemi/gpu/commands.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/view/offscreen.h>
#include <hemi/render/view/prt_view.h>

#include <algorithm>
#include <cmath>

namespace hemi::samples
{
namespace
{

float smoothstep(float e0, float e1, float x)
{
    float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

} // namespace

std::vector<float> brick_heights(uint32_t w, uint32_t h, float amplitude, float columns, float rows)
{
    const float mortar = 0.06f, bevel = 0.12f;
    std::vector<float> out(size_t(w) * h);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            float u = (x + 0.5f) / w, v = (y + 0.5f) / h;
            float row = v * rows;
            float offset = (int(row) % 2) ? 0.5f : 0.0f;
            float fu = u * columns + offset, fv = row;
            float du = std::min(fu - std::floor(fu), std::ceil(fu) - fu) * 2.0f; // 0 at a joint, 1 mid-brick
            float dv = std::min(fv - std::floor(fv), std::ceil(fv) - fv) * 2.0f;
            float edge = std::min(du * 0.5f, dv); // bricks are twice as long as tall
            out[size_t(y) * w + x] = amplitude * smoothstep(mortar, mortar + bevel, edge);
        }
    return out;
}

ShNormalMapScene make_sh_normalmap_scene(Environment environment)
{
    ShNormalMapScene s;
    s.mesh = io::make_uv_sphere(1.0f, 128, 64);
    s.map_width = 1024;
    s.map_height = 512;
    s.normal_map = bake::normal_map_from_height(brick_heights(s.map_width, s.map_height, 1.0f), s.map_width,
                                                s.map_height, 3.0f);
    math::Sh9Rgb radiance;
    if (environment == Environment::Uniform)
        radiance = math::project_sh9([](const glm::vec3&) { return glm::vec3(1.0f); }, 64);
    else
    {
        math::AnalyticSky sky;
        radiance = math::project_sh9([&](const glm::vec3& d) { return sky.radiance(d); }, 128);
    }
    s.irradiance = math::convolve_cosine(radiance);
    return s;
}

io::ImageRgba render_sh_normalmap(const gpu::Device& device, const ShNormalMapScene& scene, uint32_t width,
                                  uint32_t height, io::ImageRgba* aux)
{
    // The SH9 probe material of the material system: world-frame SH9 irradiance from a uniform source,
    // evaluated at the normal-map normal turned into world space.
    render::OffscreenTarget target(device, width, height);
    render::MaterialSystem system(device, target.desc());
    gpu::UploadBatch upload(device);
    render::GpuMesh mesh(device, scene.mesh, upload);
    io::Material material;
    material.base_color_factor = glm::vec4(scene.albedo, 1.0f);
    material.normal.image = 0;
    material.normal.sampler.mipmaps =
        false; // bilinear from mip 0 (glTF minFilter LINEAR), as the test's CPU reference
    const io::ImageRgba8 normal_map{scene.map_width, scene.map_height, scene.normal_map};
    render::TextureSet textures(device, std::span<const io::ImageRgba8>(&normal_map, 1),
                                std::span<const io::Material>(&material, 1), upload);
    render::MaterialInstance instance(system, textures, material, upload);
    render::ProbeBuffer probe(system, 1);
    render::FrameSet frame(system);
    render::MaterialKey key;
    key.source = render::CoefficientSourceKind::Uniform;
    key.basis = HEMI_BASIS_SH9;
    key.frame = render::ShadingFrame::World;
    render::DrawBindings draw;
    draw.type = &system.type(key);
    draw.frame = frame.set();
    draw.material = instance.set();
    draw.source = probe.set();
    draw.push.model = glm::mat4(1.0f);
    gpu::one_shot(device,
                  [&](VkCommandBuffer cmd)
                  {
                      upload.record(cmd);
                      render::FrameData f;
                      f.view_projection = render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f,
                                                                     float(width) / float(height));
                      frame.record_update(cmd, f);
                      probe.record_update(cmd, 0, 0, scene.irradiance);
                      target.begin(cmd, glm::vec4(0.0f));
                      render::bind_material(cmd, draw);
                      mesh.bind(cmd);
                      mesh.draw(cmd, 0, mesh.index_count());
                      target.end(cmd);
                  });
    if (aux)
        *aux = target.read_aux();
    return target.read_color();
}

} // namespace hemi::samples
