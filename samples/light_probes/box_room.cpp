// The reflection probes' box room (box_room.h).
#include "box_room.h"

#include <stdexcept>

namespace hemi::samples
{
namespace
{

io::Material material(glm::vec3 albedo, glm::vec3 emission = glm::vec3(0.0f))
{
    io::Material m;
    m.base_color_factor = glm::vec4(albedo, 1.0f);
    m.emissive_factor = emission;
    return m;
}

std::vector<io::Material> box_room_materials()
{
    return {material(glm::vec3(0.6f)), material({0.7f, 0.4f, 0.3f}), material({0.3f, 0.4f, 0.7f}),
            material(glm::vec3(0.5f), glm::vec3(4.0f, 4.0f, 3.5f))};
}

} // namespace

QuadList BoxRoom::quads()
{
    QuadList q;
    const glm::vec3 a = kBoxRoomMin, b = kBoxRoomMax;
    q.material = 1; // a terracotta floor
    q.wall_z(a.z, a.x, b.x, a.y, b.y, true);
    q.material = 2; // a blue wall at +x
    q.wall_x(b.x, a.y, b.y, a.z, b.z, false);
    q.material = 0;
    q.wall_x(a.x, a.y, b.y, a.z, b.z, true);
    q.wall_y(a.y, a.x, b.x, a.z, b.z, true);
    q.wall_y(b.y, a.x, b.x, a.z, b.z, false);
    q.wall_z(b.z, a.x, -0.5f, a.y, b.y, false);
    q.wall_z(b.z, 0.5f, b.x, a.y, b.y, false);
    q.material = 3; // the light: a panel in the ceiling
    q.wall_z(b.z, -0.5f, 0.5f, a.y, b.y, false);
    return q;
}

BoxRoom::BoxRoom()
    : mesh(quads().mesh()), materials(box_room_materials()), primitives(quads().primitives()),
      surfaces(mesh, materials, {}, primitives)
{
    bake::LightmapUvReport report;
    atlas = bake::rasterize_lightmap(mesh, 256, 256, report);
    if (!report.ok())
        throw std::runtime_error("the box room's lightmap UVs: " + report.problems[0]);
    lights.uniform = glm::vec3(0.0f);
    bake::LightmapBakeOptions o;
    o.rays = 512;
    o.bounces = 2;
    sh = bake::bake_lightmap_sh(mesh, atlas, lights, o, &surfaces);
}

} // namespace hemi::samples
