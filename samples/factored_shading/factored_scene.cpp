#include "factored_scene.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>
#include <hemi/math/camera.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/view/offscreen.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace hemi::samples
{
namespace
{
constexpr float kPi = 3.14159265358979f;

void grid_indices(io::Mesh& m, uint32_t segments, uint32_t rings)
{
    const uint32_t stride = segments + 1;
    for (uint32_t r = 0; r < rings; ++r)
        for (uint32_t s = 0; s < segments; ++s)
        {
            const uint32_t a = r * stride + s, b = a + 1, c = a + stride, d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, c, b, d, c});
        }
}
} // namespace

io::Mesh make_torus(float major, float minor, uint32_t segments, uint32_t rings)
{
    io::Mesh m;
    for (uint32_t r = 0; r <= rings; ++r)
    {
        const float v = float(r) / float(rings), theta = 2.0f * kPi * v;
        for (uint32_t s = 0; s <= segments; ++s)
        {
            const float u = float(s) / float(segments), phi = 2.0f * kPi * u;
            const glm::vec3 radial(std::cos(phi), std::sin(phi), 0.0f);
            // theta = 0 on the outside, going up first: normal = cos theta radial + sin theta z.
            const glm::vec3 n = std::cos(theta) * radial + std::sin(theta) * glm::vec3(0, 0, 1);
            m.positions.push_back(major * radial + minor * n);
            m.normals.push_back(n);
            // t = dP/du along +phi. glTF's bitangent cross(n, t) w points towards decreasing v; v grows up
            // the outside of the tube (dP/dv = +z there) while cross(n, t) = +z there: w = -1.
            m.tangents.push_back(glm::vec4(-std::sin(phi), std::cos(phi), 0.0f, -1.0f));
            m.uvs.push_back(glm::vec2(u * 4.0f, v)); // bricks of similar shape around and across the tube
        }
    }
    grid_indices(m, segments, rings);
    return m;
}

io::Mesh make_disk(float radius, uint32_t segments, uint32_t rings)
{
    io::Mesh m;
    for (uint32_t r = 0; r <= rings; ++r)
    {
        const float v = float(r) / float(rings), rho = radius * std::max(v, 1e-3f);
        for (uint32_t s = 0; s <= segments; ++s)
        {
            const float u = float(s) / float(segments), phi = 2.0f * kPi * u;
            m.positions.push_back(glm::vec3(rho * std::cos(phi), rho * std::sin(phi), 0.0f));
            m.normals.push_back(glm::vec3(0, 0, 1));
            // t = +phi; cross(n, t) = -radial = -dP/dv: w = +1.
            m.tangents.push_back(glm::vec4(-std::sin(phi), std::cos(phi), 0.0f, 1.0f));
            m.uvs.push_back(glm::vec2(u, v));
        }
    }
    // Counter-clockwise seen from +z: (a, b, c) with b further around and c further out.
    const uint32_t stride = segments + 1;
    for (uint32_t r = 0; r < rings; ++r)
        for (uint32_t s = 0; s < segments; ++s)
        {
            const uint32_t a = r * stride + s, b = a + 1, c = a + stride, d = c + 1;
            m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
        }
    return m;
}

glm::vec3 studio_sun_direction()
{
    const float az = 40.0f * kPi / 180.0f, el = 35.0f * kPi / 180.0f;
    return glm::vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
}

io::ImageRgba studio_environment(uint32_t width, uint32_t height, float sun)
{
    io::ImageRgba img;
    img.width = width;
    img.height = height;
    img.pixels.resize(size_t(width) * height * 4);
    const glm::vec3 s = studio_sun_direction();
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x)
        {
            const float phi = kPi - 2.0f * kPi * (x + 0.5f) / width, theta = kPi * (y + 0.5f) / height;
            const glm::vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
            glm::vec3 l;
            if (d.z >= 0.0f)
            {
                const float t = std::pow(1.0f - d.z, 3.0f);
                l = glm::mix(glm::vec3(0.25f, 0.45f, 1.0f), glm::vec3(1.0f, 1.0f, 1.1f), t) * 1.2f;
                // Coloured panels standing around the horizon, every 45 degrees.
                const float a = std::atan2(d.y, d.x) / (2.0f * kPi) * 8.0f;
                const int panel = int(std::floor(a + 8.0f)) % 8;
                if (d.z < 0.3f && (a - std::floor(a)) < 0.55f)
                {
                    const glm::vec3 colours[4] = {
                        {3.0f, 0.4f, 0.2f}, {0.3f, 2.5f, 0.4f}, {2.5f, 2.2f, 0.3f}, {0.6f, 0.4f, 3.0f}};
                    l = colours[panel % 4];
                }
                if (glm::dot(d, s) > std::cos(2.5f * kPi / 180.0f))
                    l = glm::vec3(sun, sun * 0.92f, sun * 0.8f);
            }
            else
            {
                const float checker =
                    (int(std::floor(d.x / -d.z * 2.0f)) + int(std::floor(d.y / -d.z * 2.0f))) & 1;
                l = glm::vec3(0.35f, 0.25f, 0.15f) * (checker ? 1.0f : 0.6f);
            }
            float* p = img.pixels.data() + (size_t(y) * width + x) * 4;
            p[0] = l.x, p[1] = l.y, p[2] = l.z, p[3] = 1.0f;
        }
    return img;
}

io::ImageRgba render_factored(const gpu::Device& device, const FactoredView& view, uint32_t width,
                              uint32_t height, io::ImageRgba* aux)
{
    if (!view.mesh || !view.environment)
        throw std::invalid_argument("render_factored needs a mesh and an environment");
    render::OffscreenTarget target(device, width, height);
    render::MaterialSystem system(device, target.desc());
    gpu::UploadBatch upload(device);
    render::GpuMesh mesh(device, *view.mesh, upload);
    io::Material material;
    material.base_color_factor = glm::vec4(view.albedo, 1.0f);
    material.normal_scale = view.normal_scale;
    std::vector<io::ImageRgba8> images;
    if (!view.normal_map.pixels.empty())
    {
        images.push_back(view.normal_map);
        material.normal.image = 0;
        material.normal.sampler.mipmaps = false; // bilinear from mip 0, as the CPU references
    }
    render::TextureSet textures(device, images, std::span<const io::Material>(&material, 1), upload);
    render::MaterialInstance instance(system, textures, material, upload);
    render::EnvironmentLighting lighting(
        system,
        view.probes.empty()
            ? std::make_shared<render::EnvironmentMaps>(device, *view.environment, upload, view.precision)
            : std::make_shared<render::EnvironmentMaps>(device, std::span<const io::EnvmapAsset>(view.probes),
                                                        upload, view.precision),
        view.brdf, view.material, upload);
    render::FrameSet frame(system);
    render::MaterialKey key;
    key.technique = view.technique;
    key.source = render::CoefficientSourceKind::Environment;
    key.basis = HEMI_BASIS_SH9;
    key.frame = render::ShadingFrame::World;
    render::DrawBindings draw;
    draw.type = &system.type(key);
    draw.frame = frame.set();
    draw.material = instance.set();
    draw.source = lighting.set();
    draw.push.model = view.model;
    draw.push.draw_id = 1;
    gpu::one_shot(device,
                  [&](VkCommandBuffer cmd)
                  {
                      upload.record(cmd);
                      render::FrameData f;
                      f.view_projection = math::look_at_projection(view.eye, view.target, view.fov_y_degrees,
                                                                   float(width) / float(height));
                      f.eye = view.eye;
                      f.lights = view.lights;
                      f.specular_exponent = view.specular_exponent;
                      f.specular_strength = view.specular_strength;
                      frame.record_update(cmd, f);
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
