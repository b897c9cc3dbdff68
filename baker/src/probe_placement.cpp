// Scattered light probes: their reach, probes at given points, automatic placement and the points file
// (probe_placement.h).
#include <hemi/bake/probe_placement.h>

#include <hemi/io/image.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>

namespace hemi::bake
{
namespace
{

float distance2(const glm::vec3& a, const glm::vec3& b)
{
    const glm::vec3 d = a - b;
    return d.x * d.x + d.y * d.y + d.z * d.z;
}

// The squared distances from each point to its k nearest others (fewer when there are fewer), through a
// uniform grid of about one point a cell, searched in growing shells until the shell is farther than the
// k-th distance found.
std::vector<std::vector<float>> nearest_distances(std::span<const glm::vec4> points, int k)
{
    const size_t n = points.size();
    std::vector<std::vector<float>> out(n);
    if (n < 2)
        return out;
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec4& p : points)
    {
        lo = glm::min(lo, glm::vec3(p));
        hi = glm::max(hi, glm::vec3(p));
    }
    const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-6f * std::max(glm::length(hi - lo), 1e-6f)));
    // About one point a cell, coarser where the points lie in a plane or along a line.
    float side = std::cbrt(extent.x * extent.y * extent.z / float(n));
    glm::ivec3 cells;
    for (;; side *= 1.25f)
    {
        const glm::dvec3 c = glm::max(glm::ceil(glm::dvec3(extent) / double(side)), glm::dvec3(1.0));
        if (c.x * c.y * c.z <= 2.0 * double(n) + 8.0)
        {
            cells = glm::ivec3(c);
            break;
        }
    }
    const glm::vec3 cell = extent / glm::vec3(cells);
    auto cell_of = [&](const glm::vec3& p)
    { return glm::clamp(glm::ivec3(glm::floor((p - lo) / cell)), glm::ivec3(0), cells - 1); };
    auto flat = [&](const glm::ivec3& c)
    { return size_t(c.x) + size_t(cells.x) * (c.y + size_t(cells.y) * c.z); };
    std::vector<uint32_t> first(size_t(cells.x) * cells.y * cells.z + 1, 0), members(n);
    for (const glm::vec4& p : points)
        ++first[flat(cell_of(glm::vec3(p))) + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    std::vector<uint32_t> fill(first.begin(), first.end() - 1);
    for (size_t i = 0; i < n; ++i)
        members[fill[flat(cell_of(glm::vec3(points[i])))]++] = uint32_t(i);
    const int wanted = int(std::min<size_t>(size_t(k), n - 1));
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 256),
        [&](const tbb::blocked_range<size_t>& range)
        {
            for (size_t i = range.begin(); i != range.end(); ++i)
            {
                const glm::vec3 p(points[i]);
                const glm::ivec3 c = cell_of(p);
                std::vector<float>& best = out[i]; // sorted, at most `wanted`
                for (int shell = 0;; ++shell)
                {
                    // A cell of this shell is `shell` cells off along some axis that has
                    // cells that far: its points at least (shell - 1) such cells away. No such
                    // axis: this shell and all beyond it are empty.
                    float reach = INFINITY;
                    for (int a = 0; a < 3; ++a)
                        if (c[a] - shell >= 0 || c[a] + shell < cells[a])
                            reach = std::min(reach, float(std::max(shell - 1, 0)) * cell[a]);
                    if (reach == INFINITY)
                        break;
                    if (int(best.size()) == wanted && reach * reach > best.back())
                        break;
                    for (int z = c.z - shell; z <= c.z + shell; ++z)
                        for (int y = c.y - shell; y <= c.y + shell; ++y)
                            for (int x = c.x - shell; x <= c.x + shell; ++x)
                            {
                                if (std::max(std::abs(x - c.x),
                                             std::max(std::abs(y - c.y), std::abs(z - c.z))) != shell)
                                    continue;
                                if (x < 0 || y < 0 || z < 0 || x >= cells.x || y >= cells.y || z >= cells.z)
                                    continue;
                                const size_t at = flat(glm::ivec3(x, y, z));
                                for (uint32_t m = first[at]; m < first[at + 1]; ++m)
                                {
                                    const uint32_t j = members[m];
                                    if (j == i)
                                        continue;
                                    const float d = distance2(p, glm::vec3(points[j]));
                                    if (int(best.size()) == wanted && d >= best.back())
                                        continue;
                                    best.insert(std::upper_bound(best.begin(), best.end(), d), d);
                                    if (int(best.size()) > wanted)
                                        best.pop_back();
                                }
                            }
                }
            }
        });
    return out;
}

// The SH9 coefficients' distance (over RGB).
double sh_distance(const std::array<glm::vec3, 9>& a, const std::array<glm::vec3, 9>& b)
{
    double s = 0.0;
    for (size_t j = 0; j < 9; ++j)
    {
        const glm::dvec3 d = glm::dvec3(a[j]) - glm::dvec3(b[j]);
        s += glm::dot(d, d);
    }
    return std::sqrt(s);
}

double sh_norm(const std::array<glm::vec3, 9>& a)
{
    return sh_distance(a, {});
}

// What a shader's lookup (hemi_probe_irradiance) gives at p: no light where no valid probe reaches.
std::array<glm::vec3, 9> shader_lookup(const io::LightProbes& probes, const io::ProbeIndex& index,
                                       const glm::vec3& p)
{
    for (uint32_t q : index.near(p))
        if (distance2(glm::vec3(probes.points[q]), p) < probes.points[q].w * probes.points[q].w)
            return probes.at(p, &index);
    return {};
}

// The probes `chosen` of `candidates` (all valid), their reaches made anew.
io::LightProbes subset(const io::LightProbes& candidates, std::span<const uint32_t> chosen, float most,
                       float scale)
{
    io::LightProbes p;
    p.depth_resolution = candidates.depth_resolution;
    p.max_distance = candidates.max_distance;
    const size_t rr = size_t(p.depth_resolution) * p.depth_resolution;
    p.lo = glm::vec3(INFINITY);
    p.hi = glm::vec3(-INFINITY);
    for (uint32_t c : chosen)
    {
        p.points.push_back(glm::vec4(glm::vec3(candidates.points[c]), 0.0f));
        p.lo = glm::min(p.lo, glm::vec3(candidates.points[c]));
        p.hi = glm::max(p.hi, glm::vec3(candidates.points[c]));
        p.irradiance.push_back(candidates.irradiance[c]);
        p.valid.push_back(1);
        if (!candidates.occlusion.empty())
            p.occlusion.push_back(candidates.occlusion[c]);
        p.depth.insert(p.depth.end(), candidates.depth.begin() + ptrdiff_t(c * rr),
                       candidates.depth.begin() + ptrdiff_t((c + 1) * rr));
    }
    p.count = glm::uvec3(uint32_t(chosen.size()), 1, 1);
    probe_reach(p.points, most, scale);
    return p;
}

} // namespace

void probe_reach(std::span<glm::vec4> points, float most, float scale)
{
    if (points.size() == 1)
        points[0].w = std::min(1.0f, most);
    const std::vector<std::vector<float>> nearest = nearest_distances(points, kReachNeighbour);
    for (size_t i = 0; i < points.size() && points.size() > 1; ++i)
    {
        const float d = std::sqrt(nearest[i].back());
        points[i].w = std::min(std::max(scale * d, 1e-6f), most);
    }
}

io::LightProbes bake_probes_at(std::span<const glm::vec3> points, uint32_t depth_resolution,
                               const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                               const LightmapLights& lights, const LightmapBakeOptions& options,
                               const LightmapSurfaces* surfaces)
{
    if (points.empty() || points.size() > size_t(1) << 24)
        throw std::invalid_argument("probes at points need 1 to 2^24 points, not " +
                                    std::to_string(points.size()));
    io::LightProbes p;
    p.depth_resolution = depth_resolution;
    for (const glm::vec3& q : points)
    {
        if (!std::isfinite(q.x + q.y + q.z))
            throw std::invalid_argument("a probe's position is not finite");
        p.points.emplace_back(q, 0.0f);
    }
    // Reaches over all the points first (the depth maps' clamp follows the largest), then over the open ones
    // alone, no farther than that: a probe inside geometry leaves a gap its neighbours cover.
    probe_reach(p.points);
    float most = 0.0f;
    for (const glm::vec4& q : p.points)
        most = std::max(most, q.w);
    bake_light_probes(p, mesh, atlas, sh, lights, options, surfaces);
    std::vector<glm::vec4> open;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.valid[i])
            open.push_back(p.points[i]);
    probe_reach(open, most);
    for (size_t i = 0, o = 0; i < p.size(); ++i)
        if (p.valid[i])
            p.points[i].w = open[o++].w;
    return p;
}

io::LightProbes place_light_probes(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                                   const LightmapLights& lights, const LightmapBakeOptions& options,
                                   const LightmapSurfaces* surfaces, const ProbePlacementOptions& placement,
                                   ProbePlacementReport* report)
{
    constexpr uint64_t kMostCandidates = uint64_t(1) << 22;
    if (placement.budget == 0 || placement.budget > (1u << 20))
        throw std::invalid_argument("a probe budget of " + std::to_string(placement.budget) +
                                    " is not in [1, 2^20]");
    if (placement.candidates_per_probe == 0 ||
        uint64_t(placement.candidates_per_probe) * placement.budget > kMostCandidates)
        throw std::invalid_argument("a probe budget of " + std::to_string(placement.budget) + " with " +
                                    std::to_string(placement.candidates_per_probe) +
                                    " candidates a probe asks for more than 2^22 candidates");
    if (mesh.positions.empty())
        throw std::invalid_argument("probes need a level to place them in");
    auto progress = [&](double f)
    {
        if (placement.progress)
            placement.progress(f);
    };
    ProbePlacementReport r;
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& v : mesh.positions)
    {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-4f * std::max(glm::length(hi - lo), 1e-6f)));
    // The fine grid: first as if all of the box were open, then finer by the open share it found (twice at
    // most), so that about candidates_per_probe x budget of its points are open.
    const double wanted = double(placement.candidates_per_probe) * placement.budget;
    double points = wanted;
    io::LightProbes grid;
    float spacing = 0.0f;
    for (int attempt = 0; attempt < 3; ++attempt)
    {
        spacing = float(std::cbrt(double(extent.x) * extent.y * extent.z / points));
        glm::uvec3 count = glm::max(glm::uvec3(glm::round(extent / spacing)), glm::uvec3(1));
        while (uint64_t(count.x) * count.y * count.z > kMostCandidates)
            count = glm::max(count * 4u / 5u, glm::uvec3(1));
        const glm::vec3 cell = extent / glm::vec3(count);
        grid = io::LightProbes{};
        grid.count = count;
        grid.lo = lo + 0.5f * cell;
        grid.hi = hi - 0.5f * cell;
        grid.depth_resolution = 0;
        LightmapBakeOptions test = options;
        test.rays = 64; // enough to tell open space from the inside of geometry
        bake_light_probes(grid, mesh, atlas, sh, lights, test, surfaces);
        const size_t open = size_t(std::count(grid.valid.begin(), grid.valid.end(), uint8_t(1)));
        if (open == 0)
            throw std::invalid_argument("no point of the level is in open space: every probe would be inside "
                                        "geometry (are the surfaces' normals facing inwards?)");
        if (double(open) >= 0.5 * wanted ||
            uint64_t(count.x) * count.y * count.z * 4 / 5 > kMostCandidates / 2)
            break;
        points = std::min(points * wanted / double(open), double(kMostCandidates));
    }
    progress(0.1);
    std::vector<glm::vec3> open_points;
    for (size_t i = 0; i < grid.size(); ++i)
        if (grid.valid[i])
            open_points.push_back(grid.position(i));
    r.candidates = grid.size();
    // The candidates baked as probes: the reach they are baked with bounds every reach chosen below (the
    // depth maps' clamp follows it): 6 times the spacing the budget would have spread evenly.
    const double open_volume = double(open_points.size()) * spacing * spacing * spacing;
    const float even = float(std::cbrt(open_volume / placement.budget));
    const float most = 6.0f * even;
    io::LightProbes candidates;
    candidates.depth_resolution = placement.depth_resolution;
    for (const glm::vec3& p : open_points)
        candidates.points.emplace_back(p, most);
    bake_light_probes(candidates, mesh, atlas, sh, lights, options, surfaces);
    std::vector<uint32_t> open; // the candidates the full bake finds open too
    for (size_t i = 0; i < candidates.size(); ++i)
        if (candidates.valid[i])
            open.push_back(uint32_t(i));
    r.open = open.size();
    if (open.empty())
        throw std::invalid_argument("no point of the level is in open space");
    progress(0.5);
    std::vector<double> norm(candidates.size());
    for (uint32_t c : open)
        norm[c] = sh_norm(candidates.irradiance[c]);

    // The first quarter: farthest-point sampling from the candidate nearest the open space's centre.
    const uint32_t budget = uint32_t(std::min<size_t>(placement.budget, open.size()));
    std::vector<uint32_t> chosen;
    std::vector<uint8_t> taken(candidates.size(), 0);
    {
        glm::dvec3 centre(0.0);
        for (uint32_t c : open)
            centre += glm::dvec3(candidates.points[c]);
        centre /= double(open.size());
        uint32_t start = open[0];
        for (uint32_t c : open)
            if (distance2(glm::vec3(candidates.points[c]), glm::vec3(centre)) <
                distance2(glm::vec3(candidates.points[start]), glm::vec3(centre)))
                start = c;
        std::vector<float> away(candidates.size(), INFINITY);
        const uint32_t first = std::max(1u, budget / 4);
        for (uint32_t next = start; chosen.size() < first;)
        {
            chosen.push_back(next);
            taken[next] = 1;
            uint32_t farthest = next;
            float far = -1.0f;
            for (uint32_t c : open)
            {
                away[c] = std::min(
                    away[c], distance2(glm::vec3(candidates.points[c]), glm::vec3(candidates.points[next])));
                if (away[c] > far)
                {
                    far = away[c];
                    farthest = c;
                }
            }
            if (far <= 0.0f)
                break;
            next = farthest;
        }
    }
    // Each open candidate's error under the chosen probes (0 for the chosen).
    std::vector<double> error(candidates.size(), 0.0);
    auto measure = [&](float scale)
    {
        const io::LightProbes p = subset(candidates, chosen, most, scale);
        const io::ProbeIndex index = io::index_probes(p);
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, open.size(), 64),
            [&](const tbb::blocked_range<size_t>& range)
            {
                for (size_t i = range.begin(); i != range.end(); ++i)
                {
                    const uint32_t c = open[i];
                    error[c] = taken[c]
                                   ? 0.0
                                   : sh_distance(shader_lookup(p, index, glm::vec3(candidates.points[c])),
                                                 candidates.irradiance[c]);
                }
            });
        double sum = 0.0, scale_sum = 0.0;
        for (uint32_t c : open)
            if (!taken[c])
            {
                sum += error[c];
                scale_sum += norm[c];
            }
        return scale_sum > 0.0 ? sum / scale_sum : 0.0;
    };
    // Rounds: the worst candidates, a fourteenth more probes a round, no two of a round within two grid
    // spacings.
    const float gap2 = 4.0f * spacing * spacing;
    while (chosen.size() < budget)
    {
        measure(kReachScale);
        ++r.rounds;
        std::vector<uint32_t> order;
        for (uint32_t c : open)
            if (!taken[c])
                order.push_back(c);
        std::stable_sort(order.begin(), order.end(),
                         [&](uint32_t a, uint32_t b) { return error[a] > error[b]; });
        const size_t batch =
            std::min<size_t>(budget - chosen.size(), std::max<size_t>(1, chosen.size() / 14));
        std::vector<uint32_t> picked;
        for (uint32_t c : order)
        {
            if (picked.size() == batch)
                break;
            bool near = false;
            for (uint32_t q : picked)
                near |= distance2(glm::vec3(candidates.points[c]), glm::vec3(candidates.points[q])) < gap2;
            if (!near)
                picked.push_back(c);
        }
        if (picked.empty())
            break;
        for (uint32_t c : picked)
        {
            chosen.push_back(c);
            taken[c] = 1;
        }
        progress(0.5 + 0.45 * double(chosen.size()) / double(budget));
    }
    // The reaches' scale that fits the candidates best.
    double best = INFINITY;
    for (float scale : {0.8f, 0.9f, 1.0f, 1.1f, 1.3f, 1.5f, 1.75f, 2.0f, 2.5f})
    {
        const double e = measure(scale);
        if (e < best)
        {
            best = e;
            r.reach_scale = scale;
        }
    }
    r.error = best;
    std::sort(chosen.begin(), chosen.end()); // the probes in the candidates' order, whatever the rounds
    io::LightProbes out = subset(candidates, chosen, most, r.reach_scale);
    out.max_distance = candidates.max_distance;
    r.placed = out.size();
    progress(1.0);
    if (report)
        *report = r;
    return out;
}

std::vector<glm::vec3> read_probe_points(const std::filesystem::path& path)
{
    std::ifstream in(path);
    if (!in)
        throw io::FormatError(path.string() + ": cannot open the probe points file");
    std::vector<glm::vec3> points;
    std::string line;
    for (size_t number = 1; std::getline(in, line); ++number)
    {
        const size_t start = line.find_first_not_of(" \t\r");
        if (start == std::string::npos || line[start] == '#')
            continue;
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream fields(line);
        glm::vec3 p;
        std::string rest;
        if (!(fields >> p.x >> p.y >> p.z) || (fields >> rest) || !std::isfinite(p.x + p.y + p.z))
            throw io::FormatError(path.string() + ":" + std::to_string(number) +
                                  ": expected three finite numbers \"x y z\", found \"" + line + "\"");
        points.push_back(p);
        if (points.size() > size_t(1) << 24)
            throw io::FormatError(path.string() + ": more than 2^24 probe points");
    }
    if (in.bad())
        throw io::FormatError(path.string() + ": cannot read the probe points file");
    if (points.empty())
        throw io::FormatError(path.string() + ": no probe points (one \"x y z\" per line)");
    return points;
}

} // namespace hemi::bake
