// Environment-map projection: exact solid angles (white furnace), agreement with analytic projection of
// the same function, and the EXR path from a file.
#include <hemi/io/image.h>
#include <hemi/math/sh.h>
#include <hemi/math/sh_environment.h>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace hemi::math;

namespace
{
// A smooth, band-limited radiance (bands 0-2): any exact projection reproduces it.
glm::vec3 smooth(const glm::vec3& d)
{
    return glm::vec3(2.0f + d.z + d.x * d.y, 1.0f - 0.5f * d.x, 1.5f + 0.25f * d.y * d.z);
}

std::vector<float> equirect_of(uint32_t w, uint32_t h, glm::vec3 (*f)(const glm::vec3&))
{
    std::vector<float> px(size_t(w) * h * 4);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            // Blender's mapping, inverted: u = 0.5 - phi / 2pi, v (up) = 1 - theta / pi.
            double theta = M_PI * (y + 0.5) / h, phi = M_PI - 2 * M_PI * (x + 0.5) / w;
            glm::vec3 d(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                        float(std::cos(theta)));
            glm::vec3 l = f(d);
            float* p = &px[(size_t(y) * w + x) * 4];
            p[0] = l.x, p[1] = l.y, p[2] = l.z, p[3] = 1.0f;
        }
    return px;
}

std::vector<float> cubemap_of(uint32_t n, glm::vec3 (*f)(const glm::vec3&))
{
    std::vector<float> px(size_t(6) * n * n * 4);
    for (int face = 0; face < 6; ++face)
        for (uint32_t y = 0; y < n; ++y)
            for (uint32_t x = 0; x < n; ++x)
            {
                glm::vec3 l =
                    f(cubemap_direction(face, -1.0f + (2.0f * x + 1.0f) / n, -1.0f + (2.0f * y + 1.0f) / n));
                float* p = &px[((size_t(face) * n + y) * n + x) * 4];
                p[0] = l.x, p[1] = l.y, p[2] = l.z, p[3] = 1.0f;
            }
    return px;
}

glm::vec3 one(const glm::vec3&)
{
    return glm::vec3(1.0f);
}
} // namespace

TEST(EquirectProjection, ConstantEnvironmentGivesPiIrradiance)
{
    std::vector<glm::vec3> c = project_equirect(3, 64, 32, equirect_of(64, 32, one));
    EXPECT_NEAR(c[0].x, 2.0 * std::sqrt(M_PI), 1e-5); // integral of y00 over the sphere
    convolve_cosine(c);
    for (glm::vec3 n : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::normalize(glm::vec3(1, -2, 0.5f))})
        EXPECT_NEAR(sh_eval_rgb(c, n).y, M_PI, 2e-3) << n.x << "," << n.y << "," << n.z;
}

TEST(CubemapProjection, SolidAnglesCoverTheSphereAndGivePiIrradiance)
{
    double total = 0;
    const int n = 16;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            total += cubemap_solid_angle(-1 + 2.0 * x / n, -1 + 2.0 * y / n, -1 + 2.0 * (x + 1) / n,
                                         -1 + 2.0 * (y + 1) / n);
    EXPECT_NEAR(6 * total, 4 * M_PI, 1e-12);
    std::vector<glm::vec3> c = project_cubemap(3, n, cubemap_of(n, one));
    convolve_cosine(c);
    for (glm::vec3 d : {glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), glm::normalize(glm::vec3(-1, 2, 0.5f))})
        EXPECT_NEAR(sh_eval_rgb(c, d).x, M_PI, 2e-3);
}

// Both image layouts must agree with exact quadrature of the same function, which catches a mirrored
// face, a swapped axis or a wrong phi origin (each changes band-1 and band-2 coefficients).
TEST(EnvironmentProjection, ImagesAgreeWithAnalyticProjection)
{
    std::vector<glm::vec3> exact = project_sh(3, smooth, 32);
    std::vector<glm::vec3> eq = project_equirect(3, 256, 128, equirect_of(256, 128, smooth));
    std::vector<glm::vec3> cube = project_cubemap(3, 64, cubemap_of(64, smooth));
    for (int i = 0; i < 9; ++i)
        for (int ch = 0; ch < 3; ++ch)
        {
            EXPECT_NEAR(eq[i][ch], exact[i][ch], 2e-3) << "equirect coefficient " << i;
            EXPECT_NEAR(cube[i][ch], exact[i][ch], 2e-3) << "cube coefficient " << i;
        }
}

// A bright spot placed where Blender's world mapping puts direction d (Cycles' direction_to_equirectangular:
// u = 0.5 - atan2(d.y, d.x) / 2pi, v = 1 - acos(d.z) / pi, v measured up the image) must come out of the
// projection pointing along d: the linear band of SH is a dipole along the mean direction, (-c3, -c1, c2) in
// hemi's sign convention. A mirrored azimuth (the pre-Blender mapping) turns (x, y) into (x, -y).
TEST(EquirectProjection, BrightSpotLandsWhereBlenderShowsIt)
{
    const uint32_t w = 512, h = 256;
    for (glm::vec3 d :
         {glm::normalize(glm::vec3(0.3f, 0.8f, 0.4f)), glm::normalize(glm::vec3(-0.7f, -0.2f, -0.3f)),
          glm::normalize(glm::vec3(0.9f, -0.4f, 0.1f))})
    {
        const double u = 0.5 - std::atan2(double(d.y), double(d.x)) / (2 * M_PI);
        const double v = 1.0 - std::acos(double(d.z)) / M_PI;
        const int cx = int(u * w), cy = int((1.0 - v) * h); // image rows go down, Blender's v goes up
        std::vector<float> px(size_t(w) * h * 4, 0.0f);
        for (int y = cy - 1; y <= cy + 1; ++y)
            for (int x = cx - 1; x <= cx + 1; ++x)
                px[(size_t(y) * w + size_t((x + w) % w)) * 4] = 1000.0f;
        const std::vector<glm::vec3> c = project_equirect(2, w, h, px);
        const glm::vec3 dipole = glm::normalize(glm::vec3(-c[3].x, -c[1].x, c[2].x));
        EXPECT_GT(glm::dot(dipole, d), std::cos(glm::radians(1.0f)))
            << "spot for (" << d.x << ", " << d.y << ", " << d.z << ") came out along (" << dipole.x << ", "
            << dipole.y << ", " << dipole.z << ")";
    }
}

TEST(EnvironmentProjection, RejectsBadSizesAndNaN)
{
    std::vector<float> px = equirect_of(8, 4, one);
    EXPECT_THROW(project_equirect(3, 8, 5, px), std::invalid_argument);
    px[17] = std::nanf("");
    EXPECT_THROW(project_equirect(3, 8, 4, px), std::invalid_argument);
    EXPECT_THROW(project_cubemap(3, 4, std::vector<float>(5 * 16 * 4)), std::invalid_argument);
}

TEST(EquirectProjection, FromAnExrFile)
{
    auto path = std::filesystem::temp_directory_path() / "hemi_env_test.exr";
    hemi::io::ImageRgba img{128, 64, equirect_of(128, 64, smooth)};
    hemi::io::write_exr(path, img);
    hemi::io::ImageRgba back = hemi::io::read_exr(path);
    ASSERT_EQ(back.width, 128u);
    ASSERT_EQ(back.height, 64u);
    EXPECT_EQ(back.pixels, img.pixels); // float channels round-trip exactly
    std::vector<glm::vec3> c = project_equirect(3, back.width, back.height, back.pixels);
    std::vector<glm::vec3> exact = project_sh(3, smooth, 32);
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(c[i].x, exact[i].x, 5e-3) << i;
    std::filesystem::remove(path);
}
