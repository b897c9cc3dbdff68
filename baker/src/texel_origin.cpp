#include "texel_origin.h"

#include <hemi/bake/ray_generator.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>

namespace hemi::bake::detail
{

namespace
{

struct Triangle
{
    glm::dvec3 p[3];
    glm::vec3 g, u, v; // unit normal (counter-clockwise front) and two directions of its plane
};

// Two unit directions of the plane normal to unit `g`, (u, v, g) right-handed.
void plane_of(const glm::vec3& g, glm::vec3& u, glm::vec3& v)
{
    u = glm::normalize(std::abs(g.x) < 0.9f ? glm::cross(g, glm::vec3(1, 0, 0))
                                            : glm::cross(g, glm::vec3(0, 1, 0)));
    v = glm::cross(g, u);
}

Triangle triangle_of(const io::Mesh& mesh, uint32_t t)
{
    Triangle r;
    for (int k = 0; k < 3; ++k)
        r.p[k] = glm::dvec3(mesh.positions[mesh.indices[3 * size_t(t) + size_t(k)]]);
    const glm::dvec3 n = glm::cross(r.p[1] - r.p[0], r.p[2] - r.p[0]);
    r.g = glm::length(n) > 0.0 ? glm::vec3(glm::normalize(n)) : glm::vec3(0, 0, 1);
    plane_of(r.g, r.u, r.v);
    return r;
}

// A point of the triangle at barycentric `b`, kept at least `margin` inside it (in its plane) from each edge.
// Artist UVs can put a texel centre exactly on a triangle's edge or corner; where that edge is where a floor
// meets a wall, the ray origin lifted off the floor lies in the wall's plane and rays from it pass the
// wall's edge: light from outside a sealed room
// (LightmapBake.SealedRoomsLeakNothingWhereSamplesLieOnEdgesAndCorners). A point already that far inside is
// returned as it is. Each margin is at most 5% of its altitude: in a sliver too thin for the margin the point
// moves a little across the sliver, not along it (to the centroid, or towards its far vertex, which can lie
// many texels away from the texel); any margin above 0 keeps the origin out of a wall's plane.
glm::vec3 inside_triangle(const Triangle& tri, glm::dvec3 b, float margin)
{
    constexpr double kMostMargin = 0.05;
    const double area2 = glm::length(glm::cross(tri.p[1] - tri.p[0], tri.p[2] - tri.p[0]));
    glm::dvec3 least(0.0); // per vertex k, the barycentric weight at `margin` from the edge opposite k
    for (int k = 0; k < 3; ++k)
    {
        const double edge = glm::length(tri.p[(k + 2) % 3] - tri.p[(k + 1) % 3]);
        // margin / the altitude from vertex k
        least[k] = area2 > 0.0 ? std::min(double(margin) * edge / area2, kMostMargin) : 1.0 / 3.0;
    }
    if (!glm::all(glm::greaterThanEqual(b, least)))
    {
        const double room = 1.0 - (least.x + least.y + least.z);
        const glm::dvec3 excess = glm::max(b - least, glm::dvec3(0.0));
        const double sum = excess.x + excess.y + excess.z;
        if (sum <= 0.0)
            b = least + glm::dvec3(room / 3.0);
        else
            b = least + excess * (room / sum);
    }
    return glm::vec3(b.x * tri.p[0] + b.y * tri.p[1] + b.z * tri.p[2]);
}

// The texel's footprint: 8 points of its square around the centre, 0.4 texels out along each axis, the
// edges' middles first, then the corners.
constexpr std::array<std::pair<int, int>, 8> kFootprint = {
    {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, 1}, {1, -1}, {-1, -1}}};

} // namespace

TexelOrigins::TexelOrigins(const EmbreeScene& scene, const io::Mesh& mesh, uint32_t width, uint32_t height,
                           float offset, std::function<bool(uint32_t)> double_sided)
    : scene_(scene), mesh_(mesh), width_(width), height_(height), offset_(offset),
      double_sided_(std::move(double_sided))
{
}

bool TexelOrigins::back_face(uint32_t triangle, const glm::vec3& direction) const
{
    return glm::dot(scene_.geometric_normal(triangle), direction) > 0.0f &&
           !(double_sided_ && double_sided_(triangle));
}

bool TexelOrigins::inside(const glm::vec3& origin, uint32_t triangle, uint64_t item) const
{
    return inside_about(origin, triangle_of(mesh_, triangle).g, item);
}

bool TexelOrigins::inside_about(const glm::vec3& origin, const glm::vec3& g, uint64_t item) const
{
    glm::vec3 u, v;
    plane_of(g, u, v);
    std::array<glm::vec3, kInsideRays> directions;
    hemisphere_directions(0x696E7369ull, item, directions);
    // Traced 8 at a time until the count decides: after k rays of which b meet backs, it stops once b is
    // more than 2.5 standard deviations of a fair coin's count from k / 2 (|2b - k| > 2.5 sqrt(k)), from 16
    // rays on. Most texels are clearly outside or clearly inside and take 16; one near the threshold takes
    // all, so that the judge is not the coin toss that 32 rays would be there.
    constexpr size_t kPacket = 8;
    std::array<Ray, kPacket> rays;
    std::array<std::optional<RayHit>, kPacket> hits;
    int back = 0, traced = 0;
    for (size_t first = 0; first < directions.size(); first += kPacket)
    {
        for (size_t k = 0; k < kPacket; ++k)
        {
            const glm::vec3& h = directions[first + k];
            rays[k] = {origin, 0.0f, h.x * u + h.y * v + h.z * g, INFINITY};
        }
        scene_.intersect(std::span<const Ray>(rays), std::span(hits));
        for (size_t k = 0; k < kPacket; ++k)
            back += hits[k] && back_face(hits[k]->primitive, rays[k].direction);
        traced += int(kPacket);
        if (traced >= 16 && std::abs(2.0 * back - traced) > 2.5 * std::sqrt(double(traced)))
            break;
    }
    return 2 * back > traced;
}

bool TexelOrigins::seen(const glm::vec3& origin, uint32_t triangle, uint64_t item,
                        const std::function<bool(const RayHit&)>& may_be_outside) const
{
    const Triangle tri = triangle_of(mesh_, triangle);
    std::array<glm::vec3, kSeenRays> directions;
    hemisphere_directions(0x7365656Eull, item, directions);
    constexpr size_t kPacket = 8;
    std::array<Ray, kPacket> rays;
    std::array<std::optional<RayHit>, kPacket> hits;
    int count = 0;
    for (size_t first = 0; first < directions.size(); first += kPacket)
    {
        for (size_t k = 0; k < kPacket; ++k)
        {
            const glm::vec3& h = directions[first + k];
            rays[k] = {origin, 0.0f, h.x * tri.u + h.y * tri.v + h.z * tri.g, INFINITY};
        }
        scene_.intersect(std::span<const Ray>(rays), std::span(hits));
        for (size_t k = 0; k < kPacket; ++k)
        {
            const std::optional<RayHit>& hit = hits[k];
            if (!hit || back_face(hit->primitive, rays[k].direction) ||
                (may_be_outside && !may_be_outside(*hit)))
                continue;
            // The point met, off its surface on the side the ray came from.
            glm::vec3 g = glm::normalize(scene_.geometric_normal(hit->primitive));
            if (glm::dot(g, rays[k].direction) > 0.0f)
                g = -g; // a double-sided surface's back
            const glm::vec3 p = offset_ray_origin(origin + rays[k].direction * hit->distance, g, offset_);
            count += !inside_about(p, g, item ^ (uint64_t(first + k + 1) << 40));
        }
        if (count >= kSeenHits)
            return true;
    }
    return false;
}

TexelOrigins::Origin TexelOrigins::find(uint32_t triangle, uint32_t x, uint32_t y,
                                        const glm::vec3& barycentric, const glm::vec3* tangent) const
{
    Triangle tri = triangle_of(mesh_, triangle);
    if (tangent)
    {
        const glm::vec3 u = *tangent - tri.g * glm::dot(tri.g, *tangent);
        if (glm::length(u) >= 1e-6f)
        {
            tri.u = glm::normalize(u);
            tri.v = glm::cross(tri.g, tri.u);
        }
    }
    const uint32_t* corner = &mesh_.indices[3 * size_t(triangle)];
    const bool has_uvs = mesh_.uvs1.size() == mesh_.positions.size();
    glm::dvec2 uv[3] = {};
    double area2 = 0.0;
    if (has_uvs)
    {
        for (int k = 0; k < 3; ++k)
            uv[k] = glm::dvec2(mesh_.uvs1[corner[k]]) * glm::dvec2(width_, height_);
        area2 = (uv[1] - uv[0]).x * (uv[2] - uv[0]).y - (uv[1] - uv[0]).y * (uv[2] - uv[0]).x;
    }
    // Half the footprint's diagonal: sqrt(2) / 2 times its side, sqrt(world area / texel area).
    const double world_area2 = glm::length(glm::cross(tri.p[1] - tri.p[0], tri.p[2] - tri.p[0]));
    const float reach =
        std::abs(area2) > 0.0 ? float(0.5 * M_SQRT2 * std::sqrt(world_area2 / std::abs(area2))) : 0.0f;
    const float margin = 2.0f * offset_;
    auto moved_out = [&](glm::vec3 p, bool& moved)
    {
        const glm::vec3 from = offset_ray_origin(p, tri.g, offset_);
        float nearest = INFINITY;
        glm::vec3 along(0.0f);
        for (int k = 0; k < 8 && reach > 0.0f; ++k)
        {
            const float a = float(k) * float(M_PI) / 4.0f;
            const glm::vec3 d = std::cos(a) * tri.u + std::sin(a) * tri.v;
            const std::optional<RayHit> hit = scene_.intersect(from, d, 0.0f, reach);
            if (hit && hit->distance < nearest && back_face(hit->primitive, d))
            {
                nearest = hit->distance;
                along = d;
            }
        }
        moved = std::isfinite(nearest);
        if (moved)
            p = p + along * (nearest + 4.0f * offset_);
        return offset_ray_origin(p, tri.g, offset_);
    };
    const uint64_t item = uint64_t(y) * width_ + x;
    const glm::vec3 centre = inside_triangle(tri, glm::dvec3(barycentric), margin);
    Origin out;
    out.origin = moved_out(centre, out.moved);
    if (!inside(out.origin, triangle, item))
        return out;
    const Origin first = out;
    if (first.moved && !inside(out.origin = offset_ray_origin(centre, tri.g, offset_), triangle, item))
    {
        out.moved = false; // the push went through the back of a thin surface into what lies behind it
        return out;
    }
    // A point of the footprint whose origin, moved out of walls or else not, lies outside geometry.
    out.moved = true;
    auto take = [&](const glm::vec3& point)
    {
        bool moved = false;
        out.origin = moved_out(point, moved);
        return !inside(out.origin, triangle, item) ||
               (moved && !inside(out.origin = offset_ray_origin(point, tri.g, offset_), triangle, item));
    };
    if (std::abs(area2) >= 1e-12)
        for (const bool beyond : {false, true})
            for (const auto& [fx, fy] : kFootprint)
            {
                const glm::dvec2 q = glm::dvec2(x + 0.5 + 0.4 * fx, y + 0.5 + 0.4 * fy);
                auto edge = [&](int a, int b)
                {
                    const glm::dvec2 e = uv[b] - uv[a], w = q - uv[a];
                    return (e.x * w.y - e.y * w.x) / area2;
                };
                glm::dvec3 b(edge(1, 2), edge(2, 0), edge(0, 1));
                const bool on = b.x >= 0.0 && b.y >= 0.0 && b.z >= 0.0;
                if (beyond && on)
                    continue;
                glm::vec3 point;
                if (beyond)
                    point = glm::vec3(b.x * tri.p[0] + b.y * tri.p[1] + b.z * tri.p[2]);
                else
                {
                    b = glm::max(b, glm::dvec3(0.0));
                    point = inside_triangle(tri, b / (b.x + b.y + b.z), margin);
                }
                if (take(point))
                    return out;
            }
    out = first;
    out.inside = true;
    return out;
}

} // namespace hemi::bake::detail
