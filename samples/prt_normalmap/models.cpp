#include "models.h"

#include "scene.h"

#include <hemi/bake/normal_map.h>
#include <hemi/io/gltf.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <functional>

namespace hemi::samples
{
namespace
{

struct SurfacePoint
{
    glm::vec3 position, normal;
};

// A closed parametric surface over [0, 1]^2 (periodic in both), built in hemi's z-up world and returned in
// glTF's y-up space. UVs repeat the texture `repeat_u` x `repeat_v` times; tangents follow +u; triangles are
// wound counter-clockwise seen from the side the normals point to.
io::Mesh parametric(uint32_t nu, uint32_t nv, float repeat_u, float repeat_v,
                    const std::function<SurfacePoint(float, float)>& surface)
{
    io::Mesh m;
    const float h = 1e-3f;
    for (uint32_t j = 0; j <= nv; ++j)
        for (uint32_t i = 0; i <= nu; ++i)
        {
            const float u = float(i) / nu, v = float(j) / nv;
            const SurfacePoint p = surface(u, v);
            const glm::vec3 n = glm::normalize(p.normal);
            const glm::vec3 du = surface(u + h, v).position - surface(u - h, v).position;
            const glm::vec3 dv = surface(u, v + h).position - surface(u, v - h).position;
            const glm::vec3 t = glm::normalize(du - glm::dot(du, n) * n);
            // glTF: bitangent = cross(n, t) * w points toward decreasing texture v.
            const float w = glm::dot(glm::cross(n, t), dv) > 0.0f ? -1.0f : 1.0f;
            m.positions.push_back(p.position);
            m.normals.push_back(n);
            m.tangents.push_back(glm::vec4(t, w));
            m.uvs.push_back(glm::vec2(u * repeat_u, v * repeat_v));
        }
    for (uint32_t j = 0; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i)
        {
            const uint32_t a = j * (nu + 1) + i, b = a + 1, c = a + nu + 1, d = c + 1;
            for (auto tri : {std::array<uint32_t, 3>{a, b, d}, std::array<uint32_t, 3>{a, d, c}})
            {
                const glm::vec3 face = glm::cross(m.positions[tri[1]] - m.positions[tri[0]],
                                                  m.positions[tri[2]] - m.positions[tri[0]]);
                const glm::vec3 n = m.normals[tri[0]] + m.normals[tri[1]] + m.normals[tri[2]];
                if (glm::dot(face, n) < 0.0f)
                    std::swap(tri[1], tri[2]);
                m.indices.insert(m.indices.end(), tri.begin(), tri.end());
            }
        }
    // World (x, y, z) -> glTF (x, z, -y): the inverse of render::gltf_to_world().
    auto to_gltf = [](glm::vec3 p) { return glm::vec3(p.x, p.z, -p.y); };
    for (size_t i = 0; i < m.positions.size(); ++i)
    {
        m.positions[i] = to_gltf(m.positions[i]);
        m.normals[i] = to_gltf(m.normals[i]);
        m.tangents[i] = glm::vec4(to_gltf(glm::vec3(m.tangents[i])), m.tangents[i].w);
    }
    return m;
}

glm::vec3 trefoil(float t)
{
    const float a = 2.0f * float(M_PI) * t;
    return 0.5f * glm::vec3((2.0f + std::cos(3.0f * a)) * std::cos(2.0f * a),
                            (2.0f + std::cos(3.0f * a)) * std::sin(2.0f * a), -std::sin(3.0f * a) + 0.0f);
}

} // namespace

io::Mesh make_prt_model(PrtModel model, float detail)
{
    auto count = [&](uint32_t n) { return std::max(3u, uint32_t(std::lround(float(n) * detail))); };
    if (model == PrtModel::Simple)
    {
        const float R = 1.0f, r = 0.45f;
        return parametric(
            count(36), count(18), 4.0f, 1.0f,
            [&](float u, float v)
            {
                const float a = 2.0f * float(M_PI) * u, b = 2.0f * float(M_PI) * v;
                const glm::vec3 n(std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b));
                return SurfacePoint{glm::vec3(R * std::cos(a), R * std::sin(a), 0.0f) + r * n, n};
            });
    }
    const float r = 0.28f;
    return parametric(count(300), count(96), 6.0f, 1.0f,
                      [&](float u, float v)
                      {
                          // Frenet frame of the knot's centre line (periodic: the tube closes without a seam
                          // crack).
                          const float e = 1e-3f;
                          const glm::vec3 c = trefoil(u), d1 = (trefoil(u + e) - trefoil(u - e)) / (2.0f * e);
                          const glm::vec3 d2 = (trefoil(u + e) - 2.0f * c + trefoil(u - e)) / (e * e);
                          const glm::vec3 t = glm::normalize(d1);
                          const glm::vec3 nrm = glm::normalize(d2 - glm::dot(d2, t) * t),
                                          bin = glm::cross(t, nrm);
                          const float b = 2.0f * float(M_PI) * v;
                          const glm::vec3 n = std::cos(b) * nrm + std::sin(b) * bin;
                          return SurfacePoint{c + r * n, n};
                      });
}

io::ImageRgba8 brick_normal_map(uint32_t width, uint32_t height)
{
    return {
        width, height,
        bake::normal_map_from_height(brick_heights(width, height, 1.0f, 8.0f, 4.0f), width, height, 3.0f)};
}

io::ImageRgba8 brick_base_color(uint32_t width, uint32_t height)
{
    const std::vector<float> h = brick_heights(width, height, 1.0f, 8.0f, 4.0f);
    io::ImageRgba8 out{width, height, std::vector<uint8_t>(size_t(width) * height * 4)};
    const glm::vec3 mortar(0.55f, 0.53f, 0.50f), brick(0.60f, 0.28f, 0.18f);
    for (size_t i = 0; i < h.size(); ++i)
    {
        // A little per-brick variation, from the brick's cell.
        const uint32_t x = uint32_t(i % width), y = uint32_t(i / width);
        const uint32_t row = y * 4 / height, col = (x * 8 + (row % 2) * width / 2) / width;
        const float shade = 0.85f + 0.3f * float((row * 7 + col * 13) % 5) / 4.0f;
        const glm::vec3 c = glm::mix(mortar, brick * shade, h[i]);
        for (int k = 0; k < 3; ++k)
            out.pixels[i * 4 + k] =
                uint8_t(std::lround(255.0f * io::srgb_oetf(std::clamp(c[k], 0.0f, 1.0f))));
        out.pixels[i * 4 + 3] = 255;
    }
    return out;
}

std::filesystem::path write_prt_model(const std::filesystem::path& dir, const std::string& name,
                                      PrtModel model, float detail, bool flat)
{
    std::filesystem::create_directories(dir);
    const std::string normal = name + "_normal.png", base = name + "_base_color.png";
    if (!flat)
        io::write_png(dir / normal, brick_normal_map(512, 256));
    io::write_png(dir / base, brick_base_color(512, 256));
    const std::filesystem::path gltf = dir / (name + ".gltf");
    io::write_gltf(gltf, make_prt_model(model, detail), base, flat ? std::string() : normal);
    return gltf;
}

} // namespace hemi::samples
