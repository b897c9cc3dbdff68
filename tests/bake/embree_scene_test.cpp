// The bakes' Embree scene: hits on a known quad (triangle, barycentrics, distance, front and back),
// occlusion within a range, degenerate triangles never hit, bad meshes refused, and concurrent queries giving
// what serial ones give.
#include "models.h"

#include <hemi/bake/embree_scene.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/io/mesh.h>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <utility>
#include <vector>

namespace
{

using hemi::bake::EmbreeScene;
using hemi::bake::RayHit;

// The unit square in z = 0, facing +z (counter-clockwise seen from above), as two triangles.
hemi::io::Mesh quad()
{
    hemi::io::Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

glm::vec3 hit_point(const hemi::io::Mesh& m, const RayHit& h)
{
    const uint32_t* t = &m.indices[size_t(h.primitive) * 3];
    return (1.0f - h.u - h.v) * m.positions[t[0]] + h.u * m.positions[t[1]] + h.v * m.positions[t[2]];
}

} // namespace

TEST(EmbreeScene, HitsCarryTriangleBarycentricsDistanceAndNormal)
{
    const hemi::io::Mesh m = quad();
    const EmbreeScene scene(m);
    EXPECT_EQ(scene.triangle_count(), 2u);
    EXPECT_FLOAT_EQ(scene.diagonal(), std::sqrt(2.0f));
    EXPECT_FLOAT_EQ(scene.ray_offset(1e-3f), 1e-3f * std::sqrt(2.0f));

    // From above (the front) and from below (the back): no culling.
    for (const auto& [point, expected] :
         {std::pair{glm::vec3(0.7f, 0.2f, 0.0f), 0u}, std::pair{glm::vec3(0.2f, 0.7f, 0.0f), 1u}})
        for (float side : {1.0f, -1.0f})
        {
            const glm::vec3 origin = point + glm::vec3(0, 0, 2.0f * side), dir(0, 0, -side);
            const std::optional<RayHit> hit = scene.intersect(origin, dir);
            ASSERT_TRUE(hit.has_value());
            EXPECT_EQ(hit->primitive, expected);
            EXPECT_NEAR(hit->distance, 2.0f, 1e-6f);
            const glm::vec3 p = hit_point(m, *hit);
            EXPECT_NEAR(glm::length(p - point), 0.0f, 1e-6f);
            // The front is +z: a ray from above meets it head on (negative dot), one from below does not.
            const glm::vec3 n = scene.geometric_normal(hit->primitive);
            EXPECT_EQ(n, glm::vec3(0, 0, 1)); // cross of the unit edges: twice the area of 1/2, exactly
            EXPECT_EQ(glm::dot(n, dir) < 0.0f, side > 0.0f);
            EXPECT_TRUE(scene.occluded(origin, dir));
        }

    // The range: a surface beyond t_far, or before t_near, is not there.
    const glm::vec3 origin(0.5f, 0.25f, 1.0f), down(0, 0, -1);
    EXPECT_FALSE(scene.intersect(origin, down, 0.0f, 0.5f).has_value());
    EXPECT_FALSE(scene.occluded(origin, down, 0.0f, 0.5f));
    EXPECT_FALSE(scene.intersect(origin, down, 1.5f).has_value());
    EXPECT_FALSE(scene.occluded(origin, down, 1.5f));
    EXPECT_TRUE(scene.occluded(origin, down, 0.5f, 1.5f));
    // Distances are in multiples of the direction's length.
    EXPECT_NEAR(scene.intersect(origin, 2.0f * down)->distance, 0.5f, 1e-6f);
    // Away from the quad, or beside it: nothing.
    EXPECT_FALSE(scene.intersect(origin, -down).has_value());
    EXPECT_FALSE(scene.occluded(glm::vec3(1.5f, 0.5f, 1.0f), down));

    // A moved scene keeps its Embree scene.
    EmbreeScene moved(quad());
    EmbreeScene other = std::move(moved);
    EXPECT_TRUE(other.occluded(origin, down));
}

TEST(EmbreeScene, DegenerateTrianglesAreNeverHit)
{
    hemi::io::Mesh m;
    // A triangle with a repeated vertex and one with three collinear vertices, both across the rays' path.
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {-1, -1, 0}, {0, 0, 0}, {1, 1, 0}};
    m.indices = {0, 1, 2, 3, 4, 5};
    const EmbreeScene scene(m);
    EXPECT_EQ(scene.geometric_normal(0), glm::vec3(0.0f));
    EXPECT_EQ(scene.geometric_normal(1), glm::vec3(0.0f));
    int hits = 0;
    for (int i = 0; i < 4096; ++i)
    {
        // Rays through points on and around both segments, from every side.
        const glm::vec3 target =
            i % 2 ? glm::vec3(float(i % 64) / 64.0f, 0, 0)
                  : glm::vec3(float(i % 64) / 32.0f - 1.0f, float(i % 64) / 32.0f - 1.0f, 0);
        const glm::vec3 d = hemi::bake::sphere_direction(1, uint64_t(i), i % 16, 16);
        hits += scene.intersect(target - d, d).has_value() + scene.occluded(target - d, d);
    }
    EXPECT_EQ(hits, 0);
}

TEST(EmbreeScene, RefusesMeshesItCannotTrace)
{
    hemi::io::Mesh m = quad();
    m.indices.push_back(0);
    EXPECT_THROW(EmbreeScene{m}, std::invalid_argument);
    m = quad();
    m.indices[4] = 4;
    EXPECT_THROW(EmbreeScene{m}, std::invalid_argument);
    m = quad();
    m.positions[2].z = NAN;
    EXPECT_THROW(EmbreeScene{m}, std::invalid_argument);
    m = quad();
    m.positions[1].x = INFINITY;
    EXPECT_THROW(EmbreeScene{m}, std::invalid_argument);
    EXPECT_THROW(EmbreeScene{hemi::io::Mesh{}}, std::invalid_argument);
    m = quad();
    m.indices.clear();
    EXPECT_THROW(EmbreeScene{m}, std::invalid_argument);
}

// After construction the scene is read-only: rays traced on many threads at once get exactly what the same
// rays traced one by one get, and occluded() agrees with intersect().
TEST(EmbreeScene, ConcurrentQueriesMatchSerialOnes)
{
    const hemi::io::Mesh knot = hemi::samples::make_prt_model(hemi::samples::PrtModel::Complex, 0.3f);
    const EmbreeScene scene(knot);
    const float offset = scene.ray_offset(1e-4f);
    const uint32_t n = uint32_t(knot.vertex_count());
    constexpr int kRays = 16;
    struct Result
    {
        uint32_t primitive = ~0u;
        float u = 0, v = 0, distance = -1;
        bool occluded = false;
        bool operator==(const Result&) const = default;
    };
    const auto trace = [&](uint32_t v, int r)
    {
        const glm::vec3 origin =
            hemi::bake::offset_ray_origin(knot.positions[v], glm::normalize(knot.normals[v]), offset);
        const glm::vec3 d = hemi::bake::sphere_direction(3, v, r, kRays);
        Result out;
        if (const std::optional<RayHit> hit = scene.intersect(origin, d))
            out = {hit->primitive, hit->u, hit->v, hit->distance, false};
        out.occluded = scene.occluded(origin, d);
        return out;
    };
    std::vector<Result> parallel(size_t(n) * kRays), serial(parallel.size());
    tbb::parallel_for(uint32_t(0), n,
                      [&](uint32_t v)
                      {
                          for (int r = 0; r < kRays; ++r)
                              parallel[size_t(v) * kRays + r] = trace(v, r);
                      });
    size_t hits = 0;
    for (uint32_t v = 0; v < n; ++v)
        for (int r = 0; r < kRays; ++r)
        {
            const Result& s = serial[size_t(v) * kRays + r] = trace(v, r);
            ASSERT_TRUE(s == parallel[size_t(v) * kRays + r]) << "vertex " << v << " ray " << r;
            ASSERT_EQ(s.occluded, s.distance >= 0.0f) << "vertex " << v << " ray " << r;
            hits += s.occluded;
        }
    // The knot shadows itself: a good share of rays hit, and not all.
    EXPECT_GT(hits, parallel.size() / 10);
    EXPECT_LT(hits, parallel.size());
}

// The packet queries (16 rays at a time) answer as the single-ray ones do: the same triangle hit or missed
// and the same occlusion for every ray of the knot's vertices, hit points within float rounding, for batch
// sizes that fill packets and that leave lanes off; the wrong output size is refused. Fails for a lane
// answer put in another lane's place, for a batch's last, partial packet dropped, or for a packet's tfar read
// as a hit.
TEST(EmbreeScene, PacketQueriesAnswerAsSingleRaysDo)
{
    const hemi::io::Mesh knot = hemi::samples::make_prt_model(hemi::samples::PrtModel::Complex, 0.3f);
    const EmbreeScene scene(knot);
    const float offset = scene.ray_offset(1e-4f);
    size_t hits = 0, total = 0, primitive_differs = 0;
    for (const int batch : {16, 37, 5})
        for (uint32_t v = 0; v < knot.vertex_count(); v += 7)
        {
            const glm::vec3 origin =
                hemi::bake::offset_ray_origin(knot.positions[v], glm::normalize(knot.normals[v]), offset);
            std::vector<glm::vec3> directions(static_cast<size_t>(batch));
            hemi::bake::sphere_directions(5, v, directions);
            std::vector<hemi::bake::Ray> rays;
            for (const glm::vec3& d : directions)
                rays.push_back({origin, 0.0f, d, v % 2 ? INFINITY : 0.5f});
            std::vector<std::optional<RayHit>> found(rays.size());
            std::vector<uint8_t> blocked(rays.size(), 7);
            scene.intersect(rays, found);
            scene.occluded(rays, blocked);
            for (size_t r = 0; r < rays.size(); ++r)
            {
                const std::optional<RayHit> one =
                    scene.intersect(origin, rays[r].direction, 0.0f, rays[r].t_far);
                ASSERT_EQ(found[r].has_value(), one.has_value()) << v << " " << r;
                ASSERT_EQ(blocked[r],
                          uint8_t(scene.occluded(origin, rays[r].direction, 0.0f, rays[r].t_far)));
                ++total;
                if (!one)
                    continue;
                ++hits;
                // Two triangles may meet the ray at one point (an edge): either is right.
                primitive_differs += found[r]->primitive != one->primitive;
                ASSERT_LT(glm::distance(hit_point(knot, *found[r]), hit_point(knot, *one)),
                          1e-5f * scene.diagonal());
                ASSERT_NEAR(found[r]->distance, one->distance, 1e-5f * scene.diagonal());
            }
        }
    EXPECT_GT(hits, total / 10);
    EXPECT_LT(hits, total);
    EXPECT_LT(primitive_differs, total / 1000 + 1);
    std::vector<hemi::bake::Ray> rays(3);
    std::vector<std::optional<RayHit>> two(2);
    std::vector<uint8_t> four(4);
    EXPECT_THROW(scene.intersect(rays, two), std::invalid_argument);
    EXPECT_THROW(scene.occluded(rays, four), std::invalid_argument);
    scene.intersect(std::span<const hemi::bake::Ray>(), std::span<std::optional<RayHit>>()); // nothing to do
}
