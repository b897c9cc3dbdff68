// hemi-probe-placement: automatic light probe placement against a grid of the same probe count (issue 44;
// docs/probes.md#placing-probes quotes its table). For each level and budget N it bakes a grid of at most N
// probes over the level's bounding box (hemi-bake lightmap --probes NX,NY,NZ) and places N probes
// automatically (--probes auto:N with N the grid's count), 1024 rays a probe, and prints the mean error of
// each one's lookup (io::LightProbes::at, with visibility) at 200 random points of the level's open space
// against probes baked exactly at those points (samples/light_probes/placement.h). The levels:
//   - the sample level (samples::make_level), lit by a sky of (0.35, 0.45, 0.65) and a sun of (8, 7.5, 7)
//     through its opening, its 512^2 lightmap (64 rays, 1 bounce);
//   - OpenArena's oa_dm3 (Debian's openarena-081-maps, the Quake III level the tests convert), unwrapped
//     into 512^2, lit by a sky of 0.5 and a sun of 3 (the light issue 41 baked it with), 32 rays, 1 bounce.
//
//   hemi-probe-placement [BUDGETS [LEVEL]]   BUDGETS: comma-separated (default 64,256,1024); LEVEL: only
//                                             the levels whose name contains it ("sample", "oa_dm3")
//
// The measure is the first 200 points; the table also gives the ratio over ten sets of 200 (its
// range: how much a mean over 200 points varies) and over all 2,000.
//
// About 10 minutes on 2 cores with the default budgets. Not a benchmark of speed: the times it prints are
// for orientation.
#include "../samples/irradiance_normalmap/level.h"
#include "../samples/light_probes/placement.h"
#include "../tests/tools/q3_level.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

int main(int argc, char** argv)
{
    using namespace hemi;
    try
    {
        std::vector<uint32_t> budgets = {64, 256, 1024};
        if (argc > 1)
        {
            budgets.clear();
            std::stringstream list(argv[1]);
            for (std::string item; std::getline(list, item, ',');)
                budgets.push_back(uint32_t(std::stoul(item)));
        }
        const std::string only = argc > 2 ? argv[2] : "";
        std::printf(
            "| level | probes (the grid's) | grid: inside geometry | grid: error | placed: error | placed / "
            "grid | placed / grid, 10 sets of 200 | placed / grid, all 2,000 |\n"
            "|---|---|---|---|---|---|---|---|\n");
        for (const std::string name : {"sample level", "oa_dm3"})
        {
            if (name.find(only) == std::string::npos)
                continue;
            bake::LightmapLights lights;
            io::GltfScene scene;
            int rays = 64;
            if (name == "sample level")
            {
                scene = samples::make_level(512);
                lights.uniform = glm::vec3(0.35f, 0.45f, 0.65f);
                lights.sun_direction = glm::normalize(glm::vec3(0.3f, 0.4f, 0.5f)); // glTF's frame, y up
                lights.sun_irradiance = glm::vec3(8.0f, 7.5f, 7.0f);
            }
            else
            {
                // Through a glTF file, as a user's pipeline gives it to hemi-bake (read_gltf makes its
                // tangents).
                const std::filesystem::path gltf =
                    std::filesystem::temp_directory_path() /
                    ("hemi_probe_placement_" + std::to_string(getpid()) + ".glb");
                io::write_gltf(gltf, test::read_q3_level(test::kOpenArenaMaps, "maps/oa_dm3.bsp").scene);
                scene = io::read_gltf(gltf);
                std::filesystem::remove(gltf);
                lights.uniform = glm::vec3(0.5f);
                lights.sun_direction = glm::normalize(glm::vec3(0.5f, 0.79f, 0.35f));
                lights.sun_irradiance = glm::vec3(3.0f);
                rays = 32;
            }
            lights.sun = true;
            const samples::LitLevel level(std::move(scene), lights, 512, name != "sample level", rays, 1);
            // 2,000 random open points: the first 200 are the issue's; ten sets of 200 show how much the mean
            // over 200 points varies.
            const samples::OpenPoints all = samples::open_points(level, 2000, 1024, 7);
            std::vector<samples::OpenPoints> sets(10);
            for (size_t i = 0; i < all.points.size(); ++i)
            {
                sets[i / 200].points.push_back(all.points[i]);
                sets[i / 200].irradiance.push_back(all.irradiance[i]);
            }
            std::fprintf(stderr, "%s: %zu triangles, 2000 open points of %zu drawn\n", name.c_str(),
                         level.scene.mesh.indices.size() / 3, all.drawn);
            for (uint32_t budget : budgets)
            {
                const samples::PlacementRow r = samples::compare_placement(level, budget, 1024, sets[0]);
                io::LightProbes grid = bake::probe_grid(level.scene.mesh, r.grid);
                bake::LightmapBakeOptions o;
                o.rays = 1024;
                bake::bake_light_probes(grid, level.scene.mesh, level.atlas, level.sh, level.lights, o,
                                        level.surfaces.get());
                double lo = INFINITY, hi = 0.0;
                for (const samples::OpenPoints& set : sets)
                {
                    const double ratio =
                        samples::lookup_error(r.placed_probes, set) / samples::lookup_error(grid, set);
                    lo = std::min(lo, ratio);
                    hi = std::max(hi, ratio);
                }
                std::printf("| %s | %zu (%ux%ux%u) | %zu | %.2f%% | %.2f%% | %.3f | %.2f-%.2f | %.2f |\n",
                            name.c_str(), r.grid_probes, r.grid.x, r.grid.y, r.grid.z, r.grid_inside,
                            100.0 * r.grid_error, 100.0 * r.placed_error, r.placed_error / r.grid_error, lo,
                            hi,
                            samples::lookup_error(r.placed_probes, all) / samples::lookup_error(grid, all));
                std::fflush(stdout);
                std::fprintf(stderr,
                             "  budget %u: grid %.1f s; placed %.1f s (%zu candidates, %zu open, %d rounds, "
                             "reach scale %.2f, error at the candidates %.1f%%)\n",
                             budget, r.grid_seconds, r.placed_seconds, r.placed.candidates, r.placed.open,
                             r.placed.rounds, r.placed.reach_scale, 100.0 * r.placed.error);
            }
        }
        return 0;
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "hemi-probe-placement: %s\n", e.what());
        return 1;
    }
}
