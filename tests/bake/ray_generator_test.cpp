// The bakes' ray directions: the same bytes for a seed whatever the thread count and order, unit and uniform
// (the sphere set's mean is near zero, one ray per z stratum), estimates with the documented weights, and the
// directions the PRT bake has always drawn (its assets are made of them).
#include <hemi/bake/ray_generator.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

namespace
{

using hemi::bake::hemisphere_direction;
using hemi::bake::sphere_direction;

constexpr uint32_t kItems = 2000;
constexpr int kRays = 64;

// Both sets of every item, drawn by parallel_for on whatever threads TBB gives it.
std::vector<glm::vec3> draw_all(uint64_t seed)
{
    std::vector<glm::vec3> out(size_t(kItems) * kRays * 2);
    tbb::parallel_for(uint32_t(0), kItems,
                      [&](uint32_t item)
                      {
                          for (int r = 0; r < kRays; ++r)
                          {
                              out[(size_t(item) * kRays + r) * 2] = sphere_direction(seed, item, r, kRays);
                              out[(size_t(item) * kRays + r) * 2 + 1] =
                                  hemisphere_direction(seed, item, r, kRays);
                          }
                      });
    return out;
}

bool same_bytes(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0;
}

} // namespace

TEST(RayGenerator, SameSeedSameBytesWhateverTheThreadCountAndOrder)
{
    const std::vector<glm::vec3> parallel = draw_all(5);
    std::vector<glm::vec3> serial;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial = draw_all(5);
    }
    std::vector<glm::vec3> eight;
    tbb::task_arena(8).execute([&] { eight = draw_all(5); });
    EXPECT_TRUE(same_bytes(parallel, serial));
    EXPECT_TRUE(same_bytes(parallel, eight));
    // Backwards, one ray at a time: no hidden state advances between calls.
    std::vector<glm::vec3> backwards(parallel.size());
    for (size_t i = backwards.size() / 2; i-- > 0;)
    {
        const uint32_t item = uint32_t(i / kRays);
        const int r = int(i % kRays);
        backwards[i * 2] = sphere_direction(5, item, r, kRays);
        backwards[i * 2 + 1] = hemisphere_direction(5, item, r, kRays);
    }
    EXPECT_TRUE(same_bytes(parallel, backwards));
    EXPECT_FALSE(same_bytes(parallel, draw_all(6))) << "another seed must give other rays";
    // Each item's set is turned by its own angle: neighbours do not share directions.
    EXPECT_NE(sphere_direction(5, 0, 3, kRays), sphere_direction(5, 1, 3, kRays));
}

TEST(RayGenerator, DirectionsAreUnitAndHemispheresPointUp)
{
    for (int rays : {1, 2, 7, 64, 1000})
        for (uint64_t item = 0; item < 50; ++item)
            for (int r = 0; r < rays; ++r)
            {
                const glm::vec3 s = sphere_direction(3, item, r, rays),
                                h = hemisphere_direction(3, item, r, rays);
                ASSERT_NEAR(glm::length(s), 1.0f, 1e-6f) << rays << " " << item << " " << r;
                ASSERT_NEAR(glm::length(h), 1.0f, 1e-6f) << rays << " " << item << " " << r;
                ASSERT_GE(h.z, 0.0f) << rays << " " << item << " " << r;
            }
}

// Ray i lies in the i-th z stratum (of height 2/R on the sphere, 1/R on the hemisphere), top down: what makes
// the set stratified rather than R independent directions.
TEST(RayGenerator, OneRayPerStratumOfZ)
{
    const int rays = 256;
    for (uint64_t item = 0; item < 20; ++item)
        for (int r = 0; r < rays; ++r)
        {
            const float s = sphere_direction(11, item, r, rays).z,
                        h = hemisphere_direction(11, item, r, rays).z;
            ASSERT_LE(s, 1.0f - 2.0f * float(r) / rays + 1e-6f);
            ASSERT_GE(s, 1.0f - 2.0f * float(r + 1) / rays - 1e-6f);
            ASSERT_LE(h, 1.0f - float(r) / rays + 1e-6f);
            ASSERT_GE(h, 1.0f - float(r + 1) / rays - 1e-6f);
        }
}

// The sphere set is balanced: its mean direction is near zero for every item (stratification keeps it far
// below the 1 / sqrt(R) = 0.06 typical of R independent directions), and nearer still over many items. The
// hemisphere's mean is (0, 0, 1/2).
TEST(RayGenerator, MeanOfTheSphereSetIsNearZero)
{
    const int rays = 256;
    glm::dvec3 all(0.0), all_h(0.0);
    const uint32_t items = 500;
    for (uint32_t item = 0; item < items; ++item)
    {
        glm::dvec3 mean(0.0), mean_h(0.0);
        for (int r = 0; r < rays; ++r)
        {
            mean += glm::dvec3(sphere_direction(1, item, r, rays)) / double(rays);
            mean_h += glm::dvec3(hemisphere_direction(1, item, r, rays)) / double(rays);
        }
        ASSERT_LT(glm::length(mean), 0.01) << "item " << item;
        ASSERT_LT(glm::length(mean_h - glm::dvec3(0.0, 0.0, 0.5)), 0.01) << "item " << item;
        all += mean / double(items);
        all_h += mean_h / double(items);
    }
    EXPECT_LT(glm::length(all), 1e-3);
    EXPECT_LT(glm::length(all_h - glm::dvec3(0.0, 0.0, 0.5)), 1e-3);
}

// The documented weights: 4 pi / R per sphere ray, 2 pi / R per hemisphere ray.
TEST(RayGenerator, EstimatesWithTheDocumentedWeights)
{
    const int rays = 256;
    for (uint64_t item = 0; item < 10; ++item)
    {
        double sphere = 0.0, cosine = 0.0;
        for (int r = 0; r < rays; ++r)
        {
            const glm::vec3 d = sphere_direction(2, item, r, rays),
                            h = hemisphere_direction(2, item, r, rays);
            sphere += (1.0 + d.x + 3.0 * d.z * d.z) * 4.0 * M_PI / rays; // 4 pi + 0 + 4 pi
            cosine += h.z * 2.0 * M_PI / rays;                           // the clamped cosine: pi
        }
        EXPECT_NEAR(sphere, 8.0 * M_PI, 0.02 * 8.0 * M_PI) << item;
        EXPECT_NEAR(cosine, M_PI, 0.01 * M_PI) << item;
    }
}

// The directions the bakes draw: the bakes' assets and checkpoints are made of them, so a change here is a
// change of every asset (and needs the checkpoint keys bumped: the lightmap's 8 and the PRT bake's 3 came
// with the angle's cosine and sine from a table of the rays' turns, exact in double where the float sum
// r g + offset had lost up to 1.5e-5 at ray 100). A tolerance rather than bits: the values go through the
// platform's sin and cos.
TEST(RayGenerator, DrawsThePrtBakesDirections)
{
    struct Ray
    {
        uint64_t seed, item;
        int ray, rays;
    };
    struct Pinned
    {
        Ray ray;
        glm::vec3 sphere, hemisphere;
    };
    // From the formula evaluated independently in double (Python: SplitMix64's mix, z = 1 - (r + u) / R or
    // 1 - 2 (r + u) / R, phi = 2 pi (frac(r g) + offset) with g the golden ratio's conjugate).
    const Pinned pinned[] = {
        {{1, 0, 0, 256},
         {-0.020806057f, -0.056138706f, 0.998206168f},
         {-0.014715406f, -0.039704967f, 0.999103084f}},
        {{1, 12345, 100, 256},
         {0.770928481f, 0.598617393f, 0.217546534f},
         {0.626619244f, 0.486562875f, 0.608773267f}},
        {{7, 3, 63, 64},
         {-0.112314919f, -0.033342592f, -0.993113101f},
         {-0.958643277f, -0.284589548f, 0.003443450f}},
        {{1, 1, 0, 1},
         {-0.529688259f, 0.816045408f, -0.231301188f},
         {-0.502631964f, 0.774362088f, 0.384349406f}},
    };
    for (const Pinned& p : pinned)
    {
        const Ray& r = p.ray;
        const glm::vec3 s = sphere_direction(r.seed, r.item, r.ray, r.rays);
        const glm::vec3 h = hemisphere_direction(r.seed, r.item, r.ray, r.rays);
        for (int c = 0; c < 3; ++c)
        {
            EXPECT_NEAR(s[c], p.sphere[c], 1e-6f) << r.seed << " " << r.item << " " << r.ray;
            EXPECT_NEAR(h[c], p.hemisphere[c], 1e-6f) << r.seed << " " << r.item << " " << r.ray;
        }
    }
    // The hash itself is integer arithmetic: exact.
    EXPECT_EQ(hemi::bake::mix64(0), 0xe220a8397b1dcdafull);
    EXPECT_EQ(hemi::bake::uniform01(1, 2, 3), 0.592672408f);
}

// The bakes draw a texel's or a vertex's whole set at once: bit for bit the directions drawn one by one, for
// set sizes that are and are not multiples of anything. Fails if the batch hashed the item differently, or
// used another stratum width.
TEST(RayGenerator, WholeSetsAreTheRaysDrawnOneByOne)
{
    for (const int rays : {1, 7, 64, 257})
        for (const uint64_t item : {uint64_t(0), uint64_t(12345), uint64_t(1) << 40})
        {
            std::vector<glm::vec3> sphere(static_cast<size_t>(rays)), hemisphere(static_cast<size_t>(rays));
            hemi::bake::sphere_directions(9, item, sphere);
            hemi::bake::hemisphere_directions(9, item, hemisphere);
            for (int r = 0; r < rays; ++r)
            {
                const glm::vec3 s = sphere_direction(9, item, r, rays),
                                h = hemisphere_direction(9, item, r, rays);
                ASSERT_EQ(std::memcmp(&sphere[size_t(r)], &s, sizeof s), 0)
                    << rays << " " << item << " " << r;
                ASSERT_EQ(std::memcmp(&hemisphere[size_t(r)], &h, sizeof h), 0)
                    << rays << " " << item << " " << r;
            }
        }
}

TEST(RayGenerator, UniformNumbersLieInZeroOne)
{
    double sum = 0.0;
    const int n = 100000;
    for (int i = 0; i < n; ++i)
    {
        const float u = hemi::bake::uniform01(4, uint64_t(i) / 100, uint64_t(i) % 100);
        ASSERT_GE(u, 0.0f);
        ASSERT_LT(u, 1.0f);
        sum += u;
    }
    EXPECT_NEAR(sum / n, 0.5, 0.005);
}

// The noise estimate's neighbour tables (SampleNeighbours), against brute force over every pair, computed
// here from the patterns as ray_generator.h and LightSampler define them:
//  - the hemisphere set's: each ray's k = 6 neighbours are the 6 nearest middles of strata (z = 1 - (r + 0.5)
//    / R, phi = 2 pi frac(r (sqrt 5 - 1) / 2)), by their distances within 1e-6 (ties may be listed either
//    way), for sizes up to 4096 (the table's search stops early; one that stopped too early fails);
//  - the environment's lattice (r / N, frac(r (sqrt 5 - 1) / 2)) on the unit torus: each sample's 6 listed
//    are distinct, not itself, and no farther than any sample not listed (also across the ends of the
//    index range, where r + d wraps to r + d - N and no longer lies d golden steps on);
//  - at most k + 1 samples: every other is a neighbour (independent).
TEST(RayGenerator, NeighbourTablesListTheNearestSamples)
{
    const int k = 6;
    for (const int rays : {8, 13, 32, 33, 100, 1000, 4096})
    {
        const hemi::bake::SampleNeighbours n = hemi::bake::hemisphere_neighbours(rays, k);
        ASSERT_EQ(n.count, rays);
        ASSERT_EQ(n.k, k);
        ASSERT_FALSE(n.independent);
        ASSERT_EQ(n.index.size(), size_t(rays) * k);
        std::vector<glm::dvec3> middle(static_cast<size_t>(rays));
        for (int r = 0; r < rays; ++r)
        {
            const double z = 1.0 - (r + 0.5) / rays,
                         phi = 2.0 * M_PI * std::fmod(r * 0.6180339887498949, 1.0),
                         s = std::sqrt(1.0 - z * z);
            middle[size_t(r)] = {s * std::cos(phi), s * std::sin(phi), z};
        }
        for (int r = 0; r < rays; ++r)
        {
            std::vector<double> all;
            for (int q = 0; q < rays; ++q)
                if (q != r)
                    all.push_back(glm::distance(middle[size_t(q)], middle[size_t(r)]));
            std::sort(all.begin(), all.end());
            std::vector<double> listed;
            for (int q = 0; q < k; ++q)
            {
                const uint32_t j = n.index[size_t(r) * k + size_t(q)];
                ASSERT_LT(j, uint32_t(rays));
                ASSERT_NE(j, uint32_t(r));
                listed.push_back(glm::distance(middle[j], middle[size_t(r)]));
            }
            std::sort(listed.begin(), listed.end());
            for (int q = 0; q < k; ++q)
                ASSERT_NEAR(listed[size_t(q)], all[size_t(q)], 1e-6) << rays << " rays, ray " << r;
        }
    }
    // Squared distance on the unit torus between samples a and b of the lattice.
    const auto torus = [](int count, int a, int b)
    {
        const auto frac = [](double v) { return v - std::floor(v); };
        double x = std::abs(double(a - b)) / count,
               y = std::abs(frac(a * 0.6180339887498949) - frac(b * 0.6180339887498949));
        x = std::min(x, 1.0 - x);
        y = std::min(y, 1.0 - y);
        return x * x + y * y;
    };
    for (const int count : {8, 9, 32, 33, 256})
    {
        const hemi::bake::SampleNeighbours n = hemi::bake::lattice_neighbours(count, k);
        ASSERT_FALSE(n.independent);
        ASSERT_EQ(n.index.size(), size_t(count) * k);
        for (int r = 0; r < count; ++r)
        {
            std::vector<bool> listed(static_cast<size_t>(count));
            double farthest = 0.0;
            for (int q = 0; q < k; ++q)
            {
                const uint32_t j = n.index[size_t(r) * k + size_t(q)];
                ASSERT_NE(j, uint32_t(r));
                ASSERT_FALSE(listed[j]) << count << " samples, sample " << r << " lists " << j << " twice";
                listed[j] = true;
                farthest = std::max(farthest, torus(count, r, int(j)));
            }
            for (int q = 0; q < count; ++q)
            {
                if (q == r || listed[size_t(q)])
                    continue;
                ASSERT_GE(torus(count, r, q), farthest - 1e-12) << count << " samples, sample " << r;
            }
        }
    }
    for (const int few : {1, 2, 7})
    {
        EXPECT_TRUE(hemi::bake::hemisphere_neighbours(few, k).independent) << few;
        EXPECT_TRUE(hemi::bake::lattice_neighbours(few, k).independent) << few;
    }
}
