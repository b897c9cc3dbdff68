#pragma once
// Light probes where they matter (issue 44; docs/probes.md): scattered probes (io::LightProbes::points) at
// points a user gives (a file, a glTF file's nodes) or placed automatically in the level's open space, more
// of them where the light changes, within a budget. Each scattered probe's weight reaches as far as its
// neighbours are (probe_reach), so that the blend stays continuous and local however dense the probes are.

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/light_probes.h>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <vector>

namespace hemi::bake
{

// Each probe's reach (points[i].w) from where the others are: kReachScale times the distance to its
// kReachNeighbour-th nearest other probe (the distance to the farthest other when there are fewer; 1 when
// there is no other), at most `most` (> 0; INFINITY for no limit). Only points[i].xyz are read.
constexpr int kReachNeighbour = 4;
constexpr float kReachScale = 1.75f;
void probe_reach(std::span<glm::vec4> points, float most = INFINITY, float scale = kReachScale);

// Light probes baked at `points` (the mesh's space), each reaching as probe_reach says over the points that
// turn out to be in open space (a probe inside geometry is kept, flagged invalid, and never used), with depth
// maps of `depth_resolution` texels a side. What bake_light_probes throws, and std::invalid_argument for no
// points, more than 2^24 or a point that is not finite.
io::LightProbes bake_probes_at(std::span<const glm::vec3> points, uint32_t depth_resolution,
                               const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                               const LightmapLights& lights, const LightmapBakeOptions& options,
                               const LightmapSurfaces* surfaces = nullptr);

// How place_light_probes works.
struct ProbePlacementOptions
{
    uint32_t budget = 256; // at most this many probes (1 to 2^20)
    // Candidates: a fine grid over the scene's bounding box dense enough that about this many of its points
    // per probe of the budget lie in open space (at most 2^22 points in all).
    uint32_t candidates_per_probe = 8;
    uint32_t depth_resolution = kProbeDepthResolution;
    // Called with a fraction in [0, 1] as the placement goes on. Empty: none.
    std::function<void(double)> progress;
};

struct ProbePlacementReport
{
    size_t candidates = 0; // points of the fine grid
    size_t open = 0;       // of them in open space: the ones baked and chosen from
    size_t placed = 0;
    int rounds = 0;
    float reach_scale = kReachScale; // the scale of the reaches chosen (probe_reach)
    // The mean error of the placed probes' lookup at the open candidates not chosen (the SH9 coefficients'
    // distance, sqrt(sum_j |c_j - c'_j|^2) over RGB), over the mean of those candidates' own SH9 norm.
    double error = 0.0;
};

// Probes placed automatically in the open space of the lit level (`sh`, as bake_light_probes takes it): the
// open points of a fine grid of candidates (in open space by bake_light_probes' test: at most half of a
// probe's rays see the backs of surfaces) are baked; a first quarter of the budget spread over them as
// evenly as can be (each the candidate farthest from those already chosen), then, in rounds, the
// candidates where the chosen probes' lookup (io::LightProbes::at, with visibility, as a shader sees it: no
// light where no probe reaches) differs most from the candidate's own probe are added, until the budget is
// spent. So probes gather where the light changes (shadow edges, doors, the two sides of walls) and thin
// out where it does not; none is inside geometry. Finally the reaches' scale that fits the candidates best
// is kept (from 0.8 to 2.5 times the 4th neighbour's distance). Deterministic for a seed, on any thread
// count. Throws std::invalid_argument for bad options, a level without open space, or what bake_light_probes
// throws.
io::LightProbes place_light_probes(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                                   const LightmapLights& lights, const LightmapBakeOptions& options,
                                   const LightmapSurfaces* surfaces, const ProbePlacementOptions& placement,
                                   ProbePlacementReport* report = nullptr);

// Probe positions from a text file (hemi-bake lightmap --probes file:PATH): one probe per line, "x y z" in
// the scene's glTF frame (the mesh's space), separated by spaces, tabs or commas; empty lines and lines
// starting with '#' are skipped. Throws io::FormatError naming the file (and the line) when it is missing or
// unreadable, a line does not hold three finite numbers, or it holds no probe, or more than 2^24.
std::vector<glm::vec3> read_probe_points(const std::filesystem::path& path);

} // namespace hemi::bake
