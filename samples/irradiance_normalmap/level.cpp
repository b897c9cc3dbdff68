#include "level.h"

#include <hemi/bake/ssbump.h>
#include <hemi/io/image.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::samples
{
namespace
{

struct Quad
{
    glm::vec3 p0, u, v; // corner and edges (counter-clockwise seen from the front: u then v)
    uint32_t material;
};

// A tangent-space normal map (glTF's: +y up the image) of the height field `height(u, v)` over one unit of UV
// (v down the image), by central differences, 8-bit PNG.
template <class Height> io::EncodedImage normal_map(const std::string& name, uint32_t size, Height height)
{
    io::ImageRgba8 image{size, size, std::vector<uint8_t>(size_t(size) * size * 4)};
    const float step = 1.0f / float(size);
    for (uint32_t y = 0; y < size; ++y)
        for (uint32_t x = 0; x < size; ++x)
        {
            const float u = (float(x) + 0.5f) * step, v = (float(y) + 0.5f) * step;
            const float hu = (height(u + step, v) - height(u - step, v)) / (2.0f * step);
            const float hv = (height(u, v + step) - height(u, v - step)) / (2.0f * step);
            // Tangent x along +u, y along -v (up the image): n ~ (-dh/du, dh/dv, 1).
            const glm::vec3 n = glm::normalize(glm::vec3(-hu, hv, 1.0f));
            uint8_t* p = &image.pixels[(size_t(y) * size + x) * 4];
            for (int c = 0; c < 3; ++c)
                p[c] = uint8_t(std::lround((n[c] * 0.5f + 0.5f) * 255.0f));
            p[3] = 255;
        }
    return {name, "image/png", io::encode_png(image)};
}

// The SSBump map (normalised convention, directional occlusion from 300 rays a texel) of the same height
// field, its highest point `top` world units up: heights over one UV unit of `size` texels.
template <class Height>
io::EncodedImage ssbump_map(const std::string& name, uint32_t size, Height height, float top)
{
    bake::HeightField field{size, size, std::vector<float>(size_t(size) * size)};
    for (uint32_t y = 0; y < size; ++y)
        for (uint32_t x = 0; x < size; ++x)
            field.heights[size_t(y) * size + x] =
                height((float(x) + 0.5f) / float(size), (float(y) + 0.5f) / float(size)) / top;
    bake::SsbumpOptions o;
    o.scale = top * float(size); // world units to texel widths
    const bake::SsbumpMap m = bake::bake_ssbump(field, o);
    return {name, "image/png", io::encode_png({size, size, bake::ssbump_rgba8(m.weights, {}, false)})};
}

// Height of a bevelled block whose edges are `d` away: rising at `slope` over the bevel `width`, flat on top.
float bevel(float d, float width, float slope)
{
    return std::min(d, width) * slope;
}

float fract(float x)
{
    return x - std::floor(x);
}

} // namespace

io::GltfScene make_level(uint32_t atlas, LevelMaps maps)
{
    if (atlas < 64)
        throw std::invalid_argument("make_level: atlas " + std::to_string(atlas) + " is smaller than 64");
    // glTF space: y up. The room spans x, z in [-4, 4], y in [0, 3]; the walls face inwards.
    std::vector<Quad> quads;
    const float h = 3.0f, s = 4.0f;
    quads.push_back({{-s, 0, s}, {2 * s, 0, 0}, {0, 0, -2 * s}, 0}); // floor, facing +y
    quads.push_back({{-s, h, -s}, {2 * s, 0, 0}, {0, 0, 2 * s}, 0}); // ceiling, facing -y
    // Wall at z = -s (facing +z) in full; wall at z = +s (facing -z) with a window from x -1 to 1, y 1 to 2.
    quads.push_back({{-s, 0, -s}, {2 * s, 0, 0}, {0, h, 0}, 1});
    quads.push_back({{s, 0, s}, {-(s - 1), 0, 0}, {0, h, 0}, 1});  // right of the window
    quads.push_back({{-1, 0, s}, {-(s - 1), 0, 0}, {0, h, 0}, 1}); // left of the window
    quads.push_back({{1, 0, s}, {-2, 0, 0}, {0, 1, 0}, 1});        // below it
    quads.push_back({{1, 2, s}, {-2, 0, 0}, {0, h - 2, 0}, 1});    // above it
    // Wall at x = -s (facing +x) with a wide opening from z -2 to 2 up to y 2.2; wall at x = +s (facing -x).
    quads.push_back({{-s, 0, s}, {0, 0, -(s - 2)}, {0, h, 0}, 2});
    quads.push_back({{-s, 0, -2}, {0, 0, -(s - 2)}, {0, h, 0}, 2});
    quads.push_back({{-s, 2.2f, 2}, {0, 0, -4}, {0, h - 2.2f, 0}, 2});
    quads.push_back({{s, 0, -s}, {0, 0, 2 * s}, {0, h, 0}, 3});
    // Four pillars, 0.6 wide, facing out.
    for (float px : {-2.0f, 2.0f})
        for (float pz : {-2.0f, 2.0f})
        {
            const float r = 0.3f;
            quads.push_back({{px - r, 0, pz + r}, {2 * r, 0, 0}, {0, h, 0}, 0});  // +z
            quads.push_back({{px + r, 0, pz - r}, {-2 * r, 0, 0}, {0, h, 0}, 0}); // -z
            quads.push_back({{px + r, 0, pz + r}, {0, 0, -2 * r}, {0, h, 0}, 0}); // +x
            quads.push_back({{px - r, 0, pz - r}, {0, 0, 2 * r}, {0, h, 0}, 0});  // -x
        }

    // Pack the charts: each quad's size in texels at the density that fills about 70% of the atlas, shelf by
    // shelf (tallest first), with a gap of 2 texels.
    double area = 0.0;
    for (const Quad& q : quads)
        area += double(glm::length(q.u)) * double(glm::length(q.v));
    const double gap = 2.0;
    double density = std::sqrt(0.7 * double(atlas) * double(atlas) / area); // texels per unit
    std::vector<size_t> order(quads.size());
    for (size_t i = 0; i < order.size(); ++i)
        order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return glm::length(quads[a].v) > glm::length(quads[b].v); });
    std::vector<glm::vec4> rect(quads.size()); // u0, v0, u1, v1 in texels
    for (int attempt = 0;; ++attempt)
    {
        double x = gap, y = gap, shelf = 0.0;
        bool fits = true;
        for (size_t i : order)
        {
            const double w = std::ceil(glm::length(quads[i].u) * density),
                         t = std::ceil(glm::length(quads[i].v) * density);
            if (x + w + gap > atlas)
            {
                x = gap;
                y += shelf + gap;
                shelf = 0.0;
            }
            rect[i] = glm::vec4(float(x), float(y), float(x + w), float(y + t));
            x += w + gap;
            shelf = std::max(shelf, t);
            fits = fits && y + t + gap <= atlas;
        }
        if (fits)
            break;
        density *= 0.95;
        if (attempt > 60)
            throw std::runtime_error("make_level: the charts do not fit");
    }

    io::GltfScene scene;
    io::Mesh& m = scene.mesh;
    const glm::vec4 colours[4] = {
        {0.75f, 0.75f, 0.72f, 1}, {0.8f, 0.25f, 0.2f, 1}, {0.25f, 0.7f, 0.3f, 1}, {0.3f, 0.35f, 0.8f, 1}};
    for (int k = 0; k < 4; ++k)
    {
        io::Material mat;
        mat.name = k == 0 ? "plaster" : k == 1 ? "red wall" : k == 2 ? "green wall" : "blue wall";
        mat.base_color_factor = colours[k];
        scene.materials.push_back(mat);
    }
    // Tiles of 0.5 units (two per UV unit), bevelled over 0.06 at 45 degrees; bricks 0.5 x 0.25 in running
    // bond, mortar joints bevelled over 0.04 at 50 degrees. Heights in world units over one UV unit.
    const auto tiles = [](float u, float v)
    {
        const float x = fract(u * 2.0f), y = fract(v * 2.0f);
        const float d = std::min(std::min(x, 1.0f - x), std::min(y, 1.0f - y)) * 0.5f;
        return bevel(d, 0.06f, 1.0f);
    };
    const auto bricks = [](float u, float v)
    {
        const float row = std::floor(v * 4.0f);
        const float x = fract(u * 2.0f + 0.5f * row), y = fract(v * 4.0f);
        const float d = std::min(std::min(x, 1.0f - x) * 0.5f, std::min(y, 1.0f - y) * 0.25f);
        return bevel(d, 0.04f, 1.19f);
    };
    if (maps == LevelMaps::Normal || maps == LevelMaps::SsbumpWall)
    {
        scene.images.push_back(normal_map("tiles normal map", 256, tiles));
        scene.images.push_back(normal_map("bricks normal map", 256, bricks));
    }
    else if (maps == LevelMaps::Ssbump)
    {
        scene.images.push_back(ssbump_map("tiles ssbump map", 256, tiles, 0.06f));
        scene.images.push_back(ssbump_map("bricks ssbump map", 256, bricks, 0.04f * 1.19f));
    }
    if (maps != LevelMaps::None)
        for (size_t k = 0; k < scene.materials.size(); ++k)
            scene.materials[k].normal.image = k == 0 ? 0 : 1;
    if (maps == LevelMaps::SsbumpWall)
    {
        scene.images.push_back(ssbump_map("bricks ssbump map", 256, bricks, 0.04f * 1.19f));
        scene.materials[3].normal.image = 2;
        scene.materials[3].technique = "ssbump";
    }
    // One primitive per material: quads grouped by material.
    for (uint32_t material = 0; material < 4; ++material)
    {
        const uint32_t first = uint32_t(m.indices.size());
        for (size_t i = 0; i < quads.size(); ++i)
        {
            const Quad& q = quads[i];
            if (q.material != material)
                continue;
            const glm::vec3 n = glm::normalize(glm::cross(q.u, q.v));
            const glm::vec3 t = glm::normalize(q.u);
            const uint32_t base = uint32_t(m.positions.size());
            const glm::vec2 corner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            for (const glm::vec2& c : corner)
            {
                m.positions.push_back(q.p0 + c.x * q.u + c.y * q.v);
                m.normals.push_back(n);
                m.tangents.emplace_back(t, 1.0f);
                // Normal-map UVs in world units; v grows down the image, so up the quad is -v.
                m.uvs.emplace_back(c.x * glm::length(q.u), -c.y * glm::length(q.v));
                const glm::vec4& r = rect[i];
                m.uvs1.emplace_back((r.x + c.x * (r.z - r.x)) / float(atlas),
                                    (r.w - c.y * (r.w - r.y)) / float(atlas));
            }
            m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        }
        scene.primitives.push_back({first, uint32_t(m.indices.size()) - first, material});
    }
    return scene;
}

} // namespace hemi::samples
