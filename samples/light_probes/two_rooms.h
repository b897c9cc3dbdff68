#pragma once
// The light probes' scene (issue 44; shared by samples/light_probes, the tests and docs/probes.md): two rooms
// of 2 x 2 x 2 m side by side along x, sharing a wall 10 cm thick. The west room (x in [-2.05, -0.05]) has no
// ceiling and takes a uniform sky of 0.5 and, optionally, a sun of 3 that lights the shared wall's west face;
// the east room (x in [0.05, 2.05]) is closed: sealed, or with a door through the shared wall (y in [0.7,
// 1.3], z in [0, 1.4]). Every surface faces into its room, albedo 0.6; each quad is a chart of its own in a
// 128^2 atlas. Baked with 2 bounces of 128 rays.

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/light_probes.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <glm/vec3.hpp>

#include <array>
#include <vector>

namespace hemi::samples
{

// A level made of axis-aligned rectangles, each its own chart in a grid of lightmap UV cells (TEXCOORD_0
// the same), each with the material `material` held when it was added.
struct QuadList
{
    std::vector<std::array<glm::vec3, 4>> quads; // counter-clockwise seen from the front
    std::vector<uint32_t> materials;
    uint32_t material = 0;
    void add(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d);
    // At x = `at` over [y0, y1] x [z0, z1], facing +x (`plus`) or -x; and the same along y and z.
    void wall_x(float at, float y0, float y1, float z0, float z1, bool plus);
    void wall_y(float at, float x0, float x1, float z0, float z1, bool plus);
    void wall_z(float at, float x0, float x1, float y0, float y1, bool plus);
    io::Mesh mesh() const;
    std::vector<io::Primitive> primitives() const; // consecutive quads of one material in one primitive
};

io::Mesh two_rooms_mesh(bool door);

struct TwoRooms
{
    io::Mesh mesh;
    std::vector<io::Material> materials;
    std::vector<io::Primitive> primitives;
    bake::LightmapSurfaces surfaces;
    bake::LightmapAtlas atlas;
    bake::LightmapLights lights;
    bake::LightmapSh sh;

    TwoRooms(bool door, bool sun);
    TwoRooms(const TwoRooms&) = delete; // `surfaces` points at `mesh`
    TwoRooms& operator=(const TwoRooms&) = delete;

    // Probes at `count` points over [lo, hi] (bake_light_probes' grid), `rays` each, with depth maps of
    // `depth` texels a side (0: none).
    io::LightProbes probes(glm::uvec3 count, glm::vec3 lo, glm::vec3 hi, int rays,
                           uint32_t depth = bake::kProbeDepthResolution) const;
    // The grid hemi-bake lightmap --probes would place: the scene's bounding box in `count` cells.
    io::LightProbes grid(glm::uvec3 count, int rays) const;
};

// The light an object receives averaged over its normals: the luminance of the SH9 irradiance's constant
// term.
double received_light(const std::array<glm::vec3, 9>& sh9);

// The same probes without their depth maps: the trilinear lookup alone, as before visibility.
io::LightProbes without_visibility(io::LightProbes probes);

} // namespace hemi::samples
