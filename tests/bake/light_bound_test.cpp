// The light bound of hemi-bake lightmap (bake/light_bound.h): an upper bound on the direct irradiance the
// lights give any point and normal, within 2x of the largest they can give. References: a sun's and a
// glTF directional light's own irradiance, pi L for a sky of radiance L, pi L_e for an emissive surface,
// I / d^2 for a point light at distance d from a floor, and for Blender's sunset.exr the irradiance summed
// here pixel by pixel at normals around the sun (independent of the bound's cells and cones).
#include "quads.h"

#include <hemi/bake/light_bound.h>
#include <hemi/io/image.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace
{

using hemi::bake::LightBound;
using hemi::bake::lightmap_light_bound;
using hemi::bake::LightmapLights;

// A 2 x 2 floor at z = 0.
hemi::io::Mesh floor_mesh()
{
    hemi::io::Mesh m;
    hemi::test::add_quad(m, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {0, 0, 1, 1});
    return m;
}

LightmapLights no_sky()
{
    LightmapLights l;
    l.uniform = glm::vec3(0.0f);
    return l;
}

// max_n sum_pixels L omega max(0, n . w) of an equirect image, at the pixels' centres (sh_environment.h's
// convention: phi = pi - 2 pi u, theta from +z), brightest channel, over 400 Fibonacci normals and then 400
// normals within 4 degrees of the best of them. A lower estimate of the true largest value.
double brute_force_largest_irradiance(const hemi::io::ImageRgba& env)
{
    struct Pixel
    {
        glm::dvec3 w, power;
    };
    std::vector<Pixel> pixels;
    for (uint32_t y = 0; y < env.height; ++y)
    {
        const double t0 = M_PI * y / env.height, t1 = M_PI * (y + 1) / env.height, t = 0.5 * (t0 + t1);
        const double omega = 2.0 * M_PI / env.width * (std::cos(t0) - std::cos(t1));
        for (uint32_t x = 0; x < env.width; ++x)
        {
            const float* p = env.at(x, y);
            const double phi = M_PI - 2.0 * M_PI * (x + 0.5) / env.width;
            if (p[0] > 0.0f || p[1] > 0.0f || p[2] > 0.0f)
                pixels.push_back({{std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)},
                                  glm::dvec3(p[0], p[1], p[2]) * omega});
        }
    }
    auto irradiance = [&](const glm::dvec3& n)
    {
        glm::dvec3 e(0.0);
        for (const Pixel& p : pixels)
            e += p.power * std::max(0.0, glm::dot(n, p.w));
        return std::max({e.x, e.y, e.z});
    };
    double best = 0.0;
    glm::dvec3 best_n(0, 0, 1);
    for (int i = 0; i < 400; ++i)
    {
        const double z = 1.0 - (2.0 * i + 1.0) / 400.0, r = std::sqrt(1.0 - z * z), a = 2.39996323 * i;
        const glm::dvec3 n(r * std::cos(a), r * std::sin(a), z);
        if (const double e = irradiance(n); e > best)
            best = e, best_n = n;
    }
    const glm::dvec3 t = glm::normalize(
        glm::cross(best_n, std::abs(best_n.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 b = glm::cross(best_n, t), centre = best_n;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j)
        {
            const double s = std::tan(4.0 * M_PI / 180.0) * (i / 9.5 - 1.0),
                         u = std::tan(4.0 * M_PI / 180.0) * (j / 9.5 - 1.0);
            best = std::max(best, irradiance(glm::normalize(centre + s * t + u * b)));
        }
    return best;
}

} // namespace

// Delta lights give their own irradiance, exactly; a uniform sky pi L (the bound within 15% above it); the
// sum of the two is bounded by the sum; an emissive material pi L_e; each named.
TEST(LightBound, SunSkyAndEmissionGiveTheirIrradiance)
{
    const hemi::io::Mesh floor = floor_mesh();
    LightmapLights l = no_sky();
    l.sun = true;
    l.sun_irradiance = {3.0f, 5.0f, 4.0f};
    LightBound b = lightmap_light_bound(l, {}, floor);
    EXPECT_DOUBLE_EQ(b.total, 5.0);
    ASSERT_NE(b.largest(), nullptr);
    EXPECT_EQ(b.largest()->name, "the sun (--sun)");

    l.uniform = glm::vec3(0.7f);
    b = lightmap_light_bound(l, {}, floor);
    EXPECT_GE(b.total, 5.0 + M_PI * 0.7 * (1.0 - 1e-6));
    EXPECT_LE(b.total, 5.0 + M_PI * 0.7 * 1.15);

    // The same sky as an image: the bound sums its pixels' light over cells and cones.
    LightmapLights image = no_sky();
    image.environment = {64, 32, std::vector<float>(64 * 32 * 4, 0.7f)};
    image.environment_name = "grey.exr";
    b = lightmap_light_bound(image, {}, floor);
    std::printf("uniform sky of 0.7 as a 64 x 32 image: bound %.5f, pi L = %.5f\n", b.total, M_PI * 0.7);
    EXPECT_GE(b.total, M_PI * 0.7 * (1.0 - 1e-6));
    EXPECT_LE(b.total, M_PI * 0.7 * 1.15);
    EXPECT_NE(b.largest()->name.find("grey.exr"), std::string::npos);
    image.environment_scale = 2.0f;
    EXPECT_NEAR(lightmap_light_bound(image, {}, floor).total, 2.0 * b.total, 1e-9 * b.total);

    hemi::io::Material lamp;
    lamp.name = "lamp";
    lamp.emissive_factor = {2.0f, 6.0f, 1.0f};
    b = lightmap_light_bound(no_sky(), {hemi::io::Material{}, lamp}, floor);
    EXPECT_DOUBLE_EQ(b.total, 6.0 * M_PI);
    EXPECT_EQ(b.largest()->name, "the emissive material 'lamp'");
}

// glTF lights: a directional light gives its lux; a point light of 100 cd 2 m above the floor's centre gives
// 100 / 4 at the floor, and 100 / 5 when it stands 2 m beyond the floor's edge and 1 m up (the floor's
// nearest point is then sqrt(5) away); glTF's range window applies at that distance.
TEST(LightBound, PunctualLightsAtTheirNearestReceiver)
{
    const hemi::io::Mesh floor = floor_mesh();
    LightmapLights l = no_sky();
    hemi::io::PunctualLight sun;
    sun.type = hemi::io::PunctualLight::Type::Directional;
    sun.name = "Daylight";
    sun.intensity = 1e5f;
    sun.color = {1.0f, 0.9f, 0.8f};
    l.punctual = {sun};
    LightBound b = lightmap_light_bound(l, {}, floor);
    EXPECT_DOUBLE_EQ(b.total, 1e5);
    EXPECT_EQ(b.largest()->name, "the glTF directional light 'Daylight' (lux)");

    hemi::io::PunctualLight bulb;
    bulb.name = "bulb";
    bulb.intensity = 100.0f;
    bulb.position = {0.0f, 0.0f, 2.0f};
    l.punctual = {bulb};
    EXPECT_DOUBLE_EQ(lightmap_light_bound(l, {}, floor).total, 25.0);
    bulb.position = {3.0f, 0.0f, 1.0f}; // 2 beyond the edge x = 1, 1 above: distance sqrt(5)
    l.punctual = {bulb};
    EXPECT_NEAR(lightmap_light_bound(l, {}, floor).total, 20.0, 1e-9);
    bulb.range = 4.0f;
    l.punctual = {bulb};
    EXPECT_NEAR(lightmap_light_bound(l, {}, floor).total, 20.0 * (1.0 - std::pow(std::sqrt(5.0) / 4.0, 4.0)),
                1e-6);
    bulb.type = hemi::io::PunctualLight::Type::Spot;
    l.punctual = {bulb};
    EXPECT_NE(lightmap_light_bound(l, {}, floor).largest()->name.find("spot light 'bulb'"),
              std::string::npos);
}

// Blender's sunset.exr (a sun pixel of 6,520 in a 1024 x 512 world): pi times its brightest pixel is
// 2.05e4, about 5,000 times what it gives; the bound is within 2x of the irradiance summed pixel by pixel
// (3.87 in its brightest channel, red), and never below it.
TEST(LightBound, BlendersSunsetIsBoundedByWhatItGives)
{
    const std::filesystem::path hdri = "/usr/share/blender/datafiles/studiolights/world/sunset.exr";
    ASSERT_TRUE(std::filesystem::exists(hdri)) << "cmake/install_deps.sh installs blender-data";
    LightmapLights l;
    l.environment = hemi::io::read_exr(hdri);
    hemi::io::clamp_negative_radiance(l.environment, hdri.string()); // as hemi-bake reads it
    l.environment_name = hdri.filename().string();
    const double bound = lightmap_light_bound(l, {}, floor_mesh()).total;
    const double summed = brute_force_largest_irradiance(l.environment);
    std::printf("sunset.exr: largest irradiance summed pixel by pixel %.4f, the bound %.4f (%.3fx)\n", summed,
                bound, bound / summed);
    const float brightest = *std::max_element(l.environment.pixels.begin(), l.environment.pixels.end());
    EXPECT_GT(brightest, 6000.0f) << "the sun pixel";
    EXPECT_LT(summed, 5.0) << "far below pi times the sun pixel, the bound that refused this file";
    EXPECT_GE(bound, summed);
    EXPECT_LE(bound, 2.0 * summed);
}
