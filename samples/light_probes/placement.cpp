// Automatic probe placement against a grid of the same count (placement.h).
#include "placement.h"

#include <hemi/bake/lightmap_unwrap.h>
#include <hemi/bake/ray_generator.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::samples
{
namespace
{

double sh_distance(const std::array<glm::vec3, 9>& a, const std::array<glm::vec3, 9>& b)
{
    double s = 0.0;
    for (size_t j = 0; j < 9; ++j)
        for (int c = 0; c < 3; ++c)
        {
            const double d = double(a[j][c]) - double(b[j][c]);
            s += d * d;
        }
    return std::sqrt(s);
}

double seconds_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

} // namespace

LitLevel::LitLevel(io::GltfScene s, const bake::LightmapLights& l, uint32_t size, bool unwrap, int rays,
                   int bounces)
    : scene(std::move(s)), lights(l)
{
    if (unwrap)
    {
        bake::UnwrapOptions u;
        u.width = u.height = size;
        bake::unwrap_lightmap(scene.mesh, u);
    }
    surfaces =
        std::make_unique<bake::LightmapSurfaces>(scene.mesh, scene.materials, scene.images, scene.primitives);
    bake::LightmapUvReport report;
    atlas = bake::rasterize_lightmap(scene.mesh, size, size, report);
    bake::LightmapBakeOptions o;
    o.rays = rays;
    o.bounces = bounces;
    sh = bake::bake_lightmap_sh(scene.mesh, atlas, lights, o, surfaces.get());
    lo = glm::vec3(INFINITY);
    hi = glm::vec3(-INFINITY);
    for (const glm::vec3& p : scene.mesh.positions)
    {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
}

glm::uvec3 grid_of(const LitLevel& level, uint32_t count)
{
    const glm::vec3 extent = glm::max(level.hi - level.lo, glm::vec3(1e-6f));
    float side = 0.8f * std::cbrt(extent.x * extent.y * extent.z / float(count));
    for (;; side *= 1.01f)
    {
        const glm::uvec3 n = glm::max(glm::uvec3(glm::round(extent / side)), glm::uvec3(1));
        if (uint64_t(n.x) * n.y * n.z <= count)
            return n;
    }
}

OpenPoints open_points(const LitLevel& level, size_t count, int rays, uint64_t seed)
{
    OpenPoints out;
    bake::LightmapBakeOptions o;
    o.rays = rays;
    o.seed = seed;
    uint64_t item = 0;
    while (out.points.size() < count)
    {
        if (out.drawn > 10000 * count)
            throw std::runtime_error("the level has too little open space to draw " + std::to_string(count) +
                                     " points from");
        std::vector<glm::vec3> drawn(count);
        for (glm::vec3& p : drawn)
        {
            const uint64_t h = bake::mix64(seed ^ (0x9E3779B97F4A7C15ull * ++item));
            const glm::vec3 t(float(h & 0x1FFFFF) / float(0x200000),
                              float((h >> 21) & 0x1FFFFF) / float(0x200000),
                              float((h >> 42) & 0x1FFFFF) / float(0x200000));
            p = level.lo + t * (level.hi - level.lo);
        }
        const io::LightProbes baked = bake::bake_probes_at(drawn, 0, level.scene.mesh, level.atlas, level.sh,
                                                           level.lights, o, level.surfaces.get());
        for (size_t i = 0; i < drawn.size() && out.points.size() < count; ++i)
        {
            ++out.drawn;
            if (baked.valid[i])
            {
                out.points.push_back(drawn[i]);
                out.irradiance.push_back(baked.irradiance[i]);
            }
        }
    }
    return out;
}

double lookup_error(const io::LightProbes& probes, const OpenPoints& reference)
{
    const io::ProbeIndex index = io::index_probes(probes);
    double error = 0.0, norm = 0.0;
    for (size_t i = 0; i < reference.points.size(); ++i)
    {
        error += sh_distance(probes.at(reference.points[i], &index), reference.irradiance[i]);
        norm += sh_distance(reference.irradiance[i], {});
    }
    return norm > 0.0 ? error / norm : 0.0;
}

PlacementRow compare_placement(const LitLevel& level, uint32_t budget, int rays, const OpenPoints& reference)
{
    PlacementRow row;
    row.budget = budget;
    bake::LightmapBakeOptions o;
    o.rays = rays;
    auto t0 = std::chrono::steady_clock::now();
    row.grid = grid_of(level, budget);
    io::LightProbes grid = bake::probe_grid(level.scene.mesh, row.grid);
    bake::bake_light_probes(grid, level.scene.mesh, level.atlas, level.sh, level.lights, o,
                            level.surfaces.get());
    row.grid_seconds = seconds_since(t0);
    row.grid_probes = grid.size();
    for (uint8_t v : grid.valid)
        row.grid_inside += !v;
    row.grid_error = lookup_error(grid, reference);
    t0 = std::chrono::steady_clock::now();
    bake::ProbePlacementOptions p;
    p.budget = uint32_t(row.grid_probes); // the same count
    row.placed_probes = bake::place_light_probes(level.scene.mesh, level.atlas, level.sh, level.lights, o,
                                                 level.surfaces.get(), p, &row.placed);
    row.placed_seconds = seconds_since(t0);
    row.placed_error = lookup_error(row.placed_probes, reference);
    return row;
}

} // namespace hemi::samples
