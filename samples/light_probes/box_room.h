#pragma once
// The reflection probes' scene (issue 44; shared by tests/bake/reflection_probe_test.cpp and
// samples/light_probes' reflection figure): a closed room of 4 x 3 x 2.5 m (x, y, z up) lit only by an
// emissive panel in its ceiling (1 m wide, across the room), walls of three colours (a terracotta floor, a
// blue wall at +x, the rest grey) so that a direction mapped wrongly shows, its 256^2 lightmap baked with 2
// bounces of 512 rays.

#include "two_rooms.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <glm/vec3.hpp>

#include <vector>

namespace hemi::samples
{

inline constexpr glm::vec3 kBoxRoomMin(-2.0f, -1.5f, 0.0f), kBoxRoomMax(2.0f, 1.5f, 2.5f);

struct BoxRoom
{
    io::Mesh mesh;
    std::vector<io::Material> materials;
    std::vector<io::Primitive> primitives;
    bake::LightmapSurfaces surfaces;
    bake::LightmapAtlas atlas;
    bake::LightmapLights lights; // none but the panel's emission
    bake::LightmapSh sh;

    BoxRoom();
    BoxRoom(const BoxRoom&) = delete; // `surfaces` points at `mesh`
    BoxRoom& operator=(const BoxRoom&) = delete;
    static QuadList quads();
};

} // namespace hemi::samples
