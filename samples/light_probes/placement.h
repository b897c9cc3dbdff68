#pragma once
// How well probes light what moves through a level, placed automatically or on a grid of the same count
// (issue 44; the table in docs/probes.md, the tests and hemi-probe-placement): a level lit and baked in
// memory, and the mean error of each set's lookup (io::LightProbes::at) at random points of the level's open
// space against probes baked exactly there.

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/probe_placement.h>
#include <hemi/io/gltf.h>
#include <hemi/io/light_probes.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace hemi::samples
{

// A glTF scene's lightmap baked in memory (its own TEXCOORD_1, or unwrapped at `atlas` when `unwrap`), what
// probes take their light from.
struct LitLevel
{
    io::GltfScene scene;
    std::unique_ptr<bake::LightmapSurfaces> surfaces; // points at scene.mesh
    bake::LightmapAtlas atlas;
    bake::LightmapLights lights;
    bake::LightmapSh sh;
    glm::vec3 lo{0.0f}, hi{0.0f}; // the mesh's bounding box

    // rays and bounces of the lightmap's bake. Throws what the unwrap, the atlas and the bake throw.
    LitLevel(io::GltfScene scene, const bake::LightmapLights& lights, uint32_t atlas, bool unwrap, int rays,
             int bounces);
};

// The grid of about `count` probes over the level's box that hemi-bake lightmap --probes would bake, its
// cells as near to cubes as the count allows.
glm::uvec3 grid_of(const LitLevel& level, uint32_t count);

// `count` random points of the level's box in open space (bake::bake_probes_at finds them open), each with
// the probe baked there (`rays` rays): the reference the lookups are held to.
struct OpenPoints
{
    std::vector<glm::vec3> points;
    std::vector<std::array<glm::vec3, 9>> irradiance;
    size_t drawn = 0; // random points drawn to find them
};
OpenPoints open_points(const LitLevel& level, size_t count, int rays, uint64_t seed);

// The mean over the points of the SH9 coefficients' distance between `probes`' lookup and the point's own
// probe (sqrt(sum_j |c_j - c'_j|^2) over RGB), over the mean of the points' own SH9 norm.
double lookup_error(const io::LightProbes& probes, const OpenPoints& reference);

struct PlacementRow
{
    uint32_t budget = 0;
    glm::uvec3 grid{0};
    size_t grid_probes = 0, grid_inside = 0; // the grid's probes, and those inside geometry
    double grid_error = 0.0;
    bake::ProbePlacementReport placed;
    double placed_error = 0.0;
    double grid_seconds = 0.0, placed_seconds = 0.0;
    io::LightProbes placed_probes;
};
// A grid of about `budget` probes (at most budget) and automatic placement of as many probes as the grid
// has, both with `rays` rays a probe, held to `reference`.
PlacementRow compare_placement(const LitLevel& level, uint32_t budget, int rays, const OpenPoints& reference);

} // namespace hemi::samples
