// SH9 conventions and irradiance, checked against DESIGN.md's printed constants and against brute-force
// integration of the clamped cosine (an evaluation that shares no code with the SH path).
#include <hemi/math/sh.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>

using namespace hemi::math;

TEST(Sh9, MatchesTheConventionTable)
{
    glm::vec3 d = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
    Sh9 y = sh9_eval(d);
    const float x = d.x, yy = d.y, z = d.z;
    // DESIGN.md Sec. 3, to the printed 6 digits.
    EXPECT_NEAR(y[0], 0.282095f, 1e-6f);
    EXPECT_NEAR(y[1], -0.488603f * yy, 1e-6f);
    EXPECT_NEAR(y[2], 0.488603f * z, 1e-6f);
    EXPECT_NEAR(y[3], -0.488603f * x, 1e-6f);
    EXPECT_NEAR(y[4], 1.092548f * x * yy, 1e-6f);
    EXPECT_NEAR(y[5], -1.092548f * yy * z, 1e-6f);
    EXPECT_NEAR(y[6], 0.315392f * (3 * z * z - 1), 1e-6f);
    EXPECT_NEAR(y[7], -1.092548f * x * z, 1e-6f);
    EXPECT_NEAR(y[8], 0.546274f * (x * x - yy * yy), 1e-6f);
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

// E(n) = integral of L(w) max(0, n.w) dw by brute force, against the SH9 approximation. For a smooth
// environment SH9 irradiance is accurate to a few percent (Ramamoorthi & Hanrahan 2001); a sign error in
// any band-1 or band-2 function, or a wrong A_l, moves E by far more.
TEST(Sh9, IrradianceOfSmoothSkyMatchesBruteForce)
{
    AnalyticSky sky;
    sky.sun_color = glm::vec3(0.0f); // keep it smooth: SH9 is a low-pass of the irradiance
    sky.zenith = {0.1f, 0.3f, 1.2f};
    auto L = [&](const glm::vec3& d) { return sky.radiance(d) + glm::vec3(0.6f * std::max(0.0f, d.x), 0, 0); };
    Sh9Rgb e = convolve_cosine(project_sh9(L, 128));
    const int steps = 256;
    for (glm::vec3 n : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                        glm::normalize(glm::vec3(0.3f, -0.8f, 0.5f)), glm::normalize(glm::vec3(-0.5f, 0.5f, -0.2f))})
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
        glm::vec3 sh = sh9_eval_rgb(e, n);
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(sh[ch], brute[ch], 0.03 * brute[ch] + 0.01)
                << "normal " << n.x << "," << n.y << "," << n.z << " channel " << ch;
    }
}
