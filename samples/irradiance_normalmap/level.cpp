#include "level.h"

#include <hemi/bake/ssbump.h>
#include <hemi/io/image.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
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

// The level made of `quads`: each quad its own lightmap chart, packed shelf by shelf into the atlas at one
// texel density (about 70% of the atlas), with the materials, maps and primitives of make_level.
io::GltfScene scene_from_quads(const std::vector<Quad>& quads, uint32_t atlas, LevelMaps maps,
                               const char* who)
{
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
            throw std::runtime_error(std::string(who) + ": the charts do not fit");
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
        // The floor's own material (kPolishedFloor), its tiles darker than the plaster: the engine sample
        // gives it a GGX coat.
        io::Material floor = scene.materials[0];
        floor.name = "polished floor";
        floor.base_color_factor = glm::vec4(0.42f, 0.4f, 0.37f, 1.0f);
        scene.materials.push_back(floor);
    }
    // One primitive per material: quads grouped by material (a quad of a material the scene lacks is the
    // plaster's).
    const uint32_t materials = uint32_t(scene.materials.size());
    for (uint32_t material = 0; material < materials; ++material)
    {
        const uint32_t first = uint32_t(m.indices.size());
        for (size_t i = 0; i < quads.size(); ++i)
        {
            const Quad& q = quads[i];
            if ((q.material < materials ? q.material : 0) != material)
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

} // namespace

io::GltfScene make_level(uint32_t atlas, LevelMaps maps)
{
    if (atlas < 64)
        throw std::invalid_argument("make_level: atlas " + std::to_string(atlas) + " is smaller than 64");
    // glTF space: y up. The room spans x, z in [-4, 4], y in [0, 3]; the walls face inwards.
    std::vector<Quad> quads;
    const float h = 3.0f, s = 4.0f;
    quads.push_back({{-s, 0, s}, {2 * s, 0, 0}, {0, 0, -2 * s}, kPolishedFloor}); // floor, facing +y
    quads.push_back({{-s, h, -s}, {2 * s, 0, 0}, {0, 0, 2 * s}, 0});              // ceiling, facing -y
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
    return scene_from_quads(quads, atlas, maps, "make_level");
}

namespace
{

// An opening in a wall: [a, b] along it, [y0, y1] up, and whether its reveals (the faces of the wall's
// thickness around it) belong to this wall (a doorway between two spaces has one set, not two).
struct Opening
{
    float a, b, y0, y1;
    bool reveals;
};

// One inward-facing wall of a space: from `p0` (its bottom corner on the left, seen from inside) along `u`
// (unit) for `length`, `height` up, with openings; the wall is `thickness` thick behind it.
void wall(std::vector<Quad>& quads, glm::vec3 p0, glm::vec3 u, float length, float height, float thickness,
          std::vector<Opening> openings, uint32_t material)
{
    const glm::vec3 up(0, 1, 0), in = glm::cross(u, up), back = -thickness * in;
    std::sort(openings.begin(), openings.end(), [](const Opening& x, const Opening& y) { return x.a < y.a; });
    // A quad over [a0, a1] x [y0, y1] of the wall's plane, facing in.
    auto face = [&](float a0, float a1, float y0, float y1)
    {
        if (a1 - a0 > 1e-4f && y1 - y0 > 1e-4f)
            quads.push_back({p0 + a0 * u + y0 * up, (a1 - a0) * u, (y1 - y0) * up, material});
    };
    // A quad p + s e1 + t e2 facing `facing` (e1 and e2 swapped when they turn the other way).
    auto facing = [&](glm::vec3 p, glm::vec3 e1, glm::vec3 e2, glm::vec3 f)
    {
        if (glm::dot(glm::cross(e1, e2), f) < 0.0f)
            std::swap(e1, e2);
        quads.push_back({p, e1, e2, material});
    };
    float at = 0.0f;
    for (const Opening& o : openings)
    {
        face(at, o.a, 0.0f, height);
        face(o.a, o.b, 0.0f, o.y0);
        face(o.a, o.b, o.y1, height);
        at = o.b;
        if (!o.reveals)
            continue;
        const glm::vec3 left = p0 + o.a * u, right = p0 + o.b * u;
        facing(left + o.y0 * up, back, (o.y1 - o.y0) * up, u);   // left reveal, facing right
        facing(right + o.y0 * up, back, (o.y1 - o.y0) * up, -u); // right reveal, facing left
        facing(left + o.y1 * up, back, (o.b - o.a) * u, -up);    // head, facing down
        facing(left + o.y0 * up, back, (o.b - o.a) * u, up);     // sill (a door's threshold), facing up
    }
    face(at, length, 0.0f, height);
}

// The inside of an axis-aligned box [x0, x1] x [0, height] x [z0, z1]: floor, ceiling and four walls, each
// wall with its openings (-z, +x, +z, -x side: openings[0..3], along each wall as wall() measures it).
void space(std::vector<Quad>& quads, float x0, float z0, float x1, float z1, float height, float thickness,
           const std::array<std::vector<Opening>, 4>& openings, uint32_t floor_material,
           uint32_t wall_material)
{
    quads.push_back({{x0, 0, z1}, {x1 - x0, 0, 0}, {0, 0, z0 - z1}, floor_material});      // floor, +y
    quads.push_back({{x0, height, z0}, {x1 - x0, 0, 0}, {0, 0, z1 - z0}, floor_material}); // ceiling, -y
    wall(quads, {x0, 0, z0}, {1, 0, 0}, x1 - x0, height, thickness, openings[0], wall_material);  // at z0, +z
    wall(quads, {x1, 0, z0}, {0, 0, 1}, z1 - z0, height, thickness, openings[1], wall_material);  // at x1, -x
    wall(quads, {x1, 0, z1}, {-1, 0, 0}, x1 - x0, height, thickness, openings[2], wall_material); // at z1, -z
    wall(quads, {x0, 0, z1}, {0, 0, -1}, z1 - z0, height, thickness, openings[3], wall_material); // at x0, +x
}

} // namespace

io::GltfScene make_large_level(uint32_t rooms_x, uint32_t rooms_z, uint32_t atlas, LevelMaps maps)
{
    if (rooms_x < 1 || rooms_z < 1 || rooms_x > 64 || rooms_z > 64)
        throw std::invalid_argument("make_large_level: " + std::to_string(rooms_x) + " x " +
                                    std::to_string(rooms_z) + " rooms is not in [1, 64] per side");
    if (atlas < 64)
        throw std::invalid_argument("make_large_level: atlas " + std::to_string(atlas) +
                                    " is smaller than 64");
    // Rooms of 8 x 8 x 3 (x, z, y) in rows along x, walls 0.3 thick; between two rows a corridor 3 wide.
    const float W = 8.0f, H = 3.0f, T = 0.3f, C = 3.0f;
    const Opening door{W / 2 - 0.6f, W / 2 + 0.6f, 0.0f, 2.2f, false};
    const Opening door_reveals{door.a, door.b, door.y0, door.y1, true};
    const Opening window{W / 2 - 1.2f, W / 2 + 1.2f, 0.9f, 2.1f, true};
    const float length = float(rooms_x) * (W + T) - T; // of the rows and the corridors
    std::vector<Quad> quads;
    for (uint32_t j = 0; j < rooms_z; ++j)
    {
        const float z0 = float(j) * (W + 2 * T + C), z1 = z0 + W;
        for (uint32_t i = 0; i < rooms_x; ++i)
        {
            const float x0 = float(i) * (W + T), x1 = x0 + W;
            std::array<std::vector<Opening>, 4> o;
            o[0].push_back(j == 0 ? window : door);                   // -z: outside, or the corridor before
            o[2].push_back(j + 1 == rooms_z ? window : door_reveals); // +z: outside, or the corridor after
            o[3].push_back(i == 0 ? window : door);                   // -x: outside, or the room before
            o[1].push_back(i + 1 == rooms_x ? window : door_reveals); // +x: outside, or the room after
            space(quads, x0, z0, x1, z1, H, T, o, 0, 1 + (i + j) % 3);
            // Four pillars, 0.5 wide, facing out.
            for (const float px : {x0 + W / 4, x1 - W / 4})
                for (const float pz : {z0 + W / 4, z1 - W / 4})
                {
                    const float r = 0.25f;
                    quads.push_back({{px - r, 0, pz + r}, {2 * r, 0, 0}, {0, H, 0}, 0});  // +z
                    quads.push_back({{px + r, 0, pz - r}, {-2 * r, 0, 0}, {0, H, 0}, 0}); // -z
                    quads.push_back({{px + r, 0, pz + r}, {0, 0, -2 * r}, {0, H, 0}, 0}); // +x
                    quads.push_back({{px - r, 0, pz - r}, {0, 0, 2 * r}, {0, H, 0}, 0});  // -x
                }
        }
        if (j + 1 == rooms_z)
            break;
        // The corridor after row j: a door to every room on either side (the reveals towards row j are its
        // rooms', those towards row j + 1 the corridor's), a window at each end.
        const float c0 = z1 + T, c1 = c0 + C;
        std::array<std::vector<Opening>, 4> o;
        for (uint32_t i = 0; i < rooms_x; ++i)
        {
            const float centre = float(i) * (W + T) + W / 2;
            o[0].push_back({centre - 0.6f, centre + 0.6f, 0.0f, 2.2f, false});                  // row j
            o[2].push_back({length - centre - 0.6f, length - centre + 0.6f, 0.0f, 2.2f, true}); // row j + 1
        }
        o[1].push_back({C / 2 - 0.8f, C / 2 + 0.8f, 0.9f, 2.1f, true});
        o[3].push_back({C / 2 - 0.8f, C / 2 + 0.8f, 0.9f, 2.1f, true});
        space(quads, 0.0f, c0, length, c1, H, T, o, 0, 0);
    }
    return scene_from_quads(quads, atlas, maps, "make_large_level");
}

} // namespace hemi::samples
