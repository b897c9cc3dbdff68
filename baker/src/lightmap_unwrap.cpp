// Planar-chart lightmap UVs (lightmap_unwrap.h).
#include <hemi/bake/lightmap_unwrap.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace hemi::bake
{
namespace
{

struct Chart
{
    glm::vec3 n, u, v;                     // the plane's frame
    glm::vec2 lo{INFINITY}, hi{-INFINITY}; // extent of the projected vertices, world units
    std::vector<uint32_t> triangles;
    uint32_t x = 0, y = 0, w = 0, h = 0; // its rectangle in the atlas, texels
};

uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
}

using Triangle2 = std::array<glm::dvec2, 3>;

// Whether two triangles of a chart's plane overlap by more than `tolerance` (separating axes: the six edge
// normals). Triangles that only touch (a shared edge or corner) do not.
bool overlap(const Triangle2& a, const Triangle2& b, double tolerance)
{
    for (const Triangle2* t : {&a, &b})
        for (int e = 0; e < 3; ++e)
        {
            const glm::dvec2 d = (*t)[size_t((e + 1) % 3)] - (*t)[size_t(e)];
            const glm::dvec2 axis(-d.y, d.x);
            const double length = glm::length(axis);
            if (!(length > 0.0))
                continue;
            double lo_a = INFINITY, hi_a = -INFINITY, lo_b = INFINITY, hi_b = -INFINITY;
            for (int k = 0; k < 3; ++k)
            {
                const double pa = glm::dot(a[size_t(k)], axis) / length,
                             pb = glm::dot(b[size_t(k)], axis) / length;
                lo_a = std::min(lo_a, pa);
                hi_a = std::max(hi_a, pa);
                lo_b = std::min(lo_b, pb);
                hi_b = std::max(hi_b, pb);
            }
            if (hi_a <= lo_b + tolerance || hi_b <= lo_a + tolerance)
                return false;
        }
    return true;
}

// Skyline packing (bottom-left, best fit), tallest first, into a `width`-texel-wide atlas: each chart goes
// where its top ends lowest, on the skyline of what is placed, `padding` texels from its neighbours and the
// border. The height used, or 0 when a chart is wider than the atlas or the atlas would pass 16384.
uint32_t pack(std::vector<Chart>& charts, float texel, uint32_t width, uint32_t padding)
{
    std::vector<size_t> order(charts.size());
    std::iota(order.begin(), order.end(), size_t(0));
    for (Chart& c : charts)
    {
        // The chart starts a quarter texel into its rectangle; +1 covers the texels its far edge touches.
        c.w = uint32_t(std::ceil(double(c.hi.x - c.lo.x) / texel + 1.0));
        c.h = uint32_t(std::ceil(double(c.hi.y - c.lo.y) / texel + 1.0));
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) {
                         return charts[a].h != charts[b].h ? charts[a].h > charts[b].h
                                                           : charts[a].w > charts[b].w;
                     });
    struct Segment
    {
        uint64_t x, y, w; // the skyline is at height y over [x, x + w)
    };
    std::vector<Segment> skyline = {{padding, padding, uint64_t(width) - std::min<uint64_t>(width, padding)}};
    uint64_t top = padding;
    for (size_t i : order)
    {
        Chart& c = charts[i];
        const uint64_t w = uint64_t(c.w) + padding,
                       h = uint64_t(c.h) + padding; // with the gap to the right / above
        if (uint64_t(c.w) + 2 * padding > width)
            return 0;
        uint64_t best_y = ~uint64_t(0), best_x = 0;
        size_t best = skyline.size();
        for (size_t s = 0; s < skyline.size(); ++s)
        {
            const uint64_t x = skyline[s].x;
            if (x + c.w + padding > width)
                break;
            uint64_t y = 0, covered = 0;
            for (size_t k = s; k < skyline.size() && covered < w; ++k)
            {
                y = std::max(y, skyline[k].y);
                covered = skyline[k].x + skyline[k].w - x;
            }
            if (y + h < best_y || (y + h == best_y && x < best_x))
            {
                best_y = y + h;
                best_x = x;
                best = s;
            }
        }
        if (best == skyline.size())
            return 0;
        c.x = uint32_t(best_x);
        c.y = uint32_t(best_y - h);
        top = std::max(top, best_y);
        if (top > 16384)
            return 0;
        // The new segment replaces what it covers; the segment it ends inside keeps its remainder.
        const uint64_t end = best_x + w;
        std::vector<Segment> next(skyline.begin(), skyline.begin() + ptrdiff_t(best));
        next.push_back({best_x, best_y, w});
        for (size_t k = best; k < skyline.size(); ++k)
        {
            const Segment& g = skyline[k];
            if (g.x + g.w <= end)
                continue;
            if (g.x < end)
                next.push_back({end, g.y, g.x + g.w - end});
            else
                next.push_back(g);
        }
        // Neighbours at one height merge.
        skyline.clear();
        for (const Segment& g : next)
            if (!skyline.empty() && skyline.back().y == g.y)
                skyline.back().w += g.w;
            else
                skyline.push_back(g);
    }
    return uint32_t(top);
}

// The largest coordinate unwrap_lightmap charts: its square and a triangle's doubled area stay within a
// float's range (3.4e38).
constexpr float kMaxUnwrapCoordinate = 1e18f;

} // namespace

UnwrapResult unwrap_lightmap(io::Mesh& mesh, const UnwrapOptions& o)
{
    if (std::string p = io::mesh_problem(mesh, io::MeshNeeds::Normals); !p.empty())
        throw std::invalid_argument("cannot unwrap the mesh: " + p);
    if (!(o.texel_size >= 0.0f) || !std::isfinite(o.texel_size))
        throw std::invalid_argument("the texel size must be a finite number >= 0");
    if (!(o.max_chart_angle_degrees > 0.0f && o.max_chart_angle_degrees < 90.0f))
        throw std::invalid_argument("the chart angle must be in (0, 90) degrees");
    if (o.padding > 64 || o.width > 16384 || o.height > 16384 || (o.width == 0) != (o.height == 0))
        throw std::invalid_argument(
            "the atlas must be W x H with both in [1, 16384] (or neither), padding <= 64");
    // The charts' geometry is float: an edge's squared length (a normal's, an area's) must stay finite.
    float largest = 0.0f;
    for (const glm::vec3& p : mesh.positions)
        largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    if (largest > kMaxUnwrapCoordinate)
    {
        char text[160];
        std::snprintf(text, sizeof text,
                      "cannot unwrap the mesh: its positions reach %.3g units, beyond the %.0e that charting "
                      "holds (squared lengths overflow a float); scale the scene down",
                      double(largest), double(kMaxUnwrapCoordinate));
        throw std::invalid_argument(text);
    }

    const size_t triangles = mesh.indices.size() / 3;
    // Weld by position, so that seams of the normal-map UVs (split vertices) do not split charts.
    std::unordered_map<std::string, uint32_t> ids;
    std::vector<uint32_t> weld(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v)
    {
        std::string key(sizeof(glm::vec3), '\0');
        std::memcpy(key.data(), &mesh.positions[v], sizeof(glm::vec3));
        weld[v] = ids.emplace(std::move(key), uint32_t(ids.size())).first->second;
    }
    std::vector<glm::vec3> normal(triangles);
    std::vector<double> area(triangles);
    std::unordered_map<uint64_t, std::vector<uint32_t>> edges;
    for (uint32_t t = 0; t < triangles; ++t)
    {
        const uint32_t* i = &mesh.indices[size_t(t) * 3];
        const glm::vec3 c = glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]],
                                       mesh.positions[i[2]] - mesh.positions[i[0]]);
        area[t] = 0.5 * double(glm::length(c));
        normal[t] = area[t] > 0.0 ? glm::normalize(c) : glm::vec3(0.0f);
        for (int e = 0; e < 3; ++e)
            edges[edge_key(weld[i[e]], weld[i[(e + 1) % 3]])].push_back(t);
    }

    // Charts: seeds in order of decreasing area (the largest faces set the planes), flood fill over shared
    // edges while the normal stays within the angle of the seed's.
    std::vector<uint32_t> seeds(triangles);
    std::iota(seeds.begin(), seeds.end(), 0u);
    std::stable_sort(seeds.begin(), seeds.end(), [&](uint32_t a, uint32_t b) { return area[a] > area[b]; });
    const float cos_max = std::cos(o.max_chart_angle_degrees * float(M_PI) / 180.0f);
    constexpr uint32_t kNone = ~0u;
    std::vector<uint32_t> chart_of(triangles, kNone);
    std::vector<Chart> charts;
    for (uint32_t seed : seeds)
    {
        if (chart_of[seed] != kNone || !(area[seed] > 0.0))
            continue;
        Chart c;
        c.n = normal[seed];
        const uint32_t id = uint32_t(charts.size());
        // A triangle joins only where its projection onto the seed's plane overlaps none of the chart's: two
        // faces of one plane modelled over each other (as shipped levels have them) or a surface folding
        // back within the angle would otherwise give two triangles one texel. Projections are looked up in
        // a grid of cells as large as the seed's longest edge (the seed has the chart's largest area, but a
        // long sliver can span many cells, and many small triangles can share one: a mesh of very uneven
        // triangles would want a grid of several levels). Overlaps shallower than the tolerance pass.
        const glm::dvec3 fu =
            glm::normalize(glm::dvec3(std::abs(c.n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)) -
                           glm::dvec3(c.n) * double(std::abs(c.n.x) < 0.9f ? c.n.x : c.n.y));
        const glm::dvec3 fv = glm::cross(glm::dvec3(c.n), fu);
        const auto project = [&](uint32_t t)
        {
            Triangle2 q;
            for (size_t k = 0; k < 3; ++k)
            {
                const glm::dvec3 p(mesh.positions[mesh.indices[size_t(t) * 3 + k]]);
                q[k] = {glm::dot(p, fu), glm::dot(p, fv)};
            }
            return q;
        };
        const Triangle2 first = project(seed);
        double cell = 0.0;
        for (size_t k = 0; k < 3; ++k)
            cell = std::max(cell, glm::length(first[(k + 1) % 3] - first[k]));
        const double tolerance = 1e-5 * cell;
        std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
        const auto cells_of = [&](const Triangle2& q, auto&& use)
        {
            const glm::dvec2 lo = glm::min(glm::min(q[0], q[1]), q[2]),
                             hi = glm::max(glm::max(q[0], q[1]), q[2]);
            const int64_t x0 = int64_t(std::floor(lo.x / cell)), x1 = int64_t(std::floor(hi.x / cell)),
                          y0 = int64_t(std::floor(lo.y / cell)), y1 = int64_t(std::floor(hi.y / cell));
            for (int64_t y = y0; y <= y1; ++y)
                for (int64_t x = x0; x <= x1; ++x)
                    if (!use(uint64_t(x) * 0x9E3779B97F4A7C15ull ^ uint64_t(y)))
                        return false;
            return true;
        };
        std::unordered_set<uint32_t> rejected; // tried for this chart and overlapping it
        const auto fits = [&](uint32_t t)
        {
            const Triangle2 q = project(t);
            return cells_of(q,
                            [&](uint64_t key)
                            {
                                const auto it = grid.find(key);
                                if (it == grid.end())
                                    return true;
                                for (const uint32_t other : it->second)
                                    if (overlap(q, project(other), tolerance))
                                        return false;
                                return true;
                            });
        };
        const auto place = [&](uint32_t t)
        {
            cells_of(project(t),
                     [&](uint64_t key)
                     {
                         grid[key].push_back(t);
                         return true;
                     });
        };
        std::vector<uint32_t> stack = {seed};
        chart_of[seed] = id;
        place(seed);
        while (!stack.empty())
        {
            const uint32_t t = stack.back();
            stack.pop_back();
            c.triangles.push_back(t);
            const uint32_t* i = &mesh.indices[size_t(t) * 3];
            for (int e = 0; e < 3; ++e)
                for (uint32_t other : edges[edge_key(weld[i[e]], weld[i[(e + 1) % 3]])])
                    if (chart_of[other] == kNone && area[other] > 0.0 &&
                        glm::dot(normal[other], c.n) >= cos_max && !rejected.count(other))
                    {
                        if (!fits(other))
                        {
                            rejected.insert(other);
                            continue;
                        }
                        chart_of[other] = id;
                        place(other);
                        stack.push_back(other);
                    }
        }
        std::sort(c.triangles.begin(), c.triangles.end()); // deterministic, whatever the fill order
        // The plane's u along the chart's longest boundary edge (an edge no other triangle of the chart
        // shares: interior diagonals would turn a rectangular wall by atan(h / w) in its box).
        float longest = 0.0f;
        c.u = std::abs(c.n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        for (uint32_t t : c.triangles)
            for (int e = 0; e < 3; ++e)
            {
                const uint32_t a = mesh.indices[size_t(t) * 3 + e],
                               b = mesh.indices[size_t(t) * 3 + (e + 1) % 3];
                int in_chart = 0;
                for (uint32_t other : edges[edge_key(weld[a], weld[b])])
                    in_chart += chart_of[other] == id;
                if (in_chart != 1)
                    continue;
                glm::vec3 d = mesh.positions[b] - mesh.positions[a];
                d -= c.n * glm::dot(c.n, d);
                if (glm::length(d) > longest * 1.0001f)
                {
                    longest = glm::length(d);
                    c.u = d / longest;
                }
            }
        c.u = glm::normalize(c.u - c.n * glm::dot(c.n, c.u));
        c.v = glm::cross(c.n, c.u);
        for (uint32_t t : c.triangles)
            for (int e = 0; e < 3; ++e)
            {
                const glm::vec3& p = mesh.positions[mesh.indices[size_t(t) * 3 + e]];
                const glm::vec2 q(glm::dot(p, c.u), glm::dot(p, c.v));
                c.lo = glm::min(c.lo, q);
                c.hi = glm::max(c.hi, q);
            }
        charts.push_back(std::move(c));
    }
    if (charts.empty())
        throw std::invalid_argument("cannot unwrap the mesh: every triangle has zero area");

    // The texel size and the atlas.
    UnwrapResult r;
    r.charts = charts.size();
    double box_area = 0.0;
    for (const Chart& c : charts)
        box_area += double(c.hi.x - c.lo.x + 1e-6f) * double(c.hi.y - c.lo.y + 1e-6f);
    uint32_t width = o.width, height = o.height;
    float texel = o.texel_size;
    if (texel > 0.0f)
    {
        // A chart wider than the largest atlas at this texel size (a texel size of 1e-30) fits no packing.
        double widest_side = 0.0;
        for (const Chart& c : charts)
            widest_side =
                std::max({widest_side, double(c.hi.x - c.lo.x) / texel, double(c.hi.y - c.lo.y) / texel});
        if (!(widest_side + 1.0 + 2.0 * o.padding <= 16384.0))
        {
            char text[160];
            std::snprintf(text, sizeof text,
                          "a chart at texel size %g is %.3g texels across, more than a 16384 x 16384 atlas "
                          "holds: choose a larger texel size",
                          double(texel), widest_side);
            throw std::invalid_argument(text);
        }
        if (width == 0)
        {
            double texels = 0.0;
            for (const Chart& c : charts)
                texels += (double(c.hi.x - c.lo.x) / texel + 1.0 + o.padding) *
                          (double(c.hi.y - c.lo.y) / texel + 1.0 + o.padding);
            // The smallest atlas over widths from the area's square root up (aspect at most 2: 1): shelves
            // waste least where the width suits the charts.
            // Failing the 2:1 rule (a chart much wider than the rest is tall), the smallest packing that
            // fits.
            uint64_t best = ~uint64_t(0), any = ~uint64_t(0);
            uint32_t any_width = 0, any_height = 0;
            double widest = 0.0;
            for (const Chart& c : charts)
                widest = std::max(widest, std::ceil(double(c.hi.x - c.lo.x) / texel + 1.0) + 2.0 * o.padding);
            // Charts that cannot fit at this texel size however they are packed (a texel size of 1e-30).
            if (!(widest <= 16384.0) || !(texels <= 16384.0 * 16384.0))
            {
                char text[160];
                std::snprintf(
                    text, sizeof text,
                    "the charts at texel size %g need %.3g texels (%.3g across the widest), more than "
                    "a 16384 x 16384 atlas holds: choose a larger texel size",
                    double(texel), texels, widest);
                throw std::invalid_argument(text);
            }
            const double side = std::max(std::sqrt(texels), widest);
            for (double f = 1.0; f <= 2.0; f += 0.05)
            {
                const uint32_t wide = uint32_t(std::clamp(std::ceil(side * f), 16.0, 16384.0));
                const uint32_t used = pack(charts, texel, wide, o.padding);
                if (used != 0 && uint64_t(wide) * used < any)
                {
                    any = uint64_t(wide) * used;
                    any_width = wide;
                    any_height = used;
                }
                if (used != 0 && used <= 2 * wide && wide <= 2 * used && uint64_t(wide) * used < best)
                {
                    best = uint64_t(wide) * used;
                    width = wide;
                    height = used;
                }
            }
            if (best == ~uint64_t(0) && any != ~uint64_t(0))
            {
                best = any;
                width = any_width;
                height = any_height;
            }
            if (best == ~uint64_t(0))
                throw std::invalid_argument("the charts at texel size " + std::to_string(texel) +
                                            " do not fit a 16384 x 16384 atlas: choose a larger texel size");
            pack(charts, texel, width,
                 o.padding); // the chosen packing, its height the shelves' (no wasted rows)
        }
        else if (const uint32_t used = pack(charts, texel, width, o.padding); used == 0 || used > height)
            throw std::invalid_argument("the charts at texel size " + std::to_string(texel) +
                                        " do not fit a " + std::to_string(width) + " x " +
                                        std::to_string(height) +
                                        " atlas: choose a larger atlas or texel size");
    }
    else
    {
        if (width == 0)
            width = height = 512;
        // The densest packing that fits: start from filling about 70% of the atlas, shrink by 3%.
        double density = std::sqrt(0.7 * double(width) * height / box_area);
        for (int attempt = 0;; ++attempt)
        {
            texel = float(1.0 / density);
            const uint32_t used = pack(charts, texel, width, o.padding);
            if (used != 0 && used <= height)
                break;
            density *= 0.97;
            if (attempt > 400)
                throw std::invalid_argument("cannot pack " + std::to_string(charts.size()) +
                                            " charts into a " + std::to_string(width) + " x " +
                                            std::to_string(height) + " atlas");
        }
    }
    r.width = width;
    r.height = height;
    r.texel_size = texel;

    // New vertices: one per (vertex, chart) it is used in.
    io::Mesh out;
    const bool has_normals = !mesh.normals.empty(), has_tangents = !mesh.tangents.empty(),
               has_uvs = !mesh.uvs.empty();
    std::unordered_map<uint64_t, uint32_t> split;
    out.indices = mesh.indices;
    for (uint32_t t = 0; t < triangles; ++t)
    {
        const uint32_t c = chart_of[t];
        for (int e = 0; e < 3; ++e)
        {
            uint32_t& index = out.indices[size_t(t) * 3 + e];
            const uint32_t v = index;
            const uint64_t key = uint64_t(v) << 32 | (c == kNone ? 0xffffffffull : c);
            const auto [it, fresh] = split.emplace(key, uint32_t(out.positions.size()));
            if (fresh)
            {
                out.positions.push_back(mesh.positions[v]);
                if (has_normals)
                    out.normals.push_back(mesh.normals[v]);
                if (has_tangents)
                    out.tangents.push_back(mesh.tangents[v]);
                if (has_uvs)
                    out.uvs.push_back(mesh.uvs[v]);
                glm::vec2 uv(float(o.padding) / float(width),
                             float(o.padding) / float(height)); // zero-area triangles
                if (c != kNone)
                {
                    const Chart& ch = charts[c];
                    const glm::vec3& p = mesh.positions[v];
                    const glm::vec2 q(glm::dot(p, ch.u) - ch.lo.x, glm::dot(p, ch.v) - ch.lo.y);
                    // A quarter texel in: a chart's corners fall between texel centres, so no texel samples
                    // a corner of the surface itself (rays from a room's corner would graze out of it).
                    uv = glm::vec2((float(ch.x) + 0.25f + q.x / texel) / float(width),
                                   (float(ch.y) + 0.25f + q.y / texel) / float(height));
                }
                out.uvs1.push_back(uv);
            }
            index = it->second;
        }
    }
    r.vertices_added = out.positions.size() - mesh.positions.size();
    r.chart_of = chart_of;
    mesh = std::move(out);
    return r;
}

} // namespace hemi::bake
