// SH9 conventions and irradiance, checked against DESIGN.md's printed constants and against brute-force
// integration of the clamped cosine (an evaluation that shares no code with the SH path).
#include <hemi/math/sh.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

using namespace hemi::math;

namespace
{
// DESIGN.md Sec. 3's table typed here, so the tests below have an SH9 evaluation that shares no code (and no
// constant) with the library's.
std::array<double, 9> design_table_sh9(glm::dvec3 d)
{
    const double x = d.x, y = d.y, z = d.z;
    return {0.282095,
            -0.488603 * y,
            0.488603 * z,
            -0.488603 * x,
            1.092548 * x * y,
            -1.092548 * y * z,
            0.315392 * (3 * z * z - 1),
            -1.092548 * x * z,
            0.546274 * (x * x - y * y)};
}
} // namespace

// At the axes, their negatives and 200 random directions (every octant, so a sign that depends on one
// coordinate's sign, such as |x| y for xy, is caught), to the table's printed 6 digits.
TEST(Sh9, MatchesTheConventionTable)
{
    std::mt19937 rng(17);
    std::normal_distribution<float> g;
    std::vector<glm::vec3> dirs = {{1, 0, 0},
                                   {-1, 0, 0},
                                   {0, 1, 0},
                                   {0, -1, 0},
                                   {0, 0, 1},
                                   {0, 0, -1},
                                   glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f))};
    for (int i = 0; i < 200; ++i)
        dirs.push_back(glm::normalize(glm::vec3(g(rng), g(rng), g(rng))));
    for (const glm::vec3& d : dirs)
    {
        const Sh9 y = sh9_eval(d);
        float general[9];
        sh_eval(3, d, general);
        const std::array<double, 9> want = design_table_sh9(glm::dvec3(d));
        for (int k = 0; k < 9; ++k)
        {
            ASSERT_NEAR(y[k], want[k], 1e-6)
                << "sh9_eval index " << k << " at " << d.x << "," << d.y << "," << d.z;
            ASSERT_NEAR(general[k], want[k], 1e-6)
                << "sh_eval index " << k << " at " << d.x << "," << d.y << "," << d.z;
        }
    }
}

TEST(Sh9, ConstantEnvironmentGivesPiIrradiance)
{
    Sh9Rgb e = convolve_cosine(project_sh9([](const glm::vec3&) { return glm::vec3(1.0f); }, 64));
    for (glm::vec3 n : {glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), glm::normalize(glm::vec3(-1, 2, -3))})
    {
        glm::vec3 E = sh9_eval_rgb(e, n);
        EXPECT_NEAR(E.x, float(M_PI), 1e-4f) << n.x << " " << n.y << " " << n.z;
        EXPECT_NEAR(E.z, float(M_PI), 1e-4f);
    }
}

// E(n) = integral of L(w) max(0, n.w) dw by brute force, against the SH9 approximation built from the
// library's projection and A_l but evaluated with DESIGN.md's table typed in this file: projection and
// evaluation share no y_lm, so a sign error in a basis function cannot cancel (the projected coefficient
// flips while the evaluation does not). The environment has a component along every band-1 and band-2
// function so that each sign matters. For a smooth environment SH9 irradiance is accurate to a few percent
// (Ramamoorthi & Hanrahan 2001); a sign error or a wrong A_l moves E by far more.
TEST(Sh9, IrradianceOfSmoothSkyMatchesBruteForce)
{
    AnalyticSky sky;
    sky.sun_color = glm::vec3(0.0f); // keep it smooth: SH9 is a low-pass of the irradiance
    sky.zenith = {0.1f, 0.3f, 1.2f};
    auto L = [&](const glm::vec3& d)
    {
        const float q = 0.5f + 0.2f * d.x - 0.25f * d.y + 0.3f * d.x * d.y - 0.3f * d.y * d.z +
                        0.25f * d.x * d.z + 0.2f * (d.x * d.x - d.y * d.y);
        return sky.radiance(d) + glm::vec3(0.6f * std::max(0.0f, d.x), q, 0.5f * q);
    };
    Sh9Rgb e = convolve_cosine(project_sh9(L, 128));
    const int steps = 256;
    for (glm::vec3 n :
         {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
          glm::vec3(0, 1, 0), glm::vec3(0, -1, 0), glm::normalize(glm::vec3(0.3f, -0.8f, 0.5f)),
          glm::normalize(glm::vec3(-0.5f, 0.5f, -0.2f)), glm::normalize(glm::vec3(0.6f, 0.6f, 0.5f)),
          glm::normalize(glm::vec3(-0.6f, -0.6f, 0.5f))})
    {
        glm::dvec3 brute(0.0);
        for (int t = 0; t < steps; ++t)
            for (int p = 0; p < 2 * steps; ++p)
            {
                double theta = (t + 0.5) * M_PI / steps, phi = (p + 0.5) * M_PI / steps;
                glm::vec3 w(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                            float(std::cos(theta)));
                double c = std::max(0.0f, glm::dot(n, w));
                brute += glm::dvec3(L(w)) * c * std::sin(theta) * (M_PI / steps) * (M_PI / steps);
            }
        const std::array<double, 9> y = design_table_sh9(glm::dvec3(n));
        glm::dvec3 sh(0.0);
        for (int k = 0; k < 9; ++k)
            sh += glm::dvec3(e[k]) * y[k];
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(sh[ch], brute[ch], 0.03 * brute[ch] + 0.01)
                << "normal " << n.x << "," << n.y << "," << n.z << " channel " << ch;
    }
}

namespace
{
glm::vec3 random_direction(std::mt19937& rng)
{
    std::normal_distribution<float> g;
    return glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
}

glm::mat3 random_rotation(std::mt19937& rng)
{
    // Gram-Schmidt of two random directions; det = +1 by construction.
    glm::vec3 a = random_direction(rng), b = random_direction(rng);
    glm::vec3 x = glm::normalize(a), y = glm::normalize(b - x * glm::dot(x, b)), z = glm::cross(x, y);
    return glm::mat3(x, y, z);
}

// Closed-form band 3 functions (Sloan, "Stupid SH Tricks", appendix, Condon-Shortley phase), an
// evaluation independent of sh_eval's recurrences.
std::array<double, 7> band3(glm::dvec3 d)
{
    double x = d.x, y = d.y, z = d.z;
    return {-0.5900435899266435 * y * (3 * x * x - y * y), 2.890611442640554 * x * y * z,
            -0.4570457994644658 * y * (5 * z * z - 1),     0.3731763325901154 * z * (5 * z * z - 3),
            -0.4570457994644658 * x * (5 * z * z - 1),     1.445305721320277 * z * (x * x - y * y),
            -0.5900435899266435 * x * (x * x - 3 * y * y)};
}
} // namespace

TEST(ShEval, RecurrenceMatchesClosedFormsForBandsZeroToThree)
{
    std::mt19937 rng(3);
    for (int i = 0; i < 100; ++i)
    {
        glm::vec3 d = random_direction(rng);
        float y[16];
        sh_eval(4, d, y);
        Sh9 y9 = sh9_eval(d);
        for (int k = 0; k < 9; ++k)
            EXPECT_NEAR(y[k], y9[k], 1e-6f) << "index " << k;
        std::array<double, 7> y3 = band3(glm::dvec3(d));
        for (int m = -3; m <= 3; ++m)
            EXPECT_NEAR(y[sh_index(3, m)], y3[m + 3], 1e-5) << "y3," << m;
    }
}

namespace
{
// Gauss-Legendre nodes and weights on [-1, 1] by Newton's method on P_n (Bonnet's recursion), written here so
// that the orthonormality below shares no quadrature with the library.
void gauss_legendre_nodes(int n, std::vector<double>& x, std::vector<double>& w)
{
    x.assign(n, 0.0);
    w.assign(n, 0.0);
    for (int i = 0; i < n; ++i)
    {
        double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 0.0;
        for (int iter = 0; iter < 100; ++iter)
        {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; ++k)
            {
                const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            const double step = p1 / dp;
            z -= step;
            if (std::abs(step) < 1e-15)
                break;
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
}
} // namespace

// Every function of order 10 (the largest the library supports, bands 0-9) against every other: the Gram
// matrix by this file's own Gauss-Legendre x uniform-phi rule (exact for these degrees) is the identity.
TEST(ShEval, OrthonormalOverTheSphere)
{
    ASSERT_EQ(kMaxShOrder, 10);
    const int order = 10, n = sh_count(order), theta_steps = 16, phi_steps = 32;
    std::vector<double> zs, ws;
    gauss_legendre_nodes(theta_steps, zs, ws);
    std::vector<double> gram(size_t(n) * n, 0.0);
    float y[100];
    for (int t = 0; t < theta_steps; ++t)
        for (int p = 0; p < phi_steps; ++p)
        {
            const double z = zs[t], r = std::sqrt(1.0 - z * z), phi = 2.0 * M_PI * (p + 0.5) / phi_steps;
            sh_eval(order, glm::vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)), y);
            const double weight = ws[t] * 2.0 * M_PI / phi_steps;
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j)
                    gram[size_t(i) * n + j] += weight * double(y[i]) * y[j];
        }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            ASSERT_NEAR(gram[size_t(i) * n + j], i == j ? 1.0 : 0.0, 2e-5) << "<y" << i << ", y" << j << ">";
}

// A second formulation of the highest bands: the zonal functions sqrt((2l+1)/4pi) P_l(z) (Legendre by
// Bonnet's recursion) and the sectoral ones sqrt(2) K_ll (-1)^l (2l-1)!! sin^l(theta) {cos, sin}(l phi),
// for every band up to 9, at random directions.
TEST(ShEval, ZonalAndSectoralFunctionsMatchClosedFormsUpToBandNine)
{
    std::mt19937 rng(23);
    for (int trial = 0; trial < 50; ++trial)
    {
        const glm::vec3 d = random_direction(rng);
        float y[100];
        sh_eval(10, d, y);
        const double z = d.z, st = std::sqrt(double(d.x) * d.x + double(d.y) * d.y),
                     phi = std::atan2(d.y, d.x);
        double p0 = 1.0, p1 = z;
        for (int l = 0; l < 10; ++l)
        {
            const double pl = l == 0 ? 1.0 : (l == 1 ? z : 0.0);
            double legendre = pl;
            if (l >= 2)
            {
                const double p2 = ((2.0 * l - 1.0) * z * p1 - (l - 1.0) * p0) / l;
                p0 = p1;
                p1 = p2;
                legendre = p2;
            }
            EXPECT_NEAR(y[sh_index(l, 0)], std::sqrt((2 * l + 1) / (4 * M_PI)) * legendre, 2e-6)
                << "y" << l << ",0";
            if (l == 0)
                continue;
            double fact2l = 1.0, dfact = 1.0; // (2l)!, (2l-1)!!
            for (int i = 1; i <= 2 * l; ++i)
                fact2l *= i;
            for (int i = 1; i <= 2 * l - 1; i += 2)
                dfact *= i;
            const double k = std::sqrt(2.0 * (2 * l + 1) / (4 * M_PI) / fact2l) * (l % 2 ? -1.0 : 1.0) *
                             dfact * std::pow(st, l);
            EXPECT_NEAR(y[sh_index(l, l)], k * std::cos(l * phi), 2e-6) << "y" << l << "," << l;
            EXPECT_NEAR(y[sh_index(l, -l)], k * std::sin(l * phi), 2e-6) << "y" << l << "," << -l;
        }
    }
}

TEST(ShConvolution, FactorsMatchTheDesignTable)
{
    EXPECT_DOUBLE_EQ(clamped_cosine_factor(0), M_PI);
    EXPECT_DOUBLE_EQ(clamped_cosine_factor(1), 2 * M_PI / 3);
    EXPECT_NEAR(clamped_cosine_factor(2), M_PI / 4, 1e-15);
    EXPECT_EQ(clamped_cosine_factor(3), 0.0);
    EXPECT_NEAR(clamped_cosine_factor(4), -M_PI / 24, 1e-15);
    EXPECT_NEAR(clamped_cosine_factor(6), M_PI / 64, 1e-15); // Ramamoorthi & Hanrahan: A_6 = pi/64
}

// A single directional light of unit irradiance, L = delta(w - s): L_lm = y_lm(s). Its SH9 irradiance is
// the known clamped-cosine approximation E(n) = 1/4 + (1/2) cos + (5/16)(3 cos^2 - 1)/2 ... evaluated via
// the addition theorem: sum_m y_lm(s) y_lm(n) = (2l+1)/(4 pi) P_l(cos).
TEST(ShConvolution, DirectionalLightGivesTheKnownClampedCosineApproximation)
{
    std::mt19937 rng(5);
    for (int i = 0; i < 50; ++i)
    {
        glm::vec3 s = random_direction(rng), n = random_direction(rng);
        Sh9 ys = sh9_eval(s);
        Sh9Rgb L;
        for (int k = 0; k < 9; ++k)
            L[k] = glm::vec3(ys[k]);
        float E = sh9_eval_rgb(convolve_cosine(L), n).x;
        double c = glm::dot(s, n);
        double expect = 0.25 + 0.5 * c + 0.3125 * 0.5 * (3 * c * c - 1);
        EXPECT_NEAR(E, expect, 1e-5) << "cos " << c;
    }
    // Peak of the approximation, at n = s: 1/4 + 1/2 + 5/16 = 1.0625, from the library.
    for (const glm::vec3& s : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(-0.4f, 0.7f, 0.2f))})
    {
        Sh9 ys = sh9_eval(s);
        Sh9Rgb L;
        for (int k = 0; k < 9; ++k)
            L[k] = glm::vec3(ys[k]);
        EXPECT_NEAR(sh9_eval_rgb(convolve_cosine(L), s).x, 1.0625, 1e-5);
    }
}

TEST(ShRotation, RotatedCoefficientsEvaluateAtTheInverselyRotatedDirection)
{
    std::mt19937 rng(9);
    const int order = 8, n = sh_count(order);
    for (int trial = 0; trial < 20; ++trial)
    {
        glm::mat3 R = random_rotation(rng);
        std::vector<float> c(n), rc(n);
        for (float& v : c)
            v = std::uniform_real_distribution<float>(-1, 1)(rng);
        ShRotation rot(order, R);
        rot.apply(c, rc);
        for (int k = 0; k < 10; ++k)
        {
            glm::vec3 d = random_direction(rng);
            float y[64], yr[64];
            sh_eval(order, d, y);
            sh_eval(order, glm::transpose(R) * d, yr);
            // Band by band, so an error in one band's block is reported as that band.
            for (int l = 0; l < order; ++l)
            {
                double a = 0, b = 0;
                for (int m = -l; m <= l; ++m)
                {
                    a += rc[sh_index(l, m)] * y[sh_index(l, m)];
                    b += c[sh_index(l, m)] * yr[sh_index(l, m)];
                }
                ASSERT_NEAR(a, b, 1e-5) << "band " << l << " trial " << trial;
            }
        }
    }
}

TEST(ShRotation, RejectsBadInput)
{
    EXPECT_THROW(ShRotation(0, glm::mat3(1.0f)), std::invalid_argument);
    glm::mat3 bad(1.0f);
    bad[1][2] = std::nanf("");
    EXPECT_THROW(ShRotation(3, bad), std::invalid_argument);
    ShRotation r(3, glm::mat3(1.0f));
    std::vector<float> in(9), out(16);
    EXPECT_THROW(r.apply(in, out), std::invalid_argument);
}

TEST(ShWindow, WeightsStartAtOneAndDecrease)
{
    for (ShWindow w : {ShWindow::Hanning, ShWindow::Lanczos, ShWindow::Laplacian})
    {
        EXPECT_DOUBLE_EQ(sh_window_weight(w, 0, 6, 0.01), 1.0);
        for (int l = 1; l < 6; ++l)
            EXPECT_LT(sh_window_weight(w, l, 6, 0.01), sh_window_weight(w, l - 1, 6, 0.01));
    }
    EXPECT_NEAR(sh_window_weight(ShWindow::Hanning, 3, 6), 0.5, 1e-12);
    EXPECT_NEAR(sh_window_weight(ShWindow::Laplacian, 1, 6, 0.25), 0.5, 1e-12);
}

// The windows' closed forms (sh.h), here as the decimal values of order 6: Lanczos sinc(pi l / 6) =
// sin(pi l / 6) / (pi l / 6) and Hanning (1 + cos(pi l / 6)) / 2, band by band; apply_window scales every
// coefficient of band l by its band's weight.
TEST(ShWindow, LanczosAndHanningEqualTheirClosedForms)
{
    const double lanczos[6] = {
        1.0, 0.954929658551372, 0.826993343132688, 0.636619772367581, 0.413496671566344, 0.190985931710274};
    const double hanning[6] = {1.0, 0.933012701892219, 0.75, 0.5, 0.25, 0.066987298107781};
    for (int l = 0; l < 6; ++l)
    {
        EXPECT_NEAR(sh_window_weight(ShWindow::Lanczos, l, 6), lanczos[l], 1e-12) << "band " << l;
        EXPECT_NEAR(sh_window_weight(ShWindow::Hanning, l, 6), hanning[l], 1e-12) << "band " << l;
    }
    std::vector<glm::vec3> c(36, glm::vec3(1.0f, 2.0f, -3.0f));
    apply_window(c, ShWindow::Lanczos);
    for (int l = 0; l < 6; ++l)
        for (int m = -l; m <= l; ++m)
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(c[size_t(sh_index(l, m))][ch],
                            float(lanczos[l]) * (ch == 0   ? 1.0f
                                                 : ch == 1 ? 2.0f
                                                           : -3.0f),
                            1e-6f)
                    << "l " << l << " m " << m;
}
