// The light probes' two rooms (two_rooms.h).
#include "two_rooms.h"

#include <hemi/math/luminance.h>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

#include <cmath>
#include <stdexcept>
#include <utility>

namespace hemi::samples
{
using glm::vec3;

namespace
{

io::Material grey()
{
    io::Material m;
    m.name = "walls";
    m.base_color_factor = glm::vec4(0.6f, 0.6f, 0.6f, 1.0f);
    return m;
}

} // namespace

void QuadList::add(vec3 a, vec3 b, vec3 c, vec3 d)
{
    quads.push_back({a, b, c, d});
    materials.push_back(material);
}

void QuadList::wall_x(float at, float y0, float y1, float z0, float z1, bool plus)
{
    if (plus)
        add({at, y0, z0}, {at, y1, z0}, {at, y1, z1}, {at, y0, z1});
    else
        add({at, y1, z0}, {at, y0, z0}, {at, y0, z1}, {at, y1, z1});
}

void QuadList::wall_y(float at, float x0, float x1, float z0, float z1, bool plus)
{
    if (plus)
        add({x1, at, z0}, {x0, at, z0}, {x0, at, z1}, {x1, at, z1});
    else
        add({x0, at, z0}, {x1, at, z0}, {x1, at, z1}, {x0, at, z1});
}

void QuadList::wall_z(float at, float x0, float x1, float y0, float y1, bool plus)
{
    if (plus)
        add({x0, y0, at}, {x1, y0, at}, {x1, y1, at}, {x0, y1, at});
    else
        add({x0, y1, at}, {x1, y1, at}, {x1, y0, at}, {x0, y0, at});
}

io::Mesh QuadList::mesh() const
{
    io::Mesh m;
    const int side = int(std::ceil(std::sqrt(double(quads.size()))));
    const float cell = 1.0f / float(side), margin = 0.1f * cell;
    for (size_t i = 0; i < quads.size(); ++i)
    {
        const float u0 = float(int(i) % side) * cell + margin, v0 = float(int(i) / side) * cell + margin,
                    u1 = u0 + cell - 2 * margin, v1 = v0 + cell - 2 * margin;
        const auto& q = quads[i];
        const uint32_t base = uint32_t(m.positions.size());
        const vec3 n = glm::normalize(glm::cross(q[1] - q[0], q[3] - q[0]));
        const vec3 t = glm::normalize(q[1] - q[0]);
        const glm::vec2 uv[4] = {{u0, v1}, {u1, v1}, {u1, v0}, {u0, v0}};
        for (int k = 0; k < 4; ++k)
        {
            m.positions.push_back(q[size_t(k)]);
            m.normals.push_back(n);
            m.tangents.emplace_back(t, 1.0f);
            m.uvs.push_back(uv[k]);
            m.uvs1.push_back(uv[k]);
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    return m;
}

std::vector<io::Primitive> QuadList::primitives() const
{
    std::vector<io::Primitive> out;
    for (size_t i = 0; i < quads.size(); ++i)
        if (!out.empty() && out.back().material == materials[i])
            out.back().index_count += 6;
        else
            out.push_back({uint32_t(6 * i), 6, materials[i]});
    return out;
}

io::Mesh two_rooms_mesh(bool door)
{
    QuadList q;
    const float w = -2.05f, e = 2.05f, a = -0.05f, b = 0.05f;
    // The west room: floor, outer walls, the shared wall's west face (no ceiling).
    q.wall_z(0, w, a, 0, 2, true);
    q.wall_x(w, 0, 2, 0, 2, true);
    q.wall_y(0, w, a, 0, 2, true);
    q.wall_y(2, w, a, 0, 2, false);
    // The east room: floor, ceiling, outer walls, the shared wall's east face.
    q.wall_z(0, b, e, 0, 2, true);
    q.wall_z(2, b, e, 0, 2, false);
    q.wall_x(e, 0, 2, 0, 2, false);
    q.wall_y(0, b, e, 0, 2, true);
    q.wall_y(2, b, e, 0, 2, false);
    // The shared wall's faces, around the door if there is one, and its top and bottom.
    for (const auto& [at, plus] : {std::pair{a, false}, std::pair{b, true}})
        if (door)
        {
            q.wall_x(at, 0, 0.7f, 0, 2, plus);
            q.wall_x(at, 1.3f, 2, 0, 2, plus);
            q.wall_x(at, 0.7f, 1.3f, 1.4f, 2, plus);
        }
        else
        {
            q.wall_x(at, 0, 2, 0, 2, plus);
        }
    q.wall_z(2, a, b, 0, 2, true);
    q.wall_z(0, a, b, 0, 2, true);
    if (door) // the jambs face into the doorway, the lintel down, the threshold up
    {
        q.wall_y(0.7f, a, b, 0, 1.4f, true);
        q.wall_y(1.3f, a, b, 0, 1.4f, false);
        q.wall_z(1.4f, a, b, 0.7f, 1.3f, false);
        q.wall_z(0, a, b, 0.7f, 1.3f, true);
    }
    return q.mesh();
}

TwoRooms::TwoRooms(bool door, bool sun)
    : mesh(two_rooms_mesh(door)), materials{grey()}, primitives{{0, uint32_t(mesh.indices.size()), 0}},
      surfaces(mesh, materials, {}, primitives)
{
    bake::LightmapUvReport report;
    atlas = bake::rasterize_lightmap(mesh, 128, 128, report);
    if (!report.ok())
        throw std::runtime_error("the two rooms' lightmap UVs: " + report.problems[0]);
    lights.uniform = vec3(0.5f);
    lights.sun = sun;
    lights.sun_direction = glm::normalize(vec3(-0.5f, 0.2f, 0.85f)); // onto the shared wall's west face
    lights.sun_irradiance = vec3(3.0f);
    bake::LightmapBakeOptions o;
    o.rays = 128;
    o.bounces = 2;
    sh = bake::bake_lightmap_sh(mesh, atlas, lights, o, &surfaces);
}

io::LightProbes TwoRooms::probes(glm::uvec3 count, vec3 lo, vec3 hi, int rays, uint32_t depth) const
{
    io::LightProbes p;
    p.count = count;
    p.lo = lo;
    p.hi = hi;
    p.depth_resolution = depth;
    bake::LightmapBakeOptions o;
    o.rays = rays;
    bake::bake_light_probes(p, mesh, atlas, sh, lights, o, &surfaces);
    return p;
}

io::LightProbes TwoRooms::grid(glm::uvec3 count, int rays) const
{
    const io::LightProbes g = bake::probe_grid(mesh, count);
    return probes(count, g.lo, g.hi, rays, g.depth_resolution);
}

double received_light(const std::array<vec3, 9>& sh9)
{
    return math::luminance(glm::dvec3(sh9[0]));
}

io::LightProbes without_visibility(io::LightProbes p)
{
    p.depth.clear();
    p.depth_resolution = 0;
    return p;
}

} // namespace hemi::samples
