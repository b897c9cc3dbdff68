#pragma once
// Light probes for what moves through a lightmapped level (hemi-bake lightmap --probes): SH9 irradiance on a
// regular grid, and what each probe sees of the level, so that a lookup blends only the probes a point can
// see (Majercik et al. 2019, "Dynamic Diffuse Global Illumination with Ray-Traced Irradiance Fields": depth
// moments and Chebyshev's inequality). The lightmap asset stores them (io/lightmap_asset.h,
// lightmap.probes and lightmap.probe_depth); docs/probes.md explains the lookup and its limits.

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hemi::io
{

// The octahedral map of the unit sphere onto [0, 1]^2 (Engelhardt & Dachsbacher 2008; Cigolle et al. 2014):
// d / (|x| + |y| + |z|) projected onto z = 0, the lower half folded out over the square's corners. u along
// x, v along y, (0.5, 0.5) is +z and the four corners -z. A probe's depth map has R x R texels over it,
// texel (x, y) centred at ((x + 0.5) / R, (y + 0.5) / R).
glm::vec2 octahedral_encode(const glm::vec3& direction); // any non-zero direction
glm::vec3 octahedral_decode(const glm::vec2& uv);        // unit length

struct ProbeIndex;

struct LightProbes
{
    // A regular grid (hemi-bake lightmap --probes NX,NY,NZ): count probes along x, y and z (all 0 when the
    // asset has none) from corner probe lo to corner probe hi (lo == hi along an axis with one probe).
    // Scattered probes (points not empty): count is (N, 1, 1) and lo, hi the bounds of the points.
    glm::uvec3 count{0};
    glm::vec3 lo{0.0f}, hi{0.0f};
    // Scattered probes, placed by hemi-bake's automatic placement, a file or a glTF file's nodes
    // (docs/probes.md) instead of a grid: probe i at points[i].xyz, and the reach of its weight, points[i].w
    // > 0: the lookup weights it by (1 - d^2 / w^2)^8 at distance d < w (a smooth bump that falls to 0 at the
    // reach) times its visibility. Empty for a grid.
    std::vector<glm::vec4> points;
    // SH9 irradiance (hemi's SH order and sign, convolved with the clamped cosine: E(n) = sum_j c_j y_j(n)
    // for any unit n), in the scene's own frame (the mesh's space), from the same lights and surfaces as the
    // lightmap: grid probe (i, j, k) at i + NX (j + NY k); scattered probe i at i.
    std::vector<std::array<glm::vec3, 9>> irradiance;
    std::vector<uint8_t> valid; // 0: inside geometry (most of its rays saw the backs of surfaces); never used
    // With mixed lights: per probe, the share of each shadowmask channel's light that reaches it (the sun's
    // rays over its disc not blocked, a punctual light's one ray; 1 where none of the channel's lights
    // reaches), what a dynamic object's mixed lights are times (their static shadows). Empty otherwise.
    std::vector<std::array<float, 4>> occlusion;
    // What each probe sees: over an R x R octahedral map of directions (R = depth_resolution), the mean of
    // the distance from the probe to the first surface (any side; a ray that escapes counts as
    // max_distance) and its standard deviation, each texel a cos^50 lobe of the probe's rays around its
    // centre direction.
    // Probe p's texel (x, y) at (p R + y) R + x. Empty (R = 0): the lookup weighs by distance alone, as
    // assets baked before visibility do.
    uint32_t depth_resolution = 0;
    float max_distance = 0.0f;
    std::vector<glm::vec2> depth;

    bool empty() const { return irradiance.empty(); }
    size_t size() const { return irradiance.size(); }
    bool scattered() const { return !points.empty(); }
    glm::vec3 position(uint32_t i, uint32_t j, uint32_t k) const; // a grid's probe (i, j, k)
    glm::vec3 position(size_t probe) const;
    // The irradiance at `p` (scene space), blended over the probes around p: a grid's 8 probes of p's cell
    // (p clamped to the grid) by their trilinear weights, scattered probes by their bumps (those whose reach
    // holds p), each valid probe's weight times its visibility(probe, p), the weights renormalised.
    // Continuous in p. Without any such valid probe, the nearest valid probe; zero without any. `index`
    // (index_probes of these probes) finds scattered probes faster, with the same result.
    std::array<glm::vec3, 9> at(const glm::vec3& p, const ProbeIndex* index = nullptr) const;
    // The mixed lights' occlusion at `p`, blended as at() blends the irradiance; all 1 without.
    std::array<float, 4> occlusion_at(const glm::vec3& p, const ProbeIndex* index = nullptr) const;
    // The mean distance and its deviation probe `probe` sees towards `direction` (bilinear over its depth
    // map, the octahedral map's edges wrapped onto their mirror images, so that it is continuous over the
    // sphere).
    glm::vec2 depth_at(size_t probe, const glm::vec3& direction) const;
    // How much of point p probe `probe` sees, in (0, 1]: 1 where p is no farther than the probe's mean
    // distance towards it, else Chebyshev's bound var / (var + (r - mean)^2) (var the deviation squared) on
    // the chance that nothing lies between, squared (sharpened, as DDGI cubes it: docs/probes.md says why a
    // square), and never below kMinVisibility so that
    // weights stay positive. 1 without depth maps.
    float visibility(size_t probe, const glm::vec3& p) const;
    static constexpr float kMinVisibility = 1e-4f;

    // The probes at() blends at `p` and their weights (summing to 1), in probe order.
    struct Blend
    {
        std::vector<uint32_t> probe;
        std::vector<float> weight;
        size_t count() const { return probe.size(); }
    };
    Blend blend(const glm::vec3& p, const ProbeIndex* index = nullptr) const;
};

// Where scattered probes reach (what a lookup needs to find the few probes whose bump holds a point): a
// grid of cells over the valid probes' reach, each listing the valid probes whose reach (a ball) meets it,
// in probe order. Empty for a grid of probes.
struct ProbeIndex
{
    glm::uvec3 cells{0};
    glm::vec3 lo{0.0f};   // the first cell's corner
    glm::vec3 cell{1.0f}; // a cell's size
    std::vector<uint32_t>
        first; // cell c's probes are probes[first[c] .. first[c + 1]), cells x + X (y + Y z)
    std::vector<uint32_t> probes;
    // The probes of the cell holding p; none outside the cells.
    std::span<const uint32_t> near(const glm::vec3& p) const;
};
// Throws std::invalid_argument for probes light_probes_problem refuses.
ProbeIndex index_probes(const LightProbes& probes);

// The probes of an NX x NY x NZ grid, or 0 when the grid is empty or holds more than 2^24 (the product is
// taken so that it cannot wrap: three counts of up to 2^32 each).
inline uint64_t probe_grid_count(uint64_t nx, uint64_t ny, uint64_t nz)
{
    constexpr uint64_t limit = uint64_t(1) << 24;
    if (nx == 0 || ny == 0 || nz == 0 || nx > limit || ny > limit || nx * ny > limit || nx * ny * nz > limit)
        return 0;
    return nx * ny * nz;
}

// What is wrong with `probes` (sizes that disagree, values that are not finite or out of range), or empty.
std::string light_probes_problem(const LightProbes& probes);

// The largest depth map side an asset may hold.
constexpr uint32_t kMaxProbeDepthResolution = 64;

// The probes for a shader's lookup (hemi_probe_irradiance, hemi/lib/probes.glsl): one RGBA32F texel
// buffer that describes itself, so that a shader needs nothing else (throws std::invalid_argument for probes
// light_probes_problem refuses, or scattered probes whose index would hold 2^24 entries or more). Integers
// are stored as floats (exact below 2^24).
//   texel 0: kind (0 grid, 1 scattered), R (depth_resolution), N (probes), S (texels a probe,
//            probe_texel_stride(R) = 9 + ceil(R^2 / 2))
//   texel 1: a grid's count xyz; scattered: the index's cells xyz and in .w the texel of its first[] table
//   texel 2: a grid's lo; scattered: the index's lo, and in .w the texel of its probes[] list
//   texel 3: a grid's hi; scattered: the index's cell size
//   from texel 4 (kProbeTexelHeader), probe p's S texels from 4 + p S: texels 0-6 its 27 SH9 floats in
//            hemi_pack_coefficients' order with float 28 its valid flag (1 or 0), texel 7 its occlusion of
//            the four shadowmask channels (all 1 without mixed lights), texel 8 its position and reach (0 in
//            a grid), then its depth map, two texels (mean, deviation) to a vec4, texel t = y R + x in .xy
//            of vec4 t / 2 when t is even, .zw when odd
//   scattered: the index's first[] (cells + 1 values) four to a texel, then its probes[] four to a texel.
std::vector<glm::vec4> probe_texels(const LightProbes& probes);
size_t probe_texel_stride(uint32_t depth_resolution);
constexpr size_t kProbeTexelHeader = 4;

} // namespace hemi::io
