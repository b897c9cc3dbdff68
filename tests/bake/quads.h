#pragma once
// Quads and planes for the lightmap and reference tests, with normal-map and lightmap UVs.
#include <hemi/io/image.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace hemi::test
{

// A quad p0 p1 p2 p3 (counter-clockwise seen from its front), split into (0, 1, 2) and (0, 2, 3), with
// lightmap UVs spanning [u0, u1] x [v0, v1] and the normal-map UV frame along p1 - p0.
inline void add_quad(io::Mesh& m, glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 p3, glm::vec4 uv1)
{
    const uint32_t base = uint32_t(m.positions.size());
    const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p3 - p0));
    const glm::vec3 t = glm::normalize(p1 - p0);
    const glm::vec3 p[4] = {p0, p1, p2, p3};
    const glm::vec2 uv[4] = {{uv1.x, uv1.y}, {uv1.z, uv1.y}, {uv1.z, uv1.w}, {uv1.x, uv1.w}};
    for (int i = 0; i < 4; ++i)
    {
        m.positions.push_back(p[i]);
        m.normals.push_back(n);
        m.tangents.emplace_back(t, 1.0f);
        m.uvs.push_back(uv[i]);
        m.uvs1.push_back(uv[i]);
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

// The denoiser's floor-and-wall scene: a 2 x 2 floor (z = 0) with a wall 0.5 high standing on it at x = -0.2,
// both its sides, each quad a chart of its own in a 64 x 64 atlas (the floor's 38 texels a side, the wall's
// 10 high).
inline void add_floor_and_wall(io::Mesh& m)
{
    add_quad(m, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {0.02f, 0.62f, 0.62f, 0.02f}); // the floor
    add_quad(m, {-0.2f, 1, 0}, {-0.2f, -1, 0}, {-0.2f, -1, 0.5f}, {-0.2f, 1, 0.5f},
             {0.66f, 0.62f, 0.81f, 0.02f});
    add_quad(m, {-0.2f, -1, 0}, {-0.2f, 1, 0}, {-0.2f, 1, 0.5f}, {-0.2f, -1, 0.5f},
             {0.83f, 0.62f, 0.98f, 0.02f});
}

// The plane z = 0 over [-1, 1]^2 as `cells` x `cells` quads, lightmap UVs over [0, 1]^2 (v down the image:
// v = 0 at y = +1).
inline io::Mesh plane(int cells)
{
    io::Mesh m;
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i)
        {
            const float u0 = float(i) / cells, u1 = float(i + 1) / cells, v0 = float(j) / cells,
                        v1 = float(j + 1) / cells;
            auto at = [](float u, float v) { return glm::vec3(2.0f * u - 1.0f, 1.0f - 2.0f * v, 0.0f); };
            add_quad(m, at(u0, v1), at(u1, v1), at(u1, v0), at(u0, v0), {u0, v1, u1, v0});
        }
    return m;
}

// The cube [-1, 1]^3 as six quads, facing into it (`inward`) or out of it, each face's lightmap UVs in its
// own cell of a 3 x 2 grid over [0, 1]^2 (with a margin), so the atlas has no overlaps.
inline io::Mesh unit_box(bool inward)
{
    io::Mesh m;
    const glm::vec3 c[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                            {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    // Counter-clockwise seen from outside; reversed for the inside.
    const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                             {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    for (int f = 0; f < 6; ++f)
    {
        const float u0 = float(f % 3) / 3.0f + 0.02f, v0 = float(f / 3) / 2.0f + 0.03f;
        const glm::vec4 uv1(u0, v0 + 0.44f, u0 + 0.29f, v0);
        const int* q = faces[f];
        if (inward)
            add_quad(m, c[q[3]], c[q[2]], c[q[1]], c[q[0]], uv1);
        else
            add_quad(m, c[q[0]], c[q[1]], c[q[2]], c[q[3]], uv1);
    }
    return m;
}

// An 8-bit sRGB code as linear, typed from the sRGB standard (IEC 61966-2-1): 128 is 0.2158 (not 0.502).
inline double srgb_decode(int code)
{
    const double v = code / 255.0;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// One material for a whole closed box: a base colour factor times a base colour texture and an emissive
// factor times an emissive texture, each texture (when given) one sRGB colour over 2 x 2 texels, and the
// linear albedo and emission that gives, decoded here. Every channel differs.
struct ColouredMaterial
{
    std::vector<io::Material> materials;
    std::vector<io::EncodedImage> images;
    glm::dvec3 albedo{0.0}, emission{0.0};

    ColouredMaterial(glm::vec3 base_factor, glm::vec3 emissive_factor, const uint8_t* base_srgb = nullptr,
                     const uint8_t* emissive_srgb = nullptr)
    {
        io::Material m;
        m.base_color_factor = glm::vec4(base_factor, 1.0f);
        m.emissive_factor = emissive_factor;
        albedo = glm::dvec3(base_factor);
        emission = glm::dvec3(emissive_factor);
        auto texture = [&](const uint8_t* srgb, io::TextureRef& ref, glm::dvec3& value)
        {
            if (!srgb)
                return;
            io::ImageRgba8 image{2, 2, std::vector<uint8_t>(16, 255)};
            for (size_t i = 0; i < 16; ++i)
                if (i % 4 != 3)
                    image.pixels[i] = srgb[i % 4];
            ref.image = int(images.size());
            images.push_back(
                {"texture " + std::to_string(images.size()), "image/png", io::encode_png(image)});
            value *= glm::dvec3(srgb_decode(srgb[0]), srgb_decode(srgb[1]), srgb_decode(srgb[2]));
        };
        texture(base_srgb, m.base_color, albedo);
        texture(emissive_srgb, m.emissive, emission);
        materials.push_back(m);
    }
};

} // namespace hemi::test
