// Lightmap UV validation and conservative rasterisation (lightmap_atlas.h).
#include <hemi/bake/lightmap_atlas.h>

#include "texel_origin.h"

#include <hemi/bake/embree_scene.h>
#include <hemi/bake/lightmap_denoise.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/io/memory.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace hemi::bake
{
namespace
{

using glm::dvec2;

double cross2(const dvec2& a, const dvec2& b)
{
    return a.x * b.y - a.y * b.x;
}

// The barycentric weights an atlas keeps of a sample point (LightmapTexels::Packed): vertices 1 and 2's.
glm::vec2 kept(const glm::dvec3& b)
{
    return {float(b.y), float(b.z)};
}

// Barycentric weights of p in triangle (a, b, c) of signed area2 = cross(b - a, c - a) != 0.
glm::dvec3 barycentric(const dvec2& p, const dvec2& a, const dvec2& b, const dvec2& c, double area2)
{
    const double w1 = cross2(p - a, c - a) / area2;
    const double w2 = cross2(b - a, p - a) / area2;
    return {1.0 - w1 - w2, w1, w2};
}

// Whether triangle (a, b, c) and the square [x0, x0 + size] x [y0, y0 + size] overlap (separating axes: the
// two coordinate axes and the three edge normals).
bool overlaps_square(const dvec2 t[3], double x0, double y0, double size = 1.0)
{
    const double lo_x = std::min({t[0].x, t[1].x, t[2].x}), hi_x = std::max({t[0].x, t[1].x, t[2].x});
    const double lo_y = std::min({t[0].y, t[1].y, t[2].y}), hi_y = std::max({t[0].y, t[1].y, t[2].y});
    if (hi_x < x0 || lo_x > x0 + size || hi_y < y0 || lo_y > y0 + size)
        return false;
    const dvec2 corners[4] = {{x0, y0}, {x0 + size, y0}, {x0, y0 + size}, {x0 + size, y0 + size}};
    for (int e = 0; e < 3; ++e)
    {
        const dvec2 a = t[e], b = t[(e + 1) % 3], other = t[(e + 2) % 3];
        const dvec2 n(-(b.y - a.y), b.x - a.x);
        const double side = glm::dot(n, other - a);
        bool all_out = true;
        for (const dvec2& q : corners)
            if (glm::dot(n, q - a) * side >= 0)
                all_out = false;
        if (all_out)
            return false;
    }
    return true;
}

// The part of triangle t inside the square [x0, x0 + 1] x [y0, y0 + 1] (Sutherland-Hodgman) and its
// centroid: a point of the triangle inside the texel's footprint. False when nothing with area is left.
bool clipped_centroid(const dvec2 t[3], double x0, double y0, dvec2& centroid)
{
    std::vector<dvec2> poly(t, t + 3), next;
    auto clip = [&](int axis, double bound, bool keep_below)
    {
        next.clear();
        for (size_t i = 0; i < poly.size(); ++i)
        {
            const dvec2 a = poly[i], b = poly[(i + 1) % poly.size()];
            const double da = keep_below ? bound - a[axis] : a[axis] - bound;
            const double db = keep_below ? bound - b[axis] : b[axis] - bound;
            if (da >= 0)
                next.push_back(a);
            if ((da >= 0) != (db >= 0))
                next.push_back(a + (b - a) * (da / (da - db)));
        }
        poly.swap(next);
    };
    clip(0, x0, false);
    clip(0, x0 + 1, true);
    clip(1, y0, false);
    clip(1, y0 + 1, true);
    if (poly.size() < 3)
        return false;
    double area = 0.0;
    dvec2 c(0.0);
    for (size_t i = 0; i < poly.size(); ++i)
    {
        const dvec2 a = poly[i], b = poly[(i + 1) % poly.size()];
        const double w = cross2(a, b);
        area += w;
        c += (a + b) * w;
    }
    if (std::abs(area) < 1e-18)
        return false;
    centroid = c / (3.0 * area);
    return true;
}

// Whether p is inside triangle t under a fill rule that gives a point on an edge shared by two triangles to
// exactly one of them (the edge's direction decides), so that a chart's texel centres are each claimed once
// and only true overlaps count twice.
bool claims(const dvec2 t[3], double area2, const dvec2& p)
{
    for (int e = 0; e < 3; ++e)
    {
        // Edges taken counter-clockwise: reverse them for a clockwise triangle.
        dvec2 a = t[e], b = t[(e + 1) % 3];
        if (area2 < 0)
            std::swap(a, b);
        const double f = cross2(b - a, p - a);
        if (f < 0)
            return false;
        if (f == 0)
        {
            const dvec2 d = b - a;
            if (!(d.y > 0 || (d.y == 0 && d.x > 0)))
                return false;
        }
    }
    return true;
}

std::string uv_text(const glm::vec2& uv)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "(%g, %g)", double(uv.x), double(uv.y));
    return buf;
}

// The mesh rasterize_lightmap needs (throws std::invalid_argument naming what is wrong).
void check_mesh(const io::Mesh& mesh, uint32_t width, uint32_t height)
{
    if (width == 0 || height == 0 || width > io::kMaxAtlasSide || height > io::kMaxAtlasSide)
        throw std::invalid_argument("lightmap size " + std::to_string(width) + "x" + std::to_string(height) +
                                    " is not in [1, " + std::to_string(io::kMaxAtlasSide) + "] per side");
    const size_t n = mesh.positions.size();
    if (n == 0 || mesh.indices.empty() || mesh.indices.size() % 3 != 0)
        throw std::invalid_argument("the mesh has no triangles");
    if (mesh.uvs1.size() != n)
        throw std::invalid_argument(
            "the mesh has no lightmap UVs (TEXCOORD_1): " + std::to_string(mesh.uvs1.size()) + " for " +
            std::to_string(n) + " vertices");
    if (mesh.normals.size() != n || mesh.tangents.size() != n)
        throw std::invalid_argument("the mesh needs a normal and a tangent per vertex for lightmap frames");
    for (uint32_t i : mesh.indices)
        if (i >= n)
            throw std::invalid_argument("triangle index " + std::to_string(i) + " out of range");
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(mesh.uvs1[i].x) || !std::isfinite(mesh.uvs1[i].y) ||
            !std::isfinite(mesh.positions[i].x) || !std::isfinite(mesh.positions[i].y) ||
            !std::isfinite(mesh.positions[i].z))
            throw std::invalid_argument("vertex " + std::to_string(i) +
                                        " has a non-finite position or lightmap UV");
}

// Triangle t's lightmap UVs in texels and twice its signed area there; false for a triangle no texel holds
// (zero area in space or in UV space).
bool triangle_uvs(const io::Mesh& mesh, size_t t, uint32_t width, uint32_t height, dvec2 uv[3], double& area2)
{
    const uint32_t* idx = &mesh.indices[t * 3];
    const glm::dvec3 p0(mesh.positions[idx[0]]), p1(mesh.positions[idx[1]]), p2(mesh.positions[idx[2]]);
    for (int k = 0; k < 3; ++k)
        uv[k] = dvec2(double(mesh.uvs1[idx[k]].x) * width, double(mesh.uvs1[idx[k]].y) * height);
    area2 = cross2(uv[1] - uv[0], uv[2] - uv[0]);
    return glm::length(glm::cross(p1 - p0, p2 - p0)) > 0.0 && std::abs(area2) >= 1e-12;
}

// The texels [x_begin, x_end] x [y_begin, y_end] of the atlas that a triangle's UV bounding box touches;
// false when none.
bool texel_bounds(const dvec2 uv[3], uint32_t width, uint32_t height, int64_t& x_begin, int64_t& x_end,
                  int64_t& y_begin, int64_t& y_end)
{
    const double lo_x = std::min({uv[0].x, uv[1].x, uv[2].x}), hi_x = std::max({uv[0].x, uv[1].x, uv[2].x});
    const double lo_y = std::min({uv[0].y, uv[1].y, uv[2].y}), hi_y = std::max({uv[0].y, uv[1].y, uv[2].y});
    x_begin = std::max<int64_t>(0, int64_t(std::floor(lo_x)));
    x_end = std::min<int64_t>(int64_t(width) - 1, int64_t(std::floor(hi_x)));
    y_begin = std::max<int64_t>(0, int64_t(std::floor(lo_y)));
    y_end = std::min<int64_t>(int64_t(height) - 1, int64_t(std::floor(hi_y)));
    return x_begin <= x_end && y_begin <= y_end;
}

// The most candidates a texel keeps: of a texel that more triangles claim (a quad copied thousands of times
// over one UV square, where judging each would cost more than the bake, and the candidates more memory than
// the lightmap) the first 64 by triangle index.
constexpr uint8_t kMaxCandidates = 64;

// A texel's candidate: its slot, the triangle, and where on it the texel samples (the centre's barycentric
// coordinates for a triangle that claims the centre, the centroid of its part of the square for one that
// grazes it).
struct Candidate
{
    size_t slot;
    uint32_t triangle;
    bool operator<(const Candidate& o) const
    {
        return slot != o.slot ? slot < o.slot : triangle < o.triangle;
    }
};

glm::dvec3 sample_barycentric(const io::Mesh& mesh, const io::BlockGrid& grid, const Candidate& c,
                              bool grazes, double* distance = nullptr)
{
    dvec2 uv[3];
    double area2;
    triangle_uvs(mesh, c.triangle, grid.width(), grid.height(), uv, area2);
    const glm::uvec2 xy = grid.texel(c.slot);
    const dvec2 centre(xy.x + 0.5, xy.y + 0.5);
    dvec2 q = centre;
    if (grazes && !clipped_centroid(uv, double(xy.x), double(xy.y), q))
        q = centre;
    glm::dvec3 b = glm::max(barycentric(q, uv[0], uv[1], uv[2], area2), glm::dvec3(0.0));
    if (distance)
        *distance = glm::length(q - centre);
    return b / (b.x + b.y + b.z);
}

// What judges overlapping texels: the mesh's ray tracer and the bake's test of a texel inside geometry,
// made when first asked for (only meshes with overlaps or charts that share texels pay for them) and kept
// for every band of the atlas.
class OverlapJudge
{
  public:
    OverlapJudge(const io::Mesh& mesh, uint32_t width, uint32_t height, std::span<const uint8_t> double_sided)
        : mesh_(mesh), width_(width), height_(height), double_sided_(double_sided)
    {
    }
    const detail::TexelOrigins& origins()
    {
        if (!origins_)
        {
            scene_ = std::make_unique<EmbreeScene>(mesh_);
            const float offset = scene_->ray_offset(1e-4f); // LightmapBakeOptions::ray_offset's default
            origins_ = std::make_unique<detail::TexelOrigins>(*scene_, mesh_, width_, height_, offset,
                                                              [sided = double_sided_](uint32_t t)
                                                              { return t < sided.size() && sided[t]; });
        }
        return *origins_;
    }
    // The scene's centre: the area-weighted centroid of its surfaces (a few faces far out, as levels have
    // them, move it little; they would move the bounding box's centre out of the playable space); and the
    // distance within which two planes are one, 1e-4 of its bounding box's diagonal. Found once, for every
    // band.
    glm::dvec3 scene_centre()
    {
        measure();
        return centre_;
    }
    double tolerance()
    {
        measure();
        return tolerance_;
    }

  private:
    void measure()
    {
        if (measured_)
            return;
        auto corner = [&](uint32_t t, int k)
        { return glm::dvec3(mesh_.positions[mesh_.indices[size_t(t) * 3 + k]]); };
        glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        glm::dvec3 weighted(0.0);
        double area = 0.0;
        for (uint32_t t = 0; t < mesh_.indices.size() / 3; ++t)
        {
            const glm::dvec3 a = corner(t, 0), b = corner(t, 1), c = corner(t, 2);
            const double w = 0.5 * glm::length(glm::cross(b - a, c - a));
            weighted += w * (a + b + c) / 3.0;
            area += w;
            lo = glm::min(lo, glm::min(a, glm::min(b, c)));
            hi = glm::max(hi, glm::max(a, glm::max(b, c)));
        }
        centre_ = area > 0.0 ? weighted / area : 0.5 * (lo + hi);
        tolerance_ = 1e-4 * glm::length(hi - lo);
        measured_ = true;
    }

    const io::Mesh& mesh_;
    uint32_t width_, height_;
    std::span<const uint8_t> double_sided_;
    std::unique_ptr<EmbreeScene> scene_;
    std::unique_ptr<detail::TexelOrigins> origins_;
    bool measured_ = false;
    glm::dvec3 centre_{0.0};
    double tolerance_ = 0.0;
};

// Per candidate (`which`: indices into `candidates`, each sampled as sample_barycentric gives), 1 when the
// texel lies inside geometry there as the lightmap bake judges a texel (detail::TexelOrigins, with its
// footprint). Deterministic on any thread count.
std::vector<uint8_t> inside_geometry(const io::Mesh& mesh, const io::BlockGrid& grid,
                                     const std::vector<Candidate>& candidates, bool grazes,
                                     std::span<const size_t> which, OverlapJudge& judge)
{
    std::vector<uint8_t> inside(which.size(), 0);
    if (which.empty())
        return inside;
    const detail::TexelOrigins& origins = judge.origins();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, which.size(), 16),
                      [&](const tbb::blocked_range<size_t>& r)
                      {
                          for (size_t k = r.begin(); k != r.end(); ++k)
                          {
                              const Candidate& c = candidates[which[k]];
                              const glm::uvec2 xy = grid.texel(c.slot);
                              inside[k] = origins
                                              .find(c.triangle, xy.x, xy.y,
                                                    glm::vec3(sample_barycentric(mesh, grid, c, grazes)))
                                              .inside;
                          }
                      });
    return inside;
}

// Overlapping lightmap UVs, as shipped levels have them (a face modelled twice back to back on one UV
// rectangle, decals on walls, a face the level's compiler left inside a wall sharing a lightmap rectangle
// with a visible one), resolved deterministically: each texel centre that several triangles claim goes to
// one of them, chosen by, in order,
//   0. the side a viewer can reach: a candidate whose point lies inside geometry as the bake judges it
//      (inside_geometry) loses to one whose point does not (a texel given to a hidden face would be filled
//      from its neighbours, and the visible face sharing it would go dark);
//   1. the plane its chart continues in: the most of the texel's 8 neighbours whose centre only one triangle
//      claims and whose triangle lies in the candidate's plane, facing its way;
//   2. the side that faces into the scene: the largest cosine between the candidate's normal and the
//      direction from its centroid to the scene's centre (the area-weighted centroid of its surfaces; of a
//      back-to-back pair, the face towards the level's inside, which is the one a player sees);
//   3. the lower triangle index.
// The chosen triangle samples the texel's centre. Where every triangle that claims a texel's centre (one or
// several) lies inside geometry there, and a triangle of another chart grazes the texel (its UVs cover part
// of the square, not the centre: q3map2's lightmap pages put faces' rectangles side by side, unpadded), the
// lowest-index grazing triangle that does not lie inside geometry takes the texel, sampled at the centroid of
// its part of the square: a viewer sees that face there, and the texel would otherwise be filled from its
// neighbours.
// The tables are those of a band of the atlas: slot s's entry is at s - base (rasterize_lightmap).
void resolve_overlaps(const io::Mesh& mesh, const io::BlockGrid& grid, size_t base,
                      std::vector<Candidate>& contested, std::vector<Candidate>& grazing,
                      const std::vector<uint8_t>& inside_count, const std::vector<int32_t>& first_inside,
                      std::vector<int32_t>& best, std::vector<double>& best_distance,
                      std::vector<glm::vec2>& best_bary, OverlapJudge& judge, LightmapUvReport& report)
{
    std::sort(grazing.begin(), grazing.end());
    grazing.erase(std::unique(grazing.begin(), grazing.end(),
                              [](const Candidate& a, const Candidate& b)
                              { return a.slot == b.slot && a.triangle == b.triangle; }),
                  grazing.end());
    // A texel that one triangle claims and another chart's grazes: its claimant is judged too.
    for (size_t g = 0; g < grazing.size(); ++g)
        if ((g == 0 || grazing[g - 1].slot != grazing[g].slot) && inside_count[grazing[g].slot - base] == 1)
            contested.push_back({grazing[g].slot, uint32_t(first_inside[grazing[g].slot - base])});
    if (contested.empty())
        return;
    std::sort(contested.begin(), contested.end());
    std::vector<size_t> all(contested.size());
    for (size_t c = 0; c < all.size(); ++c)
        all[c] = c;
    const std::vector<uint8_t> hidden = inside_geometry(mesh, grid, contested, false, all, judge);
    // The grazing triangles of texels whose every claimant is hidden.
    std::vector<size_t> judged;
    {
        size_t c = 0;
        for (size_t g = 0; g < grazing.size(); ++g)
        {
            while (c < contested.size() && contested[c].slot < grazing[g].slot)
                ++c;
            bool every = c < contested.size() && contested[c].slot == grazing[g].slot;
            for (size_t k = c; k < contested.size() && contested[k].slot == grazing[g].slot; ++k)
                every = every && hidden[k];
            if (every)
                judged.push_back(g);
        }
    }
    const std::vector<uint8_t> grazer_hidden = inside_geometry(mesh, grid, grazing, true, judged, judge);
    std::vector<uint8_t> grazer_visible(grazing.size(), 0);
    for (size_t k = 0; k < judged.size(); ++k)
        grazer_visible[judged[k]] = !grazer_hidden[k];
    size_t next_grazer = 0;
    auto corner = [&](uint32_t t, int k)
    { return glm::dvec3(mesh.positions[mesh.indices[size_t(t) * 3 + k]]); };
    const glm::dvec3 scene_centre = judge.scene_centre();
    const double tolerance = judge.tolerance();
    auto normal = [&](uint32_t t)
    { return glm::normalize(glm::cross(corner(t, 1) - corner(t, 0), corner(t, 2) - corner(t, 0))); };
    auto same_plane = [&](uint32_t a, uint32_t b)
    {
        if (a == b)
            return true;
        const glm::dvec3 na = normal(a);
        return glm::dot(na, normal(b)) > 0.999 &&
               std::abs(glm::dot(na, corner(b, 0) - corner(a, 0))) <= tolerance;
    };
    const uint32_t width = grid.width(), height = grid.height();
    for (size_t first = 0; first < contested.size();)
    {
        const size_t slot = contested[first].slot;
        size_t last = first;
        while (last < contested.size() && contested[last].slot == slot)
            ++last;
        const glm::uvec2 xy = grid.texel(slot);
        uint32_t winner = contested[first].triangle;
        int winner_hidden = 2, winner_support = -1;
        double winner_facing = -2.0;
        for (size_t c = first; c < last; ++c)
        {
            const uint32_t t = contested[c].triangle;
            if (c > first && t == contested[c - 1].triangle)
                continue;
            int support = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                {
                    const int64_t n = grid.slot(int64_t(xy.x) + dx, int64_t(xy.y) + dy);
                    if ((dx || dy) && n >= 0 && inside_count[size_t(n) - base] == 1 &&
                        best[size_t(n) - base] >= 0 && same_plane(t, uint32_t(best[size_t(n) - base])))
                        ++support;
                }
            const glm::dvec3 centroid = (corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0;
            const glm::dvec3 to_centre = scene_centre - centroid;
            const double facing =
                glm::length(to_centre) > tolerance ? glm::dot(normal(t), glm::normalize(to_centre)) : 0.0;
            // Candidates come in ascending triangle order, so a tie keeps the lower index.
            const int is_hidden = hidden[c];
            if (is_hidden < winner_hidden ||
                (is_hidden == winner_hidden &&
                 (support > winner_support || (support == winner_support && facing > winner_facing + 1e-9))))
            {
                winner = t;
                winner_hidden = is_hidden;
                winner_support = support;
                winner_facing = facing;
            }
        }
        dvec2 uv[3];
        double area2;
        triangle_uvs(mesh, winner, width, height, uv, area2);
        const size_t at = slot - base;
        best[at] = int32_t(winner);
        best_distance[at] = 0.0;
        best_bary[at] = kept(barycentric(dvec2(xy.x + 0.5, xy.y + 0.5), uv[0], uv[1], uv[2], area2));
        while (next_grazer < grazing.size() && grazing[next_grazer].slot < slot)
            ++next_grazer;
        for (size_t g = next_grazer; winner_hidden && g < grazing.size() && grazing[g].slot == slot; ++g)
            if (grazer_visible[g])
            {
                best[at] = int32_t(grazing[g].triangle);
                best_bary[at] = kept(sample_barycentric(mesh, grid, grazing[g], true, &best_distance[at]));
                ++report.grazed_instead;
                break;
            }
        if (inside_count[at] >= 2)
            report.overlaps.push_back(xy);
        first = last;
    }
}

} // namespace

LightmapTexels::LightmapTexels(const io::Mesh& mesh, uint32_t width, uint32_t height,
                               PagedArray<Packed> packed, std::vector<uint32_t> charts)
    : packed_(std::move(packed)), charts_(std::move(charts)), width_(width), height_(height),
      positions_(mesh.positions), normals_(mesh.normals), tangents_(mesh.tangents), uvs1_(mesh.uvs1),
      indices_(mesh.indices)
{
}

glm::vec3 LightmapTexels::geometric_normal(size_t i) const
{
    const uint32_t* idx = &indices_[size_t(triangle(i)) * 3];
    const glm::dvec3 p0(positions_[idx[0]]), p1(positions_[idx[1]]), p2(positions_[idx[2]]);
    return glm::vec3(glm::normalize(glm::cross(p1 - p0, p2 - p0)));
}

LightmapTexel LightmapTexels::operator[](size_t i) const
{
    const Packed k = packed_[i];
    LightmapTexel out;
    out.x = k.x;
    out.y = k.y;
    const size_t t = k.triangle & ~kCentreInside;
    out.triangle = uint32_t(t);
    out.centre_inside = (k.triangle & kCentreInside) != 0;
    const glm::dvec3 b(std::max(0.0, 1.0 - double(k.b1) - double(k.b2)), double(k.b1), double(k.b2));
    out.barycentric = glm::vec3(b);
    const uint32_t* idx = &indices_[t * 3];
    const glm::dvec3 p0(positions_[idx[0]]), p1(positions_[idx[1]]), p2(positions_[idx[2]]);
    out.position = glm::vec3(b.x * p0 + b.y * p1 + b.z * p2);
    const glm::dvec3 cross = glm::cross(p1 - p0, p2 - p0);
    const glm::dvec3 g = glm::normalize(cross); // as geometric_normal()
    out.geometric_normal = glm::vec3(g);
    glm::dvec3 nrm = b.x * glm::dvec3(normals_[idx[0]]) + b.y * glm::dvec3(normals_[idx[1]]) +
                     b.z * glm::dvec3(normals_[idx[2]]);
    nrm = glm::length(nrm) > 1e-12 ? glm::normalize(nrm) : g;
    const glm::dvec4 t4 = b.x * glm::dvec4(tangents_[idx[0]]) + b.y * glm::dvec4(tangents_[idx[1]]) +
                          b.z * glm::dvec4(tangents_[idx[2]]);
    glm::dvec3 tan = glm::dvec3(t4) - nrm * glm::dot(nrm, glm::dvec3(t4));
    if (glm::length(tan) < 1e-9)
    {
        // No usable tangent: any direction orthogonal to the normal.
        tan = std::abs(nrm.x) < 0.9 ? glm::cross(nrm, glm::dvec3(1, 0, 0))
                                    : glm::cross(nrm, glm::dvec3(0, 1, 0));
    }
    tan = glm::normalize(tan);
    const double w = tangents_[idx[0]].w < 0.0f ? -1.0 : 1.0;
    out.normal = glm::vec3(nrm);
    out.tangent = glm::vec3(tan);
    out.bitangent = glm::vec3(glm::cross(nrm, tan) * w);
    // The footprint: world area over lightmap UV area (in texels), as the rasteriser's density report has it.
    dvec2 uv[3];
    for (int c = 0; c < 3; ++c)
        uv[c] = dvec2(double(uvs1_[idx[c]].x) * width_, double(uvs1_[idx[c]].y) * height_);
    const double world_area = 0.5 * glm::length(cross),
                 uv_area = 0.5 * std::abs(cross2(uv[1] - uv[0], uv[2] - uv[0]));
    out.world_size = float(std::sqrt(world_area / uv_area));
    out.chart = charts_[t];
    return out;
}

io::BlockGrid lightmap_blocks(const io::Mesh& mesh, uint32_t width, uint32_t height)
{
    check_mesh(mesh, width, height);
    constexpr uint32_t B = io::BlockGrid::kSize;
    const uint32_t bx = (width + B - 1) / B, by = (height + B - 1) / B;
    std::vector<uint8_t> touched(size_t(bx) * by, 0);
    for (size_t t = 0; t < mesh.indices.size() / 3; ++t)
    {
        dvec2 uv[3];
        double area2;
        int64_t x0, x1, y0, y1;
        if (!triangle_uvs(mesh, t, width, height, uv, area2) ||
            !texel_bounds(uv, width, height, x0, x1, y0, y1))
            continue;
        // A block touched by the triangle contains every texel it touches; the block's square is widened by a
        // hair so that rounding cannot drop a block whose texel the exact test keeps.
        for (int64_t j = y0 / B; j <= y1 / B; ++j)
            for (int64_t i = x0 / B; i <= x1 / B; ++i)
                if (!touched[size_t(j) * bx + size_t(i)] &&
                    overlaps_square(uv, double(i * B) - 1e-6, double(j * B) - 1e-6, B + 2e-6))
                    touched[size_t(j) * bx + size_t(i)] = 1;
    }
    std::vector<uint32_t> blocks;
    for (size_t b = 0; b < touched.size(); ++b)
        if (touched[b])
            blocks.push_back(uint32_t(b));
    return io::BlockGrid(width, height, std::move(blocks));
}

LightmapAtlas rasterize_lightmap(const io::Mesh& mesh, uint32_t width, uint32_t height,
                                 LightmapUvReport& report, const std::vector<TriangleRange>& ranges,
                                 std::span<const uint8_t> double_sided, uint64_t overlap_budget,
                                 size_t band_slots, const LightmapAtlasStorage& storage)
{
    io::BlockGrid grid = lightmap_blocks(mesh, width, height); // checks the mesh
    report = {};
    const size_t triangles = mesh.indices.size() / 3;
    report.triangles = triangles;
    const std::vector<uint32_t> chart_of = lightmap_charts(mesh);
    OverlapJudge judge(mesh, width, height, double_sided);

    // Each triangle once: what the report says of it, its areas for the density, and the texel rows its UVs'
    // bounding box touches (row_end 0: none, it holds no texel).
    size_t example_outside = SIZE_MAX, example_degenerate = SIZE_MAX;
    std::vector<double> world_area(triangles, 0.0), uv_area(triangles, 0.0);
    std::vector<uint32_t> row_begin(triangles, 0), row_end(triangles, 0);
    for (size_t t = 0; t < triangles; ++t)
    {
        const uint32_t* idx = &mesh.indices[t * 3];
        const glm::dvec3 p0(mesh.positions[idx[0]]), p1(mesh.positions[idx[1]]), p2(mesh.positions[idx[2]]);
        world_area[t] = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
        dvec2 uv[3];
        bool out = false;
        for (int k = 0; k < 3; ++k)
        {
            const glm::vec2 u = mesh.uvs1[idx[k]];
            out = out || u.x < 0.0f || u.x > 1.0f || u.y < 0.0f || u.y > 1.0f;
            uv[k] = dvec2(double(u.x) * width, double(u.y) * height);
        }
        if (out)
        {
            ++report.outside;
            if (example_outside == SIZE_MAX)
                example_outside = t;
        }
        if (world_area[t] <= 0.0)
        {
            ++report.zero_area;
            continue;
        }
        const double area2 = cross2(uv[1] - uv[0], uv[2] - uv[0]);
        uv_area[t] = 0.5 * std::abs(area2);
        if (std::abs(area2) < 1e-12)
        {
            ++report.degenerate;
            if (example_degenerate == SIZE_MAX)
                example_degenerate = t;
            continue;
        }
        int64_t x_begin, x_end, y_begin, y_end;
        if (!texel_bounds(uv, width, height, x_begin, x_end, y_begin, y_end))
            continue;
        row_begin[t] = uint32_t(y_begin);
        row_end[t] = uint32_t(y_end + 1);
    }

    // The atlas in bands of whole block rows (one band without band_slots, or where it holds them all), each
    // with the block row above and below it: a texel's overlap is resolved from its 8 neighbours, which the
    // band then holds. The tables below are the band's, slot s at s - base. The same texels, records and
    // report as the whole atlas at once: every triangle that touches a band's texels is rasterised into it,
    // in the same order, and the row above holds the finished choices of the band before (the whole atlas
    // resolves its texels in slot order: a row above is finished, a row below not yet).
    const std::vector<uint32_t>& blocks = grid.blocks();
    const uint32_t bx = grid.blocks_x(), by = grid.blocks_y();
    constexpr uint32_t B = io::BlockGrid::kSize;
    std::vector<size_t> row_first(size_t(by) + 1); // per block row, its first kept block
    for (uint32_t r = 0; r <= by; ++r)
        row_first[r] = size_t(std::lower_bound(blocks.begin(), blocks.end(), uint64_t(r) * bx,
                                               [](uint32_t b, uint64_t v) { return uint64_t(b) < v; }) -
                              blocks.begin());
    const auto slot_of_row = [&](uint32_t r) { return row_first[r] * io::BlockGrid::kTexels; };

    LightmapAtlas atlas;
    atlas.width = width;
    atlas.height = height;
    PagedArray<LightmapTexels::Packed> packed;
    if (!storage.directory.empty())
    {
        packed = PagedArray<LightmapTexels::Packed>(PagedStore(
            sizeof(LightmapTexels::Packed), storage.directory, "texel-records", storage.cache_pages));
        atlas.slot_texel = PagedArray<int32_t>(
            PagedStore(sizeof(int32_t), storage.directory, "slot-texels", storage.cache_pages));
    }
    std::vector<int32_t> band_texel; // the band's own slots' texel indices, appended to atlas.slot_texel
    std::vector<int32_t> best;
    std::vector<double> best_distance;
    std::vector<glm::vec2> best_bary; // as kept (kept())
    std::vector<uint8_t> inside_count;
    std::vector<int32_t> first_inside;
    std::vector<Candidate> contested; // (slot, triangle) for centres two triangles claim
    std::vector<Candidate>
        grazing; // (slot, triangle) for another chart's triangles that graze a claimed texel
    std::vector<int32_t> finished_row; // the band before's last block row, as it was resolved
    // The first overlap (lowest triangle, then row, then column), as the whole atlas would name it.
    std::array<uint64_t, 3> example_key{UINT64_MAX, UINT64_MAX, UINT64_MAX};
    for (uint32_t r0 = 0; r0 < by;)
    {
        uint32_t r1 = r0 + 1;
        while (r1 < by && (band_slots == 0 || slot_of_row(r1 + 1) - slot_of_row(r0) <= band_slots))
            ++r1;
        const uint32_t e0 = r0 > 0 ? r0 - 1 : 0, e1 = std::min(by, r1 + 1);
        const size_t base = slot_of_row(e0), own_end = slot_of_row(r1);
        const size_t slots = slot_of_row(e1) - base;
        const int64_t y_lo = int64_t(e0) * B, y_hi = std::min<int64_t>(int64_t(e1) * B, height) - 1;
        const int64_t own_lo = int64_t(r0) * B, own_hi = std::min<int64_t>(int64_t(r1) * B, height) - 1;
        best.assign(slots, -1);
        best_distance.assign(slots, std::numeric_limits<double>::infinity());
        best_bary.assign(slots, glm::vec2(0.0f));
        inside_count.assign(slots, 0);
        first_inside.assign(slots, -1);
        contested.clear();
        grazing.clear();
        size_t band_overlaps = 0;
        // The candidates grow by doubling, within overlap_budget: refused before it is exceeded.
        auto room_for = [&](std::vector<Candidate>& list)
        {
            if (list.size() + 2 <= list.capacity())
                return;
            const size_t grown = std::max<size_t>(2 * list.capacity(), 1024);
            const size_t other = &list == &contested ? grazing.capacity() : contested.capacity();
            if (overlap_budget && (grown + other) * kOverlapCandidateBytes > overlap_budget)
                throw std::length_error(
                    "at least " + std::to_string(report.overlapping_texels + band_overlaps) +
                    " lightmap texels lie inside two or more triangles (overlapping lightmap UVs, as a mesh "
                    "instanced over one set of TEXCOORD_1 has them): resolving them needs more than " +
                    io::format_bytes((grown + other) * kOverlapCandidateBytes) +
                    " of memory, and the budget leaves " + io::format_bytes(overlap_budget));
            list.reserve(grown);
        };
        const auto in_band = [&](size_t t)
        { return row_end[t] > 0 && int64_t(row_begin[t]) <= y_hi && int64_t(row_end[t]) - 1 >= y_lo; };
        // Each texel (x, y) of rows [lo, hi] that the UV box of a triangle reaching the band touches,
        // triangle by triangle in order: visit(t, uv, area2, x, y).
        const auto each_texel = [&](int64_t lo, int64_t hi, auto&& visit)
        {
            for (size_t t = 0; t < triangles; ++t)
            {
                if (!in_band(t))
                    continue;
                dvec2 uv[3];
                double area2;
                triangle_uvs(mesh, t, width, height, uv, area2);
                int64_t x_begin, x_end, y_begin, y_end;
                texel_bounds(uv, width, height, x_begin, x_end, y_begin, y_end);
                for (int64_t y = std::max(y_begin, lo); y <= std::min(y_end, hi); ++y)
                    for (int64_t x = x_begin; x <= x_end; ++x)
                        visit(t, uv, area2, x, y);
            }
        };
        each_texel(y_lo, y_hi,
                   [&](size_t t, const dvec2(&uv)[3], double area2, int64_t x, int64_t y)
                   {
                       if (!overlaps_square(uv, double(x), double(y)))
                           return;
                       const int64_t slot = grid.slot(x, y);
                       if (slot < 0)
                           return; // cannot happen: lightmap_blocks keeps every block a triangle touches
                       const size_t texel = size_t(slot) - base;
                       const bool own = y >= own_lo && y <= own_hi;
                       const dvec2 centre(double(x) + 0.5, double(y) + 0.5);
                       glm::dvec3 b = barycentric(centre, uv[0], uv[1], uv[2], area2);
                       double distance = 0.0;
                       if (claims(uv, area2, centre))
                       {
                           if (own && inside_count[texel] >= 1)
                               room_for(contested);
                           if (inside_count[texel] == 0)
                               first_inside[texel] = int32_t(t);
                           else if (own && inside_count[texel] == 1)
                           {
                               if (band_overlaps == 0 &&
                                   std::array<uint64_t, 3>{t, uint64_t(y), uint64_t(x)} < example_key)
                               {
                                   example_key = {t, uint64_t(y), uint64_t(x)};
                                   report.overlap_example[0] = uint32_t(first_inside[texel]);
                                   report.overlap_example[1] = uint32_t(t);
                               }
                               ++band_overlaps;
                               contested.push_back({size_t(slot), uint32_t(first_inside[texel])});
                               contested.push_back({size_t(slot), uint32_t(t)});
                           }
                           else if (own && inside_count[texel] < kMaxCandidates)
                               contested.push_back({size_t(slot), uint32_t(t)});
                           inside_count[texel] = uint8_t(std::min(255, inside_count[texel] + 1));
                       }
                       if (!(b.x >= 0 && b.y >= 0 && b.z >= 0))
                       {
                           // A grazed texel: the centroid of the triangle's part inside its square.
                           dvec2 q;
                           if (!clipped_centroid(uv, double(x), double(y), q))
                               return; // touches the square only along an edge or at a corner
                           b = barycentric(q, uv[0], uv[1], uv[2], area2);
                           b = glm::max(b, glm::dvec3(0.0));
                           b /= (b.x + b.y + b.z);
                           distance = glm::length(q - centre);
                       }
                       if (distance < best_distance[texel])
                       {
                           best_distance[texel] = distance;
                           best[texel] = int32_t(t);
                           best_bary[texel] = kept(b);
                       }
                   });
        report.overlapping_texels += band_overlaps;
        // The row above as the band before resolved it.
        if (r0 > 0)
            std::copy(finished_row.begin(), finished_row.end(), best.begin());

        // Another chart's triangles that graze a texel of the band whose centre a triangle claims (a second
        // walk, once every texel's claimants are known).
        each_texel(own_lo, own_hi,
                   [&](size_t t, const dvec2(&uv)[3], double area2, int64_t x, int64_t y)
                   {
                       const int64_t slot = grid.slot(x, y);
                       dvec2 q;
                       if (slot < 0 || inside_count[size_t(slot) - base] == 0 ||
                           chart_of[t] == chart_of[size_t(first_inside[size_t(slot) - base])] ||
                           claims(uv, area2, dvec2(double(x) + 0.5, double(y) + 0.5)) ||
                           !overlaps_square(uv, double(x), double(y)) ||
                           !clipped_centroid(uv, double(x), double(y), q))
                           return;
                       room_for(grazing);
                       grazing.push_back({size_t(slot), uint32_t(t)});
                   });
        resolve_overlaps(mesh, grid, base, contested, grazing, inside_count, first_inside, best,
                         best_distance, best_bary, judge, report);
        // Covered texels in row-major order of the atlas: block row by block row, then texel row by texel row
        // across the row's kept blocks.
        const size_t own_begin = slot_of_row(r0);
        band_texel.assign(own_end - own_begin, -1);
        size_t texels = packed.size();
        for (uint32_t row = r0; row < r1; ++row)
        {
            const size_t first = row_first[row], last = row_first[row + 1];
            for (uint32_t ly = 0; ly < B; ++ly)
                for (size_t b = first; b < last; ++b)
                    for (uint32_t lx = 0; lx < B; ++lx)
                    {
                        const size_t slot = b * io::BlockGrid::kTexels + ly * B + lx, texel = slot - base;
                        if (best[texel] < 0)
                            continue;
                        const glm::uvec2 xy = grid.texel(slot);
                        band_texel[slot - own_begin] = int32_t(texels++);
                        packed.push_back(
                            {uint16_t(xy.x), uint16_t(xy.y),
                             uint32_t(best[texel]) |
                                 (best_distance[texel] == 0.0 ? LightmapTexels::kCentreInside : 0u),
                             best_bary[texel].x, best_bary[texel].y});
                    }
        }
        atlas.slot_texel.append(band_texel);
        finished_row.assign(best.begin() + ptrdiff_t(slot_of_row(r1 - 1) - base),
                            best.begin() + ptrdiff_t(own_end - base));
        r0 = r1;
    }
    std::vector<int32_t>().swap(band_texel);
    packed.finish();
    atlas.slot_texel.finish();
    atlas.texels = LightmapTexels(mesh, width, height, std::move(packed), chart_of);
    report.covered_texels = atlas.texels.size();
    atlas.grid = std::move(grid);

    // Texel density per range.
    std::vector<TriangleRange> groups = ranges;
    if (groups.empty())
        groups.push_back({0, uint32_t(triangles), "the mesh"});
    report.min_texel_size = std::numeric_limits<float>::infinity();
    report.max_texel_size = 0.0f;
    std::string min_name, max_name;
    for (const TriangleRange& r : groups)
    {
        double wa = 0.0, ua = 0.0;
        for (uint32_t t = r.first; t < r.first + r.count && t < triangles; ++t)
        {
            wa += world_area[t];
            ua += uv_area[t];
        }
        if (ua <= 0.0 || wa <= 0.0)
            continue;
        const float size = float(std::sqrt(wa / ua));
        if (size < report.min_texel_size)
        {
            report.min_texel_size = size;
            min_name = r.name;
        }
        if (size > report.max_texel_size)
        {
            report.max_texel_size = size;
            max_name = r.name;
        }
    }
    if (report.max_texel_size == 0.0f)
        report.min_texel_size = 0.0f;

    if (report.overlapping_texels)
        report.warnings.push_back(
            std::to_string(report.overlapping_texels) +
            " lightmap texel(s) lie inside two or more triangles (e.g. triangles " +
            std::to_string(report.overlap_example[0]) + " and " + std::to_string(report.overlap_example[1]) +
            "): overlapping lightmap UVs (TEXCOORD_1); each such texel takes the light of one of them (one "
            "a viewer can reach, not one inside geometry; then the one its chart continues in, else the one "
            "facing into the scene), the others get none of their own; "
            "--uv-report shows where, --strict-uv refuses, and re-unwrapping (or --unwrap) fixes it");
    if (report.outside)
        report.warnings.push_back(
            std::to_string(report.outside) + " triangle(s) have lightmap UVs outside [0, 1] (e.g. triangle " +
            std::to_string(example_outside) + " at " + uv_text(mesh.uvs1[mesh.indices[example_outside * 3]]) +
            "): only their part inside the atlas is baked");
    if (report.degenerate)
        report.warnings.push_back(std::to_string(report.degenerate) +
                                  " triangle(s) have no area in lightmap UV space (e.g. triangle " +
                                  std::to_string(example_degenerate) + "): no texel holds their light");
    if (report.max_texel_size > 4.0f * report.min_texel_size && report.min_texel_size > 0.0f)
    {
        char buf[256];
        std::snprintf(buf, sizeof buf,
                      "texel density varies %.1fx: a texel covers %.3g units on %s and %.3g on %s",
                      double(report.max_texel_size / report.min_texel_size), double(report.min_texel_size),
                      min_name.c_str(), double(report.max_texel_size), max_name.c_str());
        report.warnings.push_back(buf);
    }
    return atlas;
}

} // namespace hemi::bake
