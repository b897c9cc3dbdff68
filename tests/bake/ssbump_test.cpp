// The SSBump bake (Green 2007) against references that do not call it: Valve's basis typed from Source's
// shader, the analytic visibility of a V-groove, a brute-force Moller-Trumbore caster over the relief's
// triangles, and a direct evaluation of the bilateral filter.
#include "../png_writer.h"
#include "../temp_dir.h"

#include <hemi/bake/checkpoint.h>
#include <hemi/bake/ssbump.h>
#include <hemi/io/image.h>
#include <hemi/io/memory.h>

#include <ImfRgbaFile.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

namespace fs = std::filesystem;
using namespace hemi::bake;

namespace
{

// Source's bumpBasis (Valve's order), typed from its shader rather than taken from math::rnm_basis().
const double kBasis[3][3] = {{0.81649658092772603, 0.0, 0.57735026918962576},
                             {-0.40824829046386302, 0.70710678118654752, 0.57735026918962576},
                             {-0.40824829046386302, -0.70710678118654752, 0.57735026918962576}};

double lobe(int i, const glm::dvec3& w)
{
    return std::max(0.0, kBasis[i][0] * w.x + kBasis[i][1] * w.y + kBasis[i][2] * w.z);
}

HeightField constant(uint32_t w, uint32_t h, float v)
{
    return {w, h, std::vector<float>(size_t(w) * h, v)};
}

// A rough, deep relief: smoothed random heights.
HeightField rough(uint32_t w, uint32_t h, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    HeightField f = constant(w, h, 0.0f);
    for (float& v : f.heights)
        v = u(rng);
    HeightField g = f;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            g.heights[y * w + x] =
                0.5f * f.at(x, y) + 0.25f * f.at((x + 1) % w, y) + 0.25f * f.at(x, (y + 1) % h);
    return g;
}

fs::path dir()
{
    return hemi::test::temp_dir("ssbump_test");
}

void write_bytes(const fs::path& p, const std::vector<uint8_t>& bytes)
{
    std::ofstream f(p, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// The brute-force reference: every ray of a texel against every triangle of the relief within reach
// (Moller-Trumbore in double, grid coordinates: x along a row, y down the rows, z up), the relief built here
// from the definition, periodic when wrapping.
struct BruteForce
{
    const HeightField& f;
    double scale, epsilon, distance;
    bool wrap;

    double z(int64_t x, int64_t y) const
    {
        const int64_t w = f.width, h = f.height;
        return scale * f.at(uint32_t(((x % w) + w) % w), uint32_t(((y % h) + h) % h));
    }
    static bool hit(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b,
                    const glm::dvec3& c, double& t)
    {
        const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
        const double det = glm::dot(e1, p);
        if (std::abs(det) < 1e-14)
            return false;
        const glm::dvec3 s = o - a;
        const double u = glm::dot(s, p) / det;
        if (u < 0.0 || u > 1.0)
            return false;
        const glm::dvec3 q = glm::cross(s, e1);
        const double v = glm::dot(d, q) / det;
        if (v < 0.0 || u + v > 1.0)
            return false;
        t = glm::dot(e2, q) / det;
        return t > 1e-9;
    }
    // O_i at texel (x, y) with the bake's ray set.
    glm::dvec3 occlusion(uint32_t x, uint32_t y, uint64_t seed, int rays) const
    {
        const glm::dvec3 origin(x, y, z(x, y) + epsilon);
        const int64_t reach = int64_t(std::ceil(distance)) + 1;
        std::vector<glm::dvec3> tris;
        for (int64_t j = int64_t(y) - reach; j <= int64_t(y) + reach; ++j)
            for (int64_t i = int64_t(x) - reach; i <= int64_t(x) + reach; ++i)
            {
                if (!wrap && (i < 0 || j < 0 || i + 1 >= int64_t(f.width) || j + 1 >= int64_t(f.height)))
                    continue;
                const glm::dvec3 p00(i, j, z(i, j)), p10(i + 1, j, z(i + 1, j)), p01(i, j + 1, z(i, j + 1)),
                    p11(i + 1, j + 1, z(i + 1, j + 1));
                tris.insert(tris.end(), {p00, p10, p11, p00, p01, p11});
            }
        double seen[3] = {0, 0, 0}, all[3] = {0, 0, 0};
        for (int r = 0; r < rays; ++r)
        {
            const SsbumpRay ray = ssbump_ray(seed, uint64_t(y) * f.width + x, r, rays);
            const glm::dvec3 w(ray.direction);
            const glm::dvec3 d(w.x, -w.y, w.z); // tangent +y is up the image
            const double rho = std::sqrt(w.x * w.x + w.y * w.y);
            bool blocked = false;
            for (size_t k = 0; k < tris.size() && !blocked; k += 3)
            {
                double t = 0.0;
                if (hit(origin, d, tris[k], tris[k + 1], tris[k + 2], t) && t * rho <= distance)
                    blocked = true;
            }
            for (int i = 0; i < 3; ++i)
            {
                all[i] += ray.weight * lobe(i, w);
                if (!blocked)
                    seen[i] += ray.weight * lobe(i, w);
            }
        }
        return {seen[0] / all[0], seen[1] / all[1], seen[2] / all[2]};
    }
};

} // namespace

// Done-when line 1: a flat map bakes (1/3, 1/3, 1/3) with no occlusion in every texel in the normalised
// convention and 1/sqrt(3) in Valve's, at any height, tiling or not.
TEST(Ssbump, FlatMapBakesOneThirdOrValveWeightsWithNoOcclusion)
{
    for (float level : {0.0f, 0.5f, 1.0f})
        for (bool wrap : {true, false})
            for (SsbumpConvention c : {SsbumpConvention::Normalized, SsbumpConvention::Valve})
            {
                SsbumpOptions o;
                o.wrap = wrap;
                o.convention = c;
                const SsbumpMap m = bake_ssbump(constant(13, 9, level), o);
                const float expected = c == SsbumpConvention::Valve ? 0.57735026919f : 1.0f / 3.0f;
                for (size_t t = 0; t < m.weights.size(); ++t)
                    for (int i = 0; i < 3; ++i)
                    {
                        ASSERT_EQ(m.occlusion[t][i], 1.0f) << "texel " << t << " lobe " << i;
                        ASSERT_NEAR(m.weights[t][i], expected, 1e-6f) << "texel " << t << " lobe " << i;
                    }
                EXPECT_EQ(m.rays, uint64_t(13 * 9 * 300));
            }
}

// The weights against Eq. (3) and Valve's form with the basis typed from Source, and the way back.
TEST(Ssbump, ConventionsMatchTheFormulasAndInvert)
{
    std::mt19937 rng(5);
    std::normal_distribution<double> g;
    int inside = 0;
    for (int k = 0; k < 2000; ++k)
    {
        glm::dvec3 n(g(rng), g(rng), std::abs(g(rng)));
        n = glm::normalize(n);
        double dots[3], sq[3], sum = 0.0;
        for (int i = 0; i < 3; ++i)
        {
            dots[i] = std::clamp(kBasis[i][0] * n.x + kBasis[i][1] * n.y + kBasis[i][2] * n.z, 0.0, 1.0);
            sq[i] = dots[i] * dots[i];
            sum += sq[i];
        }
        const glm::vec3 valve = ssbump_weights(glm::vec3(n), SsbumpConvention::Valve);
        const glm::vec3 normalized = ssbump_weights(glm::vec3(n), SsbumpConvention::Normalized);
        for (int i = 0; i < 3; ++i)
        {
            EXPECT_NEAR(valve[i], dots[i], 1e-6);
            EXPECT_NEAR(normalized[i], sum > 0.0 ? sq[i] / sum : 0.0, 1e-6);
        }
        // Inside the cone of the three directions nothing is clamped and both conventions invert exactly.
        if (dots[0] > 1e-3 && dots[1] > 1e-3 && dots[2] > 1e-3)
        {
            ++inside;
            for (SsbumpConvention c : {SsbumpConvention::Normalized, SsbumpConvention::Valve})
            {
                const glm::vec3 back = ssbump_normal(ssbump_weights(glm::vec3(n), c), c);
                EXPECT_NEAR(glm::length(glm::dvec3(back) - n), 0.0, 2e-5) << to_string(c);
            }
        }
    }
    EXPECT_GT(inside, 300);
    EXPECT_EQ(ssbump_normal(glm::vec3(0.0f), SsbumpConvention::Valve), glm::vec3(0, 0, 1));
    EXPECT_EQ(parse_ssbump_convention("valve"), SsbumpConvention::Valve);
    EXPECT_THROW(parse_ssbump_convention("source"), std::invalid_argument);
}

// The normals' convention: +x along a row, +y up the image, scale texel widths per height unit.
TEST(Ssbump, NormalsFollowTheTangentConvention)
{
    HeightField ramp = constant(8, 8, 0.0f);
    for (uint32_t y = 0; y < 8; ++y)
        for (uint32_t x = 0; x < 8; ++x)
            ramp.heights[y * 8 + x] = 0.1f * float(x) + 0.05f * float(7 - y); // rises to the right and up
    const std::vector<glm::vec3> n = height_normals(ramp, 2.0f, false);
    // dh/dx = 0.1 -> -0.2 after scale; the height rises up the image (towards row 0): +y slope 0.1 -> -0.1.
    const glm::vec3 expected = glm::normalize(glm::vec3(-0.2f, -0.1f, 1.0f));
    for (uint32_t t : {0u, 9u, 63u})
        EXPECT_NEAR(glm::length(n[t] - expected), 0.0f, 1e-6f) << "texel " << t;
}

// Done-when line 1: a V-groove's directional occlusion matches its analytic visibility, per direction and
// integrated per lobe. The groove runs along y: h(x) = |x - 32| / 32 on a 64-wide tiling map, scale 32, so
// the walls rise at 45 degrees from the floor at x = 32 up to the ridge at x = 0 = 64.
TEST(Ssbump, VGrooveOcclusionMatchesAnalyticVisibility)
{
    const uint32_t w = 64, h = 16;
    HeightField groove = constant(w, h, 0.0f);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            groove.heights[y * w + x] = std::abs(float(x) - 32.0f) / 32.0f;
    const double scale = 32.0, eps = 1e-3, distance = 64.0;
    // The profile along azimuth phi from (x0, floor): p(t) = |x0 + t cos(phi) - 32| periodic, a polyline
    // with kinks where x is a multiple of 32; the horizon slope is the largest (p(t) - p(0) - eps) / t over
    // its kinks and the end t = distance.
    auto profile = [&](double x)
    {
        const double m = std::fmod(std::fmod(x, 64.0) + 64.0, 64.0);
        return scale / 32.0 * std::abs(m - 32.0);
    };
    auto horizon = [&](double x0, double phi)
    {
        const double c = std::cos(phi);
        double best = -1e300;
        std::vector<double> ts = {distance};
        if (std::abs(c) > 1e-12)
            for (int k = -4; k <= 4; ++k)
            {
                const double t = (32.0 * k - x0) / c;
                if (t > 1e-9 && t <= distance)
                    ts.push_back(t);
            }
        for (double t : ts)
            best = std::max(best, (profile(x0 + t * c) - profile(x0) - eps) / t);
        return best;
    };
    const HeightFieldTracer tracer(groove, float(scale), true, float(eps), float(distance));
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int checked = 0;
    for (uint32_t x0 : {32u, 40u, 20u, 3u})
        for (int k = 0; k < 4000; ++k)
        {
            const double phi = 2.0 * M_PI * u(rng), z = u(rng);
            const double rho = std::sqrt(1.0 - z * z);
            const double slope = z / rho, hz = horizon(x0, phi);
            if (std::abs(slope - hz) < 1e-4)
                continue; // a tie within rounding
            const glm::vec3 d(float(rho * std::cos(phi)), float(rho * std::sin(phi)), float(z));
            ASSERT_EQ(tracer.occluded(x0, 5, d), slope < hz) << "x " << x0 << " phi " << phi << " z " << z;
            ++checked;
        }
    EXPECT_GT(checked, 15000);

    // Integrated: O_i at the floor (x = 32) from the analytic horizon, by quadrature over phi and over z
    // above the horizon, against the bake at 300 rays along the whole floor line (16 texels, the same
    // analytic O).
    glm::dvec3 analytic(0.0);
    {
        const int nphi = 4096, nz = 2048;
        double seen[3] = {0, 0, 0}, all[3] = {0, 0, 0};
        for (int a = 0; a < nphi; ++a)
        {
            const double phi = 2.0 * M_PI * (a + 0.5) / nphi;
            const double k = horizon(32.0, phi);
            const double zc = k > 0.0 ? k / std::sqrt(1.0 + k * k) : 0.0;
            for (int b = 0; b < nz; ++b)
            {
                const double z = (b + 0.5) / nz, rho = std::sqrt(1.0 - z * z);
                const glm::dvec3 wdir(rho * std::cos(phi), rho * std::sin(phi), z);
                for (int i = 0; i < 3; ++i)
                {
                    all[i] += lobe(i, wdir);
                    if (z >= zc)
                        seen[i] += lobe(i, wdir);
                }
            }
        }
        analytic = glm::dvec3(seen[0] / all[0], seen[1] / all[1], seen[2] / all[2]);
    }
    // The +x lobe looks across the groove, the two others along it: the first is the most occluded.
    EXPECT_LT(analytic[0], analytic[1] - 0.05);
    SsbumpOptions o;
    o.scale = float(scale);
    o.max_distance = float(distance);
    o.epsilon = float(eps);
    const SsbumpMap m = bake_ssbump(groove, o);
    glm::dvec3 mean(0.0), worst(0.0);
    for (uint32_t y = 0; y < h; ++y)
    {
        const glm::dvec3 occ(m.occlusion[y * w + 32]);
        mean += occ / double(h);
        worst = glm::max(worst, glm::abs(occ - analytic));
        // The floor's normal is +z (symmetric differences): its weights are O_i / 3.
        EXPECT_NEAR(m.weights[y * w + 32][1], occ[1] / 3.0, 1e-6);
    }
    for (int i = 0; i < 3; ++i)
    {
        // The README's figure: one texel's O_i at 300 rays is within 0.03 of the exact value, and the mean
        // over 16 texels within 0.01 (Monte Carlo noise; nothing is biased).
        EXPECT_NEAR(mean[i], analytic[i], 0.01) << "lobe " << i;
        EXPECT_LT(worst[i], 0.03) << "lobe " << i;
    }
}

// Done-when line 2: the bake's occlusion equals a brute-force ray cast against the height-field triangles at
// sampled texels (the borders among them), tiling and not, with the bake's own rays: ray for ray, every texel
// within 1e-5 (the README's figure). Measured: every texel of this map in all four configurations (not only
// the sampled ones) within 5e-8, the float rounding of the stored occlusion; no ray differs. One ray of 300
// differing would move a texel by about 0.003.
TEST(Ssbump, OcclusionEqualsBruteForceRayCast)
{
    const HeightField f = rough(24, 20, 3);
    for (bool wrap : {true, false})
        for (float distance : {7.0f, 0.0f})
        {
            SsbumpOptions o;
            o.scale = 4.0f;
            o.wrap = wrap;
            o.max_distance = distance;
            o.rays = 300;
            const SsbumpMap m = bake_ssbump(f, o);
            const BruteForce brute{f, o.scale, o.epsilon, distance > 0.0f ? distance : 24.0, wrap};
            int texels = 0;
            double occluded = 0.0;
            for (uint32_t y : {0u, 1u, 7u, 19u})
                for (uint32_t x : {0u, 5u, 12u, 23u})
                {
                    const glm::dvec3 ref = brute.occlusion(x, y, o.seed, o.rays);
                    const glm::dvec3 got(m.occlusion[y * f.width + x]);
                    const double diff = glm::length(ref - got);
                    EXPECT_LT(diff, 1e-5)
                        << "texel (" << x << ", " << y << ") wrap " << wrap << " distance " << distance;
                    ++texels;
                    occluded += 3.0 - (ref.x + ref.y + ref.z);
                }
            EXPECT_GT(occluded / texels, 0.3) << "the relief must occlude something to test";
        }
}

// Done-when line 1: a tiling map's result tiles without a seam. Baking the map rolled by half its size and
// rolling the result back gives the same normals exactly and the same occlusion within Monte Carlo noise at
// the borders as inside (without wrapping the borders differ).
TEST(Ssbump, TilingMapBakesWithoutSeam)
{
    const uint32_t w = 32, h = 24;
    const HeightField f = rough(w, h, 11);
    HeightField rolled = f;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            rolled.heights[((y + h / 2) % h) * w + (x + w / 2) % w] = f.at(x, y);
    SsbumpOptions o;
    o.scale = 4.0f;
    o.rays = 1024;
    double border_of[2] = {0, 0};
    for (bool wrap : {true, false})
    {
        o.wrap = wrap;
        const SsbumpMap a = bake_ssbump(f, o), b = bake_ssbump(rolled, o);
        double border = 0.0, inside = 0.0;
        int nb = 0, ni = 0;
        bool normals_equal = true;
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
            {
                const size_t i = y * w + x, j = ((y + h / 2) % h) * w + (x + w / 2) % w;
                normals_equal = normals_equal && a.normals[i] == b.normals[j];
                const double d = glm::length(glm::dvec3(a.occlusion[i]) - glm::dvec3(b.occlusion[j]));
                const bool at_border = x < 2 || y < 2 || x + 2 >= w || y + 2 >= h;
                (at_border ? border : inside) += d;
                ++(at_border ? nb : ni);
            }
        border /= nb;
        inside /= ni;
        border_of[wrap] = border;
        EXPECT_EQ(normals_equal, wrap);
        if (wrap)
        {
            EXPECT_LT(border, 1.5 * inside + 1e-3) << "border " << border << " inside " << inside;
            EXPECT_LT(inside, 0.03);
        }
    }
    // Without wrapping the borders see another relief: the same statistic is far from noise there.
    EXPECT_GT(border_of[0], 3.0 * border_of[1]);
}

// The same bytes on one thread as on all of them, and after resuming from a checkpoint.
TEST(Ssbump, DeterministicAcrossThreadsAndResume)
{
    const HeightField f = rough(40, 36, 21);
    SsbumpOptions o;
    o.scale = 3.0f;
    o.rays = 64;
    const SsbumpMap all = bake_ssbump(f, o);
    SsbumpMap one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = bake_ssbump(f, o);
    }
    ASSERT_EQ(all.weights.size(), one.weights.size());
    EXPECT_EQ(0, std::memcmp(all.weights.data(), one.weights.data(), all.weights.size() * sizeof(glm::vec3)));

    // Slices of one row at this size (2^22 rays a slice); a save after every slice leaves the state before
    // the last one in the file, which a second bake resumes from.
    o.checkpoint = dir() / "determinism.partial";
    o.checkpoint_seconds = 0.0;
    o.rays = 4096;
    const SsbumpMap first = bake_ssbump(f, o);
    ASSERT_TRUE(fs::exists(o.checkpoint));
    EXPECT_FALSE(first.resumed);
    const SsbumpMap resumed = bake_ssbump(f, o);
    EXPECT_TRUE(resumed.resumed);
    EXPECT_LT(resumed.rays, first.rays);
    EXPECT_EQ(0, std::memcmp(first.weights.data(), resumed.weights.data(),
                             first.weights.size() * sizeof(glm::vec3)));
    // Another scale is another key: the checkpoint is ignored.
    o.scale = 2.0f;
    EXPECT_FALSE(bake_ssbump(f, o).resumed);
    remove_checkpoint(o.checkpoint);
}

// The bilateral filter against a direct evaluation of its definition, and what it is for: the stairs of an
// 8-bit ramp are smoothed while a deep step keeps its height.
TEST(Ssbump, BilateralFilterSmoothsStairsAndKeepsEdges)
{
    const uint32_t w = 48, h = 8;
    HeightField f = constant(w, h, 0.0f);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const double ramp =
                0.2 + 0.0011 * x; // a shallow ramp: stairs of one 8-bit step every ~3.6 texels
            const double v = x >= 24 ? ramp + 0.5 : ramp;
            f.heights[y * w + x] = float(std::round(v * 255.0) / 255.0);
        }
    const BilateralFilter filter = default_filter(8);
    EXPECT_EQ(filter.radius, 2);
    const HeightField g = bilateral_filter(f, filter, false);
    // Direct evaluation at a few texels.
    for (uint32_t x : {0u, 10u, 23u, 24u, 47u})
    {
        const uint32_t y = 3;
        double sum = 0.0, weight = 0.0;
        for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx)
            {
                const int sx = int(x) + dx, sy = int(y) + dy;
                if (sx < 0 || sy < 0 || sx >= int(w) || sy >= int(h))
                    continue;
                const double v = f.at(uint32_t(sx), uint32_t(sy)), c = f.at(x, y);
                const double k =
                    std::exp(-(dx * dx + dy * dy) / 2.0) * std::exp(-(v - c) * (v - c) / (2 * 0.02 * 0.02));
                sum += k * v;
                weight += k;
            }
        EXPECT_NEAR(g.at(x, y), sum / weight, 1e-6) << "x " << x;
    }
    // Stairs: the filtered ramp is closer to the true ramp than the quantised one; the step stays a step.
    double before = 0.0, after = 0.0;
    for (uint32_t x = 4; x < 20; ++x)
    {
        const double truth = 0.2 + 0.0011 * x;
        before += std::pow(f.at(x, 3) - truth, 2);
        after += std::pow(g.at(x, 3) - truth, 2);
    }
    EXPECT_LT(after, 0.5 * before);
    EXPECT_NEAR(g.at(22, 3), f.at(22, 3), 0.002);
    EXPECT_NEAR(g.at(25, 3), f.at(25, 3), 0.002);
    // Tiling: filtering the rolled map equals rolling the filtered one.
    HeightField rolled = f;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            rolled.heights[y * w + (x + 7) % w] = f.at(x, y);
    const HeightField a = bilateral_filter(f, filter, true), b = bilateral_filter(rolled, filter, true);
    for (uint32_t x = 0; x < w; ++x)
        EXPECT_EQ(a.at(x, 2), b.at((x + 7) % w, 2)) << "x " << x;
    EXPECT_THROW(bilateral_filter(f, {2, 0.0f}, true), std::invalid_argument);
    EXPECT_THROW(bilateral_filter(f, {-1, 0.1f}, true), std::invalid_argument);
}

// 16-bit PNGs keep their 16 bits; a channel can be chosen; alpha is kept for the output.
TEST(Ssbump, ReadsHeightMapsAtFullDepth)
{
    std::vector<uint16_t> grey(6 * 4);
    for (size_t i = 0; i < grey.size(); ++i)
        grey[i] = uint16_t(i * 2731 + 1);
    const fs::path p16 = dir() / "grey16.png";
    write_bytes(p16, hemi::test::encode_png_samples(6, 4, 1, 16, grey));
    const HeightMapFile a = read_height_map(p16, HeightChannel::Grey);
    EXPECT_EQ(a.bits, 16);
    ASSERT_EQ(a.field.heights.size(), grey.size());
    for (size_t i = 0; i < grey.size(); ++i)
        EXPECT_FLOAT_EQ(a.field.heights[i], float(grey[i]) / 65535.0f);
    EXPECT_TRUE(a.alpha.empty());

    // RGBA with the heights in alpha (Valve's height2ssbump reads it), 8 bits.
    std::vector<uint16_t> rgba(6 * 4 * 4);
    for (size_t i = 0; i < 24; ++i)
    {
        rgba[i * 4 + 0] = 200;
        rgba[i * 4 + 1] = uint16_t(i);
        rgba[i * 4 + 2] = 7;
        rgba[i * 4 + 3] = uint16_t(i * 10);
    }
    const fs::path p8 = dir() / "rgba8.png";
    write_bytes(p8, hemi::test::encode_png_samples(6, 4, 4, 8, rgba));
    const HeightMapFile b = read_height_map(p8, HeightChannel::A);
    EXPECT_EQ(b.bits, 8);
    EXPECT_FLOAT_EQ(b.field.heights[5], 50.0f / 255.0f);
    const HeightMapFile c = read_height_map(p8, HeightChannel::G);
    EXPECT_FLOAT_EQ(c.field.heights[5], 5.0f / 255.0f);
    ASSERT_EQ(c.alpha.size(), 24u);
    EXPECT_EQ(c.alpha[5], 50);
}

// Issue 41, defect 17: a data image is decoded at the channels its file has, not expanded to RGBA: a 4096^2
// grey height map (16.8 M pixels, 8 bits) takes one float a pixel (67 MB) and stb's byte a pixel while it
// decodes; expanded to 16-bit RGBA and then RGBA floats (the old way) it took 24 bytes a pixel, 400 MB. A
// budget that cannot hold the decode (HEMI_MEMORY_BUDGET=32M) refuses it, naming the file and the size,
// before decoding. Grey reads as grey in red, green and blue with alpha 1, as the callers read RGBA.
TEST(Ssbump, AHeightMapIsDecodedAtItsOwnChannelsWithinTheMemoryBudget)
{
    const uint32_t side = 4096;
    std::vector<uint16_t> grey(size_t(side) * side, 0);
    for (uint32_t x = 0; x < side; ++x)
        grey[x] = uint16_t(x & 255); // the top row a ramp
    const fs::path path = dir() / "grey_4096.png";
    write_bytes(path, hemi::test::encode_png_samples(side, side, 1, 8, grey));
    grey = {};
    {
        const uint64_t before = hemi::io::peak_memory();
        const hemi::io::DataImage image = hemi::io::read_data_image(path);
        const uint64_t grew = hemi::io::peak_memory() - before;
        std::printf("a %ux%u grey PNG decoded: %zu floats, peak grew %.1f MiB\n", side, side,
                    image.pixels.size(), double(grew) / 1048576.0);
        EXPECT_EQ(image.channels, 1);
        EXPECT_EQ(image.pixels.size(), size_t(side) * side);
        EXPECT_LT(grew, uint64_t(side) * side * (1 + 4) * 2);
        EXPECT_FLOAT_EQ(image.rgba(7, 0), 7.0f / 255.0f);
        EXPECT_FLOAT_EQ(image.rgba(7, 2), 7.0f / 255.0f);
        EXPECT_FLOAT_EQ(image.rgba(7, 3), 1.0f);
    }
    ASSERT_EQ(setenv("HEMI_MEMORY_BUDGET", "32M", 1), 0);
    try
    {
        hemi::io::read_data_image(path);
        ADD_FAILURE() << "a decode the budget cannot hold was not refused";
    }
    catch (const hemi::io::FormatError& e)
    {
        const std::string message = e.what();
        EXPECT_NE(message.find(path.string() + " (a 4096x4096 image): needs about 80.0 MiB"),
                  std::string::npos)
            << message;
    }
    unsetenv("HEMI_MEMORY_BUDGET");
}

// Done-when line 5: bad height maps give clear errors naming the file.
TEST(Ssbump, BadHeightMapsNameTheFileAndTheProblem)
{
    auto message = [](const fs::path& p, HeightChannel ch = HeightChannel::Grey) -> std::string
    {
        try
        {
            read_height_map(p, ch);
        }
        catch (const hemi::io::FormatError& e)
        {
            return e.what();
        }
        return "";
    };
    auto expect = [&](const fs::path& p, const std::string& problem, HeightChannel ch = HeightChannel::Grey)
    {
        const std::string m = message(p, ch);
        EXPECT_NE(m.find(p.string()), std::string::npos) << m;
        EXPECT_NE(m.find(problem), std::string::npos) << "expected '" << problem << "' in: " << m;
    };
    expect(dir() / "missing.png", "");
    EXPECT_FALSE(message(dir() / "missing.png").empty());
    const fs::path junk = dir() / "junk.png";
    write_bytes(junk, {'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'});
    expect(junk, "neither a PNG nor an EXR");
    const fs::path empty = dir() / "empty.png";
    write_bytes(empty, {});
    expect(empty, "empty");
    const fs::path zero = dir() / "zero.png";
    write_bytes(zero, hemi::test::encode_png_samples(0, 4, 1, 8, {}));
    EXPECT_FALSE(message(zero).empty());
    // Truncated.
    std::vector<uint8_t> good = hemi::test::encode_png_samples(6, 4, 1, 16, std::vector<uint16_t>(24, 1000));
    good.resize(good.size() - 20);
    const fs::path cut = dir() / "cut.png";
    write_bytes(cut, good);
    EXPECT_FALSE(message(cut).empty());
    // A JPEG is lossy: not a height map.
    hemi::io::ImageRgba8 img{4, 4, std::vector<uint8_t>(64, 128)};
    const fs::path jpeg = dir() / "heights.jpg";
    write_bytes(jpeg, hemi::io::encode_jpeg(img));
    expect(jpeg, "JPEG");
    // A tangent-space normal map where heights are expected.
    std::vector<uint16_t> normals(16 * 16 * 3);
    for (size_t i = 0; i < 256; ++i)
    {
        const glm::vec3 n = glm::normalize(glm::vec3(std::sin(0.3f * float(i)) * 0.4f, 0.2f, 1.0f));
        for (int c = 0; c < 3; ++c)
            normals[i * 3 + size_t(c)] = uint16_t(std::lround((n[c] * 0.5f + 0.5f) * 255.0f));
    }
    const fs::path normal_map = dir() / "normal.png";
    write_bytes(normal_map, hemi::test::encode_png_samples(16, 16, 3, 8, normals));
    expect(normal_map, "--from-normal");
    // A colour image read as grey.
    std::vector<uint16_t> colour(16 * 3);
    for (size_t i = 0; i < 16; ++i)
        colour[i * 3] = uint16_t(i * 16), colour[i * 3 + 1] = 3, colour[i * 3 + 2] = 250;
    const fs::path colour_map = dir() / "colour.png";
    write_bytes(colour_map, hemi::test::encode_png_samples(4, 4, 3, 8, colour));
    expect(colour_map, "--channel");
    expect(colour_map, "no alpha", HeightChannel::A);
    // A constant alpha holds no heights.
    std::vector<uint16_t> opaque(16 * 4, 255);
    const fs::path opaque_map = dir() / "opaque.png";
    write_bytes(opaque_map, hemi::test::encode_png_samples(4, 4, 4, 8, opaque));
    expect(opaque_map, "constant", HeightChannel::A);

    // A NaN in an EXR.
    const fs::path nan_exr = dir() / "nan.exr";
    {
        Imf::Rgba px[4];
        for (Imf::Rgba& p : px)
            p = Imf::Rgba(0.5f, 0.5f, 0.5f, 1.0f);
        px[3].r = half(NAN);
        Imf::RgbaOutputFile file(nan_exr.c_str(), 2, 2, Imf::WRITE_RGBA);
        file.setFrameBuffer(px, 1, 2);
        file.writePixels(2);
    }
    expect(nan_exr, "not finite");

    // Options: the scale must be positive and finite.
    for (float s : {0.0f, -2.0f, NAN, INFINITY})
    {
        SsbumpOptions o;
        o.scale = s;
        try
        {
            check_ssbump_options(o);
            ADD_FAILURE() << "scale " << s << " accepted";
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find("scale"), std::string::npos) << e.what();
        }
    }
    // NaN heights handed to the library directly.
    HeightField nan = constant(4, 4, 0.5f);
    nan.heights[6] = NAN;
    try
    {
        bake_ssbump(nan, {});
        ADD_FAILURE() << "NaN accepted";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("(2, 1)"), std::string::npos) << e.what();
    }
}
