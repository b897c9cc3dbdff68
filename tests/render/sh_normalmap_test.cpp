// The sh_normalmap sample's frame: not blank, white furnace exact, and the GPU's shading equal to a CPU
// evaluation of the same material (analytic sphere frame, bilinear normal-map lookup, SH9 irradiance)
// at the UV the GPU reports for each sampled pixel.
#include "../gpu_fixture.h"

#include "normal_map_lookup.h"
#include "scene.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>

namespace
{

class ShNormalMapSample : public hemi::test::GpuTest
{
};

// `bitangent_sign` -1 is the wrong frame (a flipped bitangent), used to show the comparison would catch it.
glm::vec3 cpu_shade(const hemi::samples::ShNormalMapScene& s, glm::vec2 uv, float bitangent_sign = 1.0f)
{
    float phi = 2.0f * float(M_PI) * uv.x, theta = float(M_PI) * uv.y;
    glm::vec3 N(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    glm::vec3 T(-std::sin(phi), std::cos(phi), 0.0f);
    glm::vec3 B =
        -glm::vec3(std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), -std::sin(theta));
    glm::vec3 nt = glm::normalize(hemi::test::sample_bilinear(s, uv) * 2.0f - 1.0f);
    glm::vec3 n = glm::normalize(T * nt.x + bitangent_sign * B * nt.y + N * nt.z);
    return s.albedo * hemi::math::sh9_eval_rgb(s.irradiance, n) / float(M_PI);
}

} // namespace

TEST_F(ShNormalMapSample, ImageIsNotBlankAndMatchesCpuShading)
{
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Sky);
    const uint32_t W = 240, H = 180;
    hemi::io::ImageRgba aux;
    hemi::io::ImageRgba color = hemi::samples::render_sh_normalmap(hemi::test::device(), scene, W, H, &aux);

    size_t covered = 0;
    double sum = 0, sum2 = 0;
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x)
            if (aux.at(x, y)[3] == 1.0f)
            {
                ++covered;
                double l = color.at(x, y)[1];
                sum += l;
                sum2 += l * l;
            }
            else
                EXPECT_EQ(color.at(x, y)[3], 0.0f) << "background pixel " << x << "," << y << " was drawn";
    ASSERT_GT(covered, size_t(W * H / 5)) << "the sphere covers too little of the image";
    double mean = sum / covered, stddev = std::sqrt(std::max(0.0, sum2 / covered - mean * mean));
    EXPECT_GT(mean, 0.1);
    EXPECT_GT(stddev, 0.02) << "no shading variation: normal map or lighting missing";

    int compared = 0, failures = 0, flipped_rejected = 0;
    for (uint32_t y = 2; y + 2 < H; y += 5)
        for (uint32_t x = 2; x + 2 < W; x += 5)
        {
            glm::vec2 uv;
            if (!hemi::test::comparable_sphere_pixel(aux, x, y, uv))
                continue; // silhouettes (interpolated frames), poles (degenerate tangents), seam
            glm::vec3 want = cpu_shade(scene, uv);
            const float* got = color.at(x, y);
            ++compared;
            // The same comparison against a flipped bitangent: it must reject many pixels, or the tolerance
            // could not tell the right frame from the wrong one.
            const glm::vec3 flipped = cpu_shade(scene, uv, -1.0f);
            bool flipped_fails = false;
            for (int c = 0; c < 3; ++c)
                flipped_fails = flipped_fails || std::abs(got[c] - flipped[c]) > 0.02f * flipped[c] + 0.004f;
            flipped_rejected += flipped_fails;
            for (int c = 0; c < 3; ++c)
                if (std::abs(got[c] - want[c]) > 0.02f * want[c] + 0.004f && failures++ < 10)
                    ADD_FAILURE() << "pixel " << x << "," << y << " uv " << uv.x << "," << uv.y << " channel "
                                  << c << ": GPU " << got[c] << ", CPU " << want[c];
        }
    EXPECT_GT(compared, 300);
    EXPECT_GT(flipped_rejected, compared / 10) << "a flipped bitangent would pass this comparison";
    RecordProperty("flipped_bitangent_rejected",
                   std::to_string(flipped_rejected) + "/" + std::to_string(compared));
}

// Constant environment L = 1: E = pi for every normal, so every covered pixel is exactly the albedo,
// whatever the normal map does: to 1e-5 of the albedo on the 32-bit float target.
TEST_F(ShNormalMapSample, WhiteFurnaceRendersTheAlbedo)
{
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Uniform);
    hemi::io::ImageRgba aux;
    hemi::io::ImageRgba color = hemi::samples::render_sh_normalmap(hemi::test::device(), scene, 96, 96, &aux);
    size_t covered = 0;
    double worst = 0.0;
    for (uint32_t y = 0; y < 96; ++y)
        for (uint32_t x = 0; x < 96; ++x)
            if (aux.at(x, y)[3] == 1.0f)
            {
                ++covered;
                for (int c = 0; c < 3; ++c)
                {
                    worst = std::max(worst,
                                     double(std::abs(color.at(x, y)[c] - scene.albedo[c]) / scene.albedo[c]));
                    ASSERT_NEAR(color.at(x, y)[c], scene.albedo[c], 1e-5f * scene.albedo[c]) << x << "," << y;
                }
            }
    char value[32];
    std::snprintf(value, sizeof value, "%.3g", worst);
    RecordProperty("furnace_worst_relative", value);
    EXPECT_GT(covered, 1000u);
}
