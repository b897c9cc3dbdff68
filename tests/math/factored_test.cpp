// Heidrich & Seidel 1999 on the CPU: the factored BRDF tables against the models written out in this file
// (not through hemi's evaluation), and the parabolic maps against the geometry and integrals of §4 computed
// here.
#include <hemi/math/brdf.h>
#include <hemi/math/paraboloid.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace
{
constexpr double kPi = 3.14159265358979323846;

// ---- the models, typed from the papers (Cook & Torrance 1982's Fresnel in its s/p form, Beckmann, Smith)
// ----

double fresnel_sp(double c, double n)
{
    // Snell: sin t = sin i / n; rs, rp from the cosines (an independent form of the unpolarised reflectance).
    const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
    const double ct = std::sqrt(std::max(0.0, 1.0 - (s / n) * (s / n)));
    const double rs = (c - n * ct) / (c + n * ct), rp = (n * c - ct) / (n * c + ct);
    return 0.5 * (rs * rs + rp * rp);
}
double smith_g1(double c, double m)
{
    if (c >= 1.0)
        return 1.0;
    const double a = 1.0 / (m * std::tan(std::acos(c)));
    return 2.0 / (1.0 + std::erf(a) + std::exp(-a * a) / (a * std::sqrt(kPi)));
}
// Eq. 1 with the microfacet normalisation: F G D_w / (4 cos a cos b) * cos a, D_w the Beckmann distribution
// normalised to integral D_w cos = 1.
double torrance_sparrow_beckmann(const glm::dvec3& l, const glm::dvec3& v, double m, double n)
{
    const double ca = l.z, cb = v.z;
    if (ca <= 0 || cb <= 0)
        return 0.0;
    const glm::dvec3 h = glm::normalize(l + v);
    const double t2 = (1 - h.z * h.z) / (h.z * h.z);
    const double dw = std::exp(-t2 / (m * m)) / (kPi * m * m * std::pow(h.z, 4));
    return fresnel_sp(glm::dot(l, h), n) * smith_g1(ca, m) * smith_g1(cb, m) * dw / (4 * ca * cb) * ca;
}

// Bilinear lookup of a table as a GPU sampler makes it, with the axis mappings the header documents.
double axis_coord(hemi::math::BrdfTable::Axis axis, double c)
{
    using A = hemi::math::BrdfTable::Axis;
    return axis == A::Cosine         ? c
           : axis == A::SqrtOneMinus ? std::sqrt(std::max(0.0, 1.0 - c))
                                     : std::acos(c) / kPi;
}
double lookup(const hemi::math::BrdfTable& t, uint32_t channel, double a, double b)
{
    const double pu = std::clamp(axis_coord(t.u_axis, a), 0.0, 1.0) * (t.size - 1);
    const double pv = std::clamp(axis_coord(t.v_axis, b), 0.0, 1.0) * (t.size - 1);
    const uint32_t i = std::min(uint32_t(pu), t.size - 2), j = std::min(uint32_t(pv), t.size - 2);
    const double fu = pu - i, fv = pv - j;
    auto at = [&](uint32_t x, uint32_t y)
    { return double(t.values[(size_t(y) * t.size + x) * t.channels + channel]); };
    return (1 - fv) * ((1 - fu) * at(i, j) + fu * at(i + 1, j)) +
           fv * ((1 - fu) * at(i, j + 1) + fu * at(i + 1, j + 1));
}

std::vector<glm::dvec3> hemisphere(int n, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<glm::dvec3> out;
    for (int i = 0; i < n; ++i)
    {
        const double z = u(rng), phi = 2 * kPi * u(rng), s = std::sqrt(1 - z * z);
        out.emplace_back(s * std::cos(phi), s * std::sin(phi), z);
    }
    return out;
}
} // namespace

TEST(Brdf, FresnelMatchesTheSPolarisationForm)
{
    for (double n : {1.1, 1.5, 2.4, 200.0})
        for (int i = 0; i <= 100; ++i)
        {
            const double c = i / 100.0;
            EXPECT_NEAR(hemi::math::fresnel_dielectric(c, n), fresnel_sp(c, n), 1e-12)
                << "n " << n << " cos " << c;
        }
    EXPECT_NEAR(hemi::math::fresnel_dielectric(1.0, 1.5), 0.04, 1e-12);
    EXPECT_NEAR(hemi::math::fresnel_dielectric(0.0, 1.5), 1.0, 1e-12);
}

TEST(Brdf, DistributionsIntegrateToEq1sNormalisation)
{
    // integral of D(n.h) (n.h) over the hemisphere of h = pi / 4, by the test's own midpoint rule in theta.
    for (auto dist : {hemi::math::FacetDistribution::Beckmann, hemi::math::FacetDistribution::Gaussian})
        for (double m : {0.05, 0.2, 0.5})
        {
            const hemi::math::TorranceSparrow model(dist, m, 1.5);
            const int n = 200000;
            double sum = 0.0;
            for (int i = 0; i < n; ++i)
            {
                const double t = (i + 0.5) * (kPi / 2) / n;
                sum += model.distribution_term(std::cos(t)) * std::cos(t) * std::sin(t);
            }
            EXPECT_NEAR(2 * kPi * sum * (kPi / 2) / n, kPi / 4, 1e-6)
                << hemi::math::facet_distribution_name(dist) << " m " << m;
        }
}

// Done-when 1 (CPU): the product of the two tables equals f_r cos(alpha) evaluated directly over a dense set
// of directions, to 0.5% of max(value, 1% of the peak) with cos_alpha, cos_beta >= 0.1 and to 2% in the
// grazing band (README, "Factored BRDFs"). A table sampled linearly in cos_delta (the paper's axis) fails at
// m = 0.1.
TEST(Brdf, TorranceSparrowTablesProductMatchesEq1)
{
    for (double m : {0.1, 0.3})
    {
        const hemi::math::TorranceSparrow model(hemi::math::FacetDistribution::Beckmann, m, 1.5);
        const auto tables = hemi::math::torrance_sparrow_tables(model, 256);
        ASSERT_EQ(tables.size(), 2u);
        const auto dirs = hemisphere(700, 7);
        double peak = 0.0;
        for (const auto& l : dirs)
            for (const auto& v : dirs)
                peak = std::max(peak, torrance_sparrow_beckmann(l, v, m, 1.5));
        double bulk = 0.0, grazing = 0.0;
        for (const auto& l : dirs)
            for (const auto& v : dirs)
            {
                const double direct = torrance_sparrow_beckmann(l, v, m, 1.5);
                const glm::dvec3 h = glm::normalize(l + v);
                const double table =
                    lookup(tables[0], 0, glm::dot(l, h), h.z) * lookup(tables[1], 0, l.z, v.z);
                const double rel = std::abs(table - direct) / std::max(direct, 0.01 * peak);
                double& worst = l.z < 0.1 || v.z < 0.1 ? grazing : bulk;
                worst = std::max(worst, rel);
                // and hemi's own direct evaluation agrees with the one typed here
                ASSERT_NEAR(model.eval_cos({0, 0, 1}, l, v), direct, 1e-9 * std::max(1.0, direct));
            }
        EXPECT_LT(bulk, 0.005) << "m " << m;
        EXPECT_LT(grazing, 0.02) << "m " << m;
    }
}

TEST(Brdf, SingleTableModelsMatchTheirLobes)
{
    const glm::dvec3 n(0, 0, 1), t(1, 0, 0);
    const auto dirs = hemisphere(500, 11);
    const double e = 50.0;
    // Banks: cos_alpha (kd sqrt(1 - (t.l)^2) + ks max(0, cos of the angle between v and the nearest reflected
    // direction on the cone about t)^e), written out as the cone's maximum over its azimuth (brute force).
    const auto banks = hemi::math::banks_table(e, 256);
    for (size_t i = 0; i < dirs.size(); i += 5)
        for (size_t j = 0; j < dirs.size(); j += 5)
        {
            const glm::dvec3 l = dirs[i], v = dirs[j];
            double best = -1.0;
            for (int k = 0; k < 3600; ++k)
            {
                const double phi = 2 * kPi * k / 3600, s = std::sqrt(1 - l.x * l.x);
                const glm::dvec3 r(-l.x, s * std::cos(phi), s * std::sin(phi)); // r.t = -l.t, |r| = 1
                best = std::max(best, glm::dot(r, v));
            }
            const double direct = l.z * (std::sqrt(1 - l.x * l.x) + std::pow(std::max(0.0, best), e));
            const double table = l.z * (lookup(banks, 0, l.x, v.x) + lookup(banks, 1, l.x, v.x));
            EXPECT_NEAR(table, direct, 0.01 * std::max(direct, 0.01))
                << "l " << l.x << "," << l.y << "," << l.z;
            EXPECT_NEAR(hemi::math::banks_eval_cos(n, t, l, v, 1, 1, e), direct,
                        2e-3 * std::max(direct, 0.01));
        }
    // Phong (Eq. 8 normalised): ((e + 1) / 2 pi) max(0, r_v.l)^e; Blinn-Phong x ((e + 8) / 8 pi) (n.h)^e.
    const auto phong = hemi::math::lobe_table(hemi::math::LobeModel::Phong, e, 256);
    const auto blinn = hemi::math::lobe_table(hemi::math::LobeModel::BlinnPhong, e, 256);
    const auto cosine = hemi::math::lobe_table(hemi::math::LobeModel::CosineLobe, e, 256);
    for (const auto& l : dirs)
        for (size_t j = 0; j < dirs.size(); j += 3)
        {
            const glm::dvec3 v = dirs[j];
            const glm::dvec3 r = glm::dvec3(-v.x, -v.y, v.z);
            const double p = (e + 1) / (2 * kPi) * std::pow(std::max(0.0, glm::dot(r, l)), e);
            const double hz = glm::normalize(l + v).z;
            const double b = l.z * (e + 8) / (8 * kPi) * std::pow(hz, e);
            EXPECT_NEAR(lookup(phong, 0, l.z, glm::dot(r, l)), p,
                        0.005 * std::max(p, (e + 1) / (2 * kPi) * 0.01));
            EXPECT_NEAR(lookup(blinn, 0, l.z, hz), b, 0.005 * std::max(b, (e + 8) / (8 * kPi) * 0.01));
            // cosine lobe: x ((e + 2) / 2 pi) max(0, r_v.l)^e
            const double cl = l.z * (e + 2) / (2 * kPi) * std::pow(std::max(0.0, glm::dot(r, l)), e);
            EXPECT_NEAR(lookup(cosine, 0, l.z, glm::dot(r, l)), cl,
                        0.005 * std::max(cl, (e + 2) / (2 * kPi) * 0.01));
        }
}

TEST(Brdf, BadParametersAreRefused)
{
    using hemi::math::FacetDistribution;
    EXPECT_THROW(hemi::math::TorranceSparrow(FacetDistribution::Beckmann, 0.0, 1.5), std::invalid_argument);
    EXPECT_THROW(hemi::math::TorranceSparrow(FacetDistribution::Beckmann, NAN, 1.5), std::invalid_argument);
    EXPECT_THROW(hemi::math::TorranceSparrow(FacetDistribution::Beckmann, 1e-200, 1.5),
                 std::invalid_argument);
    EXPECT_THROW(hemi::math::lobe_table(hemi::math::LobeModel::Phong, 1e40, 16), std::invalid_argument);
    // Far from the peak D underflows to 0, not 0 / 0.
    EXPECT_EQ(hemi::math::TorranceSparrow(FacetDistribution::Beckmann, 0.01, 1.5).distribution_term(1e-100),
              0.0);
    EXPECT_THROW(hemi::math::TorranceSparrow(FacetDistribution::Beckmann, 0.3, 1.0), std::invalid_argument);
    EXPECT_THROW(hemi::math::TorranceSparrow(FacetDistribution::Beckmann, 0.3, NAN), std::invalid_argument);
    EXPECT_THROW(hemi::math::banks_table(0.0, 16), std::invalid_argument);
    EXPECT_THROW(hemi::math::lobe_table(hemi::math::LobeModel::Phong, -1.0, 16), std::invalid_argument);
    EXPECT_THROW(hemi::math::parse_lobe_model("ward"), std::invalid_argument);
    EXPECT_THROW(hemi::math::fresnel_table(0.9, 16), std::invalid_argument);
}

// ---- parabolic maps ----

TEST(Paraboloid, ConventionAndRoundTripWithinHalfATexel)
{
    using namespace hemi::math;
    // Anchors: +z at the front's centre, -z at the back's, +x and +y on both circles (y up the image).
    EXPECT_EQ(parabolic_half({0, 0, 1}), 0);
    EXPECT_EQ(parabolic_half({0, 0, -1}), 1);
    EXPECT_NEAR(glm::length(parabolic_xy({0, 0, 1}, 0)), 0.0, 1e-15);
    EXPECT_NEAR(glm::length(parabolic_xy({0, 0, -1}, 1)), 0.0, 1e-15);
    for (int half : {0, 1})
    {
        EXPECT_NEAR(glm::length(parabolic_xy({1, 0, 0}, half) - glm::dvec2(1, 0)), 0.0, 1e-15);
        EXPECT_NEAR(glm::length(parabolic_xy({0, 1, 0}, half) - glm::dvec2(0, 1)), 0.0, 1e-15);
    }
    // The paraboloid of Eq. 5 reflects d into the viewing direction -z... (front): its normal (x, y, 1)
    // halves d and +z.
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.3, -0.5, 0.7));
    const glm::dvec2 xy = parabolic_xy(d, 0);
    const glm::dvec3 h = glm::normalize(d + glm::dvec3(0, 0, 1));
    EXPECT_NEAR(xy.x, h.x / h.z, 1e-12);
    EXPECT_NEAR(xy.y, h.y / h.z, 1e-12);

    for (uint32_t size : {16u, 512u})
    {
        ParabolicImage img;
        img.size = size;
        img.extent = parabolic_extent(size);
        std::mt19937 rng(3);
        std::normal_distribution<double> g;
        for (int i = 0; i < 20000; ++i)
        {
            const glm::dvec3 dir = glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
            const int half = parabolic_half(dir);
            const glm::dvec2 p = parabolic_xy(dir, half);
            ASSERT_LE(glm::length(p), 1.0 + 1e-12);
            ASSERT_NEAR(glm::length(parabolic_direction(half, p.x, p.y) - dir), 0.0, 1e-12);
            // The texel the direction falls in: its centre is within half a texel (m / size in x and y).
            const double m = img.extent;
            const uint32_t col = std::min(size - 1, uint32_t((p.x / m + 1) / 2 * size));
            const uint32_t row = std::min(size - 1, uint32_t((1 - p.y / m) / 2 * size));
            const glm::dvec2 c = parabolic_xy(img.direction(half, col, row), half);
            ASSERT_LE(std::abs(c.x - p.x), m / size + 1e-12);
            ASSERT_LE(std::abs(c.y - p.y), m / size + 1e-12);
        }
    }
}

TEST(Paraboloid, TexelSolidAnglesSumToTheSphereAndVaryByFour)
{
    using namespace hemi::math;
    for (uint32_t size : {8u, 64u, 256u})
    {
        ParabolicImage img; // the paper's square (extent 1), where the ratio is the paper's 4
        img.size = size;
        double in_circle = 0.0, lo = 1e9, hi = 0.0;
        for (uint32_t r = 0; r < size; ++r)
            for (uint32_t c = 0; c < size; ++c)
            {
                const double in = img.solid_angle_in_circle(c, r), whole = img.solid_angle(c, r);
                in_circle += 2 * in; // both halves
                ASSERT_LE(in, whole + 1e-15);
                if (in == whole)
                    lo = std::min(lo, whole), hi = std::max(hi, whole);
            }
        EXPECT_NEAR(in_circle, 4 * kPi, 1e-4) << size;
        img.extent = parabolic_extent(size); // and hemi's, one texel beyond the circle
        double sum = 0.0;
        for (uint32_t r = 0; r < size; ++r)
            for (uint32_t c = 0; c < size; ++c)
                sum += 2 * img.solid_angle_in_circle(c, r);
        EXPECT_NEAR(sum, 4 * kPi, 1e-4) << size;
        if (size == 256)
        {
            EXPECT_GT(hi / lo, 3.9);
            EXPECT_LT(hi / lo, 4.0);
        }
    }
    // A texel's solid angle against the test's own midpoint rule of Eq. 6 (4 dA / (1 + x^2 + y^2)^2).
    const double x0 = 0.25, y0 = -0.75, x1 = 0.5, y1 = -0.5;
    double sum = 0.0;
    const int n = 2000;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
        {
            const double x = x0 + (i + 0.5) * (x1 - x0) / n, y = y0 + (j + 0.5) * (y1 - y0) / n;
            const double r = 1 + x * x + y * y;
            sum += 4 / (r * r) * (x1 - x0) * (y1 - y0) / (double(n) * n);
        }
    EXPECT_NEAR(parabolic_solid_angle(x0, y0, x1, y1), sum, 1e-9);
}

namespace
{
std::vector<float> equirect(uint32_t w, uint32_t h, auto radiance)
{
    std::vector<float> px(size_t(w) * h * 4);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            // sh_environment.h's convention: phi = pi - 2 pi u from +x toward +y, theta from +z.
            const double phi = kPi - 2 * kPi * (x + 0.5) / w, theta = kPi * (y + 0.5) / h;
            const glm::dvec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta));
            const glm::dvec3 l = radiance(d);
            float* p = px.data() + (size_t(y) * w + x) * 4;
            p[0] = float(l.x), p[1] = float(l.y), p[2] = float(l.z), p[3] = 1.0f;
        }
    return px;
}
} // namespace

TEST(Paraboloid, ResamplesAnEquirectInItsOrientation)
{
    using namespace hemi::math;
    // Each channel lights one axis: a mirrored or rotated mapping puts red where green belongs.
    auto l = [](const glm::dvec3& d) { return glm::dvec3(1 + d.x, 1 + d.y, 1 + d.z); };
    const auto px = equirect(1024, 512, l);
    const ParabolicImage img = parabolic_from_equirect(64, 1024, 512, px);
    for (int half : {0, 1})
        for (uint32_t r = 0; r < 64; ++r)
            for (uint32_t c = 0; c < 64; ++c)
            {
                const glm::dvec3 expect = l(img.direction(half, c, r));
                const float* t = img.at(half, c, r);
                for (int k = 0; k < 3; ++k)
                    ASSERT_NEAR(t[k], expect[k], 0.02) << half << " " << c << "," << r;
            }
}

// Done-when 2: a constant environment gives a constant map at every mip level and a constant prefiltered
// result for every exponent (white furnace, 1%).
TEST(Paraboloid, WhiteFurnaceAtEveryLevelAndExponent)
{
    using namespace hemi::math;
    const auto px = equirect(256, 128, [](const glm::dvec3&) { return glm::dvec3(0.5, 1.0, 2.0); });
    const auto chain = parabolic_mip_chain(parabolic_from_equirect(256, 256, 128, px));
    ASSERT_EQ(chain.size(), 9u);
    for (const ParabolicImage& level : chain)
        for (size_t i = 0; i < level.rgb.size(); i += 3)
        {
            ASSERT_NEAR(level.rgb[i], 0.5f, 1e-6f);
            ASSERT_NEAR(level.rgb[i + 1], 1.0f, 1e-6f);
            ASSERT_NEAR(level.rgb[i + 2], 2.0f, 1e-6f);
        }
    for (double e : {1.0, 4.0, 30.0, 200.0})
        for (bool exact : {false, true})
        {
            const ParabolicImage g = exact ? prefilter_phong_exact(chain, e) : prefilter_phong(chain, e);
            EXPECT_EQ(g.size, glossy_size(e, 256));
            double worst = 0.0;
            for (size_t i = 0; i < g.rgb.size(); i += 3)
                worst = std::max(worst, std::abs(g.rgb[i + 1] - 1.0));
            EXPECT_LT(worst, 0.01) << "exponent " << e << (exact ? ", exact" : "");
        }
}

// Done-when 2: a single bright texel's prefiltered lobe is the analytic Phong lobe,
// ((e + 1) / 2 pi) max(0, r.d)^e * L * its solid angle, at every output texel; and the mip chain weights it
// by its solid angle.
TEST(Paraboloid, SingleBrightTexelGivesThePhongLobe)
{
    using namespace hemi::math;
    const uint32_t n = 64;
    const double m = parabolic_extent(n);
    // A texel's solid angle by the test's own midpoint rule of Eq. 6, whole or inside the circle.
    auto omega = [&](uint32_t c, uint32_t r, bool circle)
    {
        const double x0 = m * (-1 + 2.0 * c / n), y1 = m * (1 - 2.0 * r / n), step = 2.0 * m / n;
        double s = 0.0;
        const int k = 400;
        for (int i = 0; i < k; ++i)
            for (int j = 0; j < k; ++j)
            {
                const double x = x0 + (i + 0.5) * step / k, y = y1 - (j + 0.5) * step / k;
                const double q = 1 + x * x + y * y;
                if (!circle || x * x + y * y <= 1.0)
                    s += 4 / (q * q) * step * step / (double(k) * k);
            }
        return s;
    };
    struct Bright
    {
        int half;
        uint32_t col, row;
    };
    // Inside the front's circle off its centre, inside the back's, and one the back's circle cuts.
    for (const Bright b : {Bright{0, 41, 22}, Bright{1, 12, 40}, Bright{1, 62, 31}})
    {
        ParabolicImage level0;
        level0.size = n;
        level0.extent = m;
        level0.rgb.assign(size_t(2) * n * n * 3, 0.0f);
        const float radiance = 1000.0f;
        for (int k = 0; k < 3; ++k)
            level0.at(b.half, b.col, b.row)[k] = radiance;
        const auto chain = parabolic_mip_chain(level0);
        // Level 1: the bright texel's share of its 2 x 2 block, by solid angle (a plain average gives 1/4).
        double block = 0.0;
        for (uint32_t k = 0; k < 4; ++k)
            block += omega((b.col & ~1u) + (k & 1), (b.row & ~1u) + (k >> 1), false);
        const double share = radiance * omega(b.col, b.row, false) / block;
        EXPECT_NEAR(chain[1].at(b.half, b.col / 2, b.row / 2)[0], share, 1e-4 * share);

        const double e = 16.0;
        ASSERT_EQ(glossy_size(e, n), n);
        const ParabolicImage g = prefilter_phong_exact(chain, e);
        const glm::dvec3 d = level0.direction(b.half, b.col, b.row);
        const double w = omega(b.col, b.row, true); // the directions the texel holds for its half
        const double peak = (e + 1) / (2 * kPi) * radiance * w;
        int compared = 0;
        for (int half : {0, 1})
            for (uint32_t r = 0; r < n; ++r)
                for (uint32_t c = 0; c < n; ++c)
                {
                    const double cosine = glm::dot(g.direction(half, c, r), d);
                    const double expect =
                        (e + 1) / (2 * kPi) * std::pow(std::max(0.0, cosine), e) * radiance * w;
                    if (expect > 1e-3 * peak)
                    {
                        ASSERT_NEAR(g.at(half, c, r)[0], expect, 1e-3 * expect)
                            << half << " " << c << "," << r;
                        ++compared;
                    }
                    else
                        ASSERT_LT(g.at(half, c, r)[0], 2e-3 * peak);
                }
        EXPECT_GT(compared, 200) << b.half << " " << b.col << "," << b.row;
    }
}

namespace
{
// An environment with what makes prefiltering hard, w x h: a small sun of radiance 2000 (`sun_radius`
// radians), a sky gradient, a dark ground and bright panels across the parabolic seam (z = 0).
std::vector<float> hard_environment(uint32_t w, uint32_t h, double sun_radius)
{
    const glm::dvec3 sun = glm::normalize(glm::dvec3(0.6, 0.5, 0.45));
    return equirect(w, h,
                    [&](const glm::dvec3& d)
                    {
                        if (glm::dot(d, sun) > std::cos(sun_radius))
                            return glm::dvec3(2000.0, 1900.0, 1700.0);
                        if (std::abs(d.z) < 0.15 && std::abs(d.x) > 0.8)
                            return glm::dvec3(8.0, 2.0, 1.0);
                        if (d.z < 0.0)
                            return glm::dvec3(0.05, 0.04, 0.03);
                        return glm::dvec3(0.3, 0.5, 1.0) * (1.0 + 2.0 * (1.0 - d.z));
                    });
}

// The RMSE of `fast` against `exact` at the envmap report's 1024 directions (a Fibonacci sphere), relative
// to the exact map's RMS.
double prefilter_rmse(const hemi::math::ParabolicImage& fast, const hemi::math::ParabolicImage& exact)
{
    const uint32_t directions = 1024;
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    double diff = 0.0, rms = 0.0;
    for (uint32_t k = 0; k < directions; ++k)
    {
        const double z = 1.0 - (k + 0.5) * 2.0 / directions, r = std::sqrt(1.0 - z * z);
        const glm::dvec3 d(r * std::cos(golden * k), r * std::sin(golden * k), z);
        const glm::dvec3 f = fast.sample(d), x = exact.sample(d);
        diff += glm::dot(f - x, f - x);
        rms += glm::dot(x, x);
    }
    return std::sqrt(diff / rms);
}
} // namespace

// prefilter_phong (the default) against prefilter_phong_exact (hemi-bake envmap --exact) on an environment
// with what makes prefiltering hard: a small sun of radiance 2000 (a quarter of a texel at level 0), a sky
// gradient, a dark ground and bright panels across the seam. At the envmap report's 1024 directions each map
// (the diffuse one, e = 10 and e = 60, both of which coarsen the source and interpolate at this size) is
// within 0.5% RMSE of the exact one, relative to its RMS, and sums at least 8x fewer texel pairs. Fails for a
// coarse source taken from the plain mipmaps (whose texels across the circle mix the two halves: 2-5%), for a
// block at its centre instead of its radiance's centroid (the sun moves by up to a block), or for
// interpolation weights that are not the midpoint cubic.
TEST(Paraboloid, FastPrefilterIsWithinHalfAPercentOfTheExactSum)
{
    using namespace hemi::math;
    const auto chain =
        parabolic_mip_chain(parabolic_from_equirect(128, 1024, 512, hard_environment(1024, 512, 0.012)));
    for (double e : {1.0, 10.0, 60.0})
    {
        PrefilterStats fast_stats, exact_stats;
        const ParabolicImage fast = prefilter_phong(chain, e, &fast_stats);
        const ParabolicImage exact = prefilter_phong_exact(chain, e, &exact_stats);
        ASSERT_EQ(fast.size, exact.size);
        const double rmse = prefilter_rmse(fast, exact);
        std::printf("e = %g: %ux%u, RMSE %.3f%% of the exact map's RMS, %llu texel pairs against %llu\n", e,
                    fast.size, fast.size, 100.0 * rmse, (unsigned long long)fast_stats.texel_pairs,
                    (unsigned long long)exact_stats.texel_pairs);
        EXPECT_LT(rmse, 0.005) << "exponent " << e;
        if (e > 1.0)
        {
            EXPECT_LT(fast_stats.texel_pairs * 8, exact_stats.texel_pairs) << "exponent " << e;
        }
    }
}

// The README's configuration (issue 41, claim 9): the default glossy maps e = 10, 100 and 1000 of a 2048 x
// 1024 environment with a sun of radiance 2000, on a 2 x 512^2 chain, each within 0.3% RMSE of the exact sum
// at the report's 1024 directions (the same environment as above at the README's size; measured in the
// docs' table on the studio sky: 0.28%, 0.22%, 0.30%). About 6 s in a release build: the exact sums.
TEST(Paraboloid, TheReadmesGlossyMapsAreWithinItsStatedPrecisionOfTheExactSum)
{
    using namespace hemi::math;
    const auto chain =
        parabolic_mip_chain(parabolic_from_equirect(512, 2048, 1024, hard_environment(2048, 1024, 0.006)));
    for (double e : {10.0, 100.0, 1000.0})
    {
        const ParabolicImage fast = prefilter_phong(chain, e), exact = prefilter_phong_exact(chain, e);
        ASSERT_EQ(fast.size, exact.size);
        const double rmse = prefilter_rmse(fast, exact);
        std::printf("e = %g: 2 x %u^2, RMSE %.3f%% of the exact map's RMS\n", e, fast.size, 100.0 * rmse);
        EXPECT_LT(rmse, 0.003) << "exponent " << e;
    }
}

// A lobe far narrower than a texel (a texel against itself, where a float dot product can exceed 1) gives
// finite values, up to the largest exponent allowed (1e6); one beyond 1e6 is refused. Under a constant
// environment of 1 no texel can exceed the lobe's normalisation times the whole sphere, (e + 1) / (2 pi) * 4
// pi, and none is negative.
TEST(Paraboloid, HugeExponentsStayFinite)
{
    using namespace hemi::math;
    const std::vector<float> px(64 * 32 * 4, 1.0f);
    const auto chain = parabolic_mip_chain(parabolic_from_equirect(32, 64, 32, px));
    for (const double e : {3e4, kMaxPhongExponent})
    {
        const ParabolicImage g = prefilter_phong(chain, e);
        ASSERT_EQ(g.size, 32u);
        const double bound = (e + 1) / (2 * kPi) * 4 * kPi;
        double sum = 0.0;
        for (float v : g.rgb)
        {
            ASSERT_TRUE(std::isfinite(v)) << "exponent " << e;
            ASSERT_GE(v, 0.0f) << "exponent " << e;
            ASSERT_LE(v, bound) << "exponent " << e;
            sum += v;
        }
        EXPECT_GT(sum, 0.0) << "exponent " << e;
    }
    EXPECT_THROW(prefilter_phong(chain, 2e6), std::invalid_argument);
}

// The two halves agree along the seam: a smooth environment sampled just above and just below z = 0 (the
// lookup a shader makes) jumps by much less than it changes over one texel within a half, in the mirror map
// and in the diffuse and a glossy map. A back half mirrored in x, or halves that stop at the circle, jump by
// far more.
TEST(Paraboloid, SeamBetweenTheHalvesIsContinuous)
{
    using namespace hemi::math;
    auto l = [](const glm::dvec3& d)
    { return glm::dvec3(2 + d.x + 0.5 * d.y, 2 + std::sin(3 * d.x) * d.y, 2 + d.z); };
    const auto px = equirect(1024, 512, l);
    const auto chain = parabolic_mip_chain(parabolic_from_equirect(128, 1024, 512, px));
    for (double e : {0.0, 1.0, 10.0})
    {
        const ParabolicImage map = e == 0.0 ? chain[0] : prefilter_phong(chain, e);
        const double texel = 2.0 / map.size; // radians along the seam's meridian, one texel at the circle
        double jump = 0.0, change = 0.0, worst_jump = 0.0, worst_change = 0.0;
        for (int i = 0; i < 720; ++i)
        {
            const double phi = 2 * kPi * (i + 0.3) / 720;
            const glm::dvec3 above(std::cos(phi), std::sin(phi), 1e-7),
                below(std::cos(phi), std::sin(phi), -1e-7);
            const glm::dvec3 up(std::cos(phi) * std::cos(texel), std::sin(phi) * std::cos(texel),
                                std::sin(texel));
            const glm::dvec3 a = map.sample(above), b = map.sample(below), c = map.sample(up);
            for (int k = 0; k < 3; ++k)
            {
                jump += std::abs(a[k] - b[k]);
                change += std::abs(c[k] - a[k]);
                worst_jump = std::max(worst_jump, std::abs(a[k] - b[k]));
                worst_change = std::max(worst_change, std::abs(c[k] - a[k]));
            }
        }
        EXPECT_LT(jump, 0.25 * change) << "exponent " << e << " (0: mirror)";
        EXPECT_LT(worst_jump, 0.5 * worst_change) << "exponent " << e << " (0: mirror)";
    }
}

TEST(Paraboloid, BadInputIsRefused)
{
    using namespace hemi::math;
    const std::vector<float> px(8 * 4 * 4, 1.0f);
    EXPECT_THROW(parabolic_from_equirect(100, 8, 4, px), std::invalid_argument);
    EXPECT_THROW(parabolic_from_equirect(16, 8, 5, px), std::invalid_argument);
    std::vector<float> nan = px;
    nan[5] = NAN;
    EXPECT_THROW(parabolic_from_equirect(16, 8, 4, nan), std::invalid_argument);
    const auto chain = parabolic_mip_chain(parabolic_from_equirect(16, 8, 4, px));
    EXPECT_THROW(prefilter_phong(chain, 0.0), std::invalid_argument);
    EXPECT_THROW(prefilter_phong(chain, NAN), std::invalid_argument);
}
