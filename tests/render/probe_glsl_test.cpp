// The GLSL library's probe lookup (hemi_probe_irradiance, hemi/lib/probes.glsl) and the reflection probes'
// box projection (hemi_box_projected_direction, against math::box_projected_direction), run by a compute
// shader (tests/shaders/probe_lookup.comp) over the texel buffer io::probe_texels() packs, held to the C++
// lookup (io::LightProbes::at and occlusion_at, written separately) at points in and around a grid whose
// probes see walls at various distances: the same weights, the same visibility, the same folds of the
// octahedral maps.
#include "../gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>
#include <hemi/io/light_probes.h>
#include <hemi/math/box_projection.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace
{
using namespace hemi;

class ProbeGlsl : public test::GpuTest
{
};

// A 4 x 3 x 2 grid over [0, 3] x [0, 2] x [0, 1], two probes invalid, each probe's depth map a smooth
// function of direction (means 0.2 to 1.6 around the 1-unit cells, deviations 0.02 to 0.3), so that points
// in a cell see some probes and not others, with mixed lights' occlusion.
io::LightProbes probes()
{
    io::LightProbes p;
    p.count = glm::uvec3(4, 3, 2);
    p.lo = glm::vec3(0.0f);
    p.hi = glm::vec3(3.0f, 2.0f, 1.0f);
    p.depth_resolution = 8;
    p.max_distance = 2.6f;
    const size_t n = 24;
    for (size_t i = 0; i < n; ++i)
    {
        std::array<glm::vec3, 9> sh;
        for (size_t j = 0; j < 9; ++j)
            sh[j] = glm::vec3(std::sin(float(i * 9 + j)), std::cos(float(i * 5 + j * 3)),
                              0.1f * float(j) + float(i % 5));
        p.irradiance.push_back(sh);
        p.valid.push_back(i == 5 || i == 18 ? 0 : 1);
        p.occlusion.push_back({float(i % 7) / 6.0f, 1.0f, float(i % 3) / 2.0f, 0.25f});
        for (uint32_t y = 0; y < 8; ++y)
            for (uint32_t x = 0; x < 8; ++x)
            {
                const glm::vec3 d = io::octahedral_decode(glm::vec2(x + 0.5f, y + 0.5f) / 8.0f);
                const float mean = 0.9f + 0.7f * std::sin(3.0f * d.x + 2.0f * d.y + float(i)) * d.z;
                p.depth.emplace_back(mean, 0.02f + 0.28f * (0.5f + 0.5f * std::cos(float(i) + 4.0f * d.y)));
            }
    }
    return p;
}

// The same probes, scattered: 60 probes at random points of [0, 3] x [0, 2] x [0, 1] with reaches 0.5 to
// 1.3 and the same kinds of depth maps, three of them invalid.
io::LightProbes scattered_probes()
{
    io::LightProbes p = probes();
    uint32_t seed = 5;
    auto random = [&seed] { return float((seed = seed * 1664525u + 1013904223u) >> 8) / float(1u << 24); };
    const io::LightProbes grid = p;
    p.irradiance.clear();
    p.valid.clear();
    p.occlusion.clear();
    p.depth.clear();
    p.lo = glm::vec3(INFINITY);
    p.hi = glm::vec3(-INFINITY);
    for (size_t i = 0; i < 60; ++i)
    {
        const glm::vec3 at(random() * 3.0f, random() * 2.0f, random());
        p.points.emplace_back(at, 0.5f + 0.8f * random());
        p.lo = glm::min(p.lo, at);
        p.hi = glm::max(p.hi, at);
        const size_t from = i % 24; // another grid probe's values
        p.irradiance.push_back(grid.irradiance[from]);
        p.valid.push_back(i == 7 || i == 30 || i == 41 ? 0 : 1);
        p.occlusion.push_back(grid.occlusion[from]);
        p.depth.insert(p.depth.end(), grid.depth.begin() + ptrdiff_t(from * 64),
                       grid.depth.begin() + ptrdiff_t(from * 64 + 64));
    }
    p.count = glm::uvec3(60, 1, 1);
    return p;
}

// hemi_probe_irradiance at each point over io::probe_texels(probes): per point 9 SH9 coefficients, the
// occlusion, then the box projection's direction and influence.
std::vector<glm::vec4> shader_lookup(const io::LightProbes& grid, const std::vector<glm::vec4>& points)
{
    gpu::Device& dev = test::device();
    const std::vector<glm::vec4> texels = io::probe_texels(grid);

    const std::vector<gpu::Binding> bindings = {
        {0, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
        {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
        {2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT}};
    const gpu::Program program =
        gpu::create_compute_program(dev, {test::test_spirv("probe_lookup.comp"), bindings, 4, {}});
    const size_t texel_bytes = texels.size() * sizeof(glm::vec4),
                 point_bytes = points.size() * sizeof(glm::vec4),
                 out_bytes = points.size() * 11 * sizeof(glm::vec4);
    const gpu::Buffer probe_buffer =
        gpu::create_buffer(dev, {texel_bytes, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
    gpu::write_buffer(dev, probe_buffer, texels.data(), texel_bytes);
    const gpu::BufferView view =
        gpu::create_buffer_view(dev, probe_buffer.handle(), VK_FORMAT_R32G32B32A32_SFLOAT, 0, texel_bytes);
    const gpu::Buffer in = gpu::create_buffer(dev, {point_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    gpu::write_buffer(dev, in, points.data(), point_bytes);
    const gpu::Buffer out = gpu::create_buffer(dev, {out_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    const gpu::DescriptorPool pool = gpu::create_descriptor_pool(dev, bindings, 1);
    const VkDescriptorSet set = gpu::allocate_descriptor_set(dev, pool, program.set_layout);
    gpu::DescriptorWrite writes[3];
    writes[0].binding = 0;
    writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    writes[0].texel_view = view.get();
    writes[1] = {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, {in.handle(), 0, VK_WHOLE_SIZE}};
    writes[2] = {2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, {out.handle(), 0, VK_WHOLE_SIZE}};
    gpu::write_descriptors(dev, set, writes);
    const uint32_t push = uint32_t(points.size());
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.pipeline);
                      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.layout, 0, 1, &set,
                                              0, nullptr);
                      vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof push, &push);
                      vkCmdDispatch(cmd, uint32_t(points.size() + 63) / 64, 1, 1);
                  });
    std::vector<glm::vec4> values(points.size() * 11);
    gpu::read_buffer(dev, out, values.data(), out_bytes);
    return values;
}

std::vector<glm::vec4> random_points(uint32_t seed, int count)
{
    std::vector<glm::vec4> points;
    auto random = [&seed] { return float((seed = seed * 1664525u + 1013904223u) >> 8) / float(1u << 24); };
    for (int i = 0; i < count; ++i) // in the grid and up to half a cell around it
        points.emplace_back(random() * 4.0f - 0.5f, random() * 3.0f - 0.5f, random() * 2.0f - 0.5f, 0.0f);
    return points;
}

} // namespace

TEST_F(ProbeGlsl, TheShadersLookupIsTheLibrarysCpuLookup)
{
    const io::LightProbes grid = probes();
    ASSERT_EQ(io::light_probes_problem(grid), "");
    ASSERT_EQ(io::probe_texels(grid).size(), io::kProbeTexelHeader + 24 * io::probe_texel_stride(8));
    const std::vector<glm::vec4> points = random_points(11, 2000);
    const std::vector<glm::vec4> values = shader_lookup(grid, points);

    double worst = 0.0;
    int occluded = 0; // points where some probe of the cell sees under 1% of the point
    for (size_t i = 0; i < points.size(); ++i)
    {
        const glm::vec3 p(points[i]);
        const std::array<glm::vec3, 9> want = grid.at(p);
        const std::array<float, 4> occlusion = grid.occlusion_at(p);
        const io::LightProbes::Blend b = grid.blend(p);
        for (size_t n = 0; n < b.count(); ++n)
            if (grid.visibility(b.probe[n], p) < 0.01f)
            {
                ++occluded;
                break;
            }
        for (size_t j = 0; j < 9; ++j)
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, double(std::abs(values[i * 11 + j][c] - want[j][c])));
        for (int c = 0; c < 4; ++c)
            worst = std::max(worst, double(std::abs(values[i * 11 + 9][c] - occlusion[size_t(c)])));
    }
    double worst_direction = 0.0;
    int fading = 0;
    for (size_t i = 0; i < points.size(); ++i)
    {
        const glm::vec3 p(points[i]), r = glm::normalize(p - glm::vec3(1.3f, 0.8f, 0.4f));
        const glm::vec3 want = math::box_projected_direction(
            p, r, glm::vec3(-0.5f), glm::vec3(3.5f, 2.5f, 1.5f), glm::vec3(1.5f, 1.0f, 0.5f));
        worst_direction =
            std::max(worst_direction, double(glm::distance(glm::vec3(values[i * 11 + 10]), want)));
        const float influence = math::box_influence(p, glm::vec3(0.0f), glm::vec3(3.0f, 2.0f, 1.0f), 0.3f);
        worst_direction = std::max(worst_direction, double(std::abs(values[i * 11 + 10].w - influence)));
        fading += influence > 0.0f && influence < 1.0f;
    }
    EXPECT_GT(fading, 200) << "the points no longer cross the influence's fade";
    std::printf(
        "the shader's box projection and influence against the CPU's: largest difference %.2e (%d points "
        "in the fade)\n",
        worst_direction, fading);
    EXPECT_LT(worst_direction, 1e-4);
    std::printf("the shader's probe lookup against the CPU's: largest difference %.2e over %zu points, %d of "
                "them with a probe that does not see them\n",
                worst, points.size(), occluded);
    EXPECT_LT(worst, 1e-4); // values of magnitude up to 5: float rounding of the weights
    EXPECT_GT(occluded, 200) << "the grid no longer exercises visibility";
}

// Scattered probes through the index the texels carry: the same as the CPU's lookup over every probe
// (LightProbes::at without an index, which visits all 60), and the CPU's lookup through index_probes the
// same to the bit; where no valid probe reaches a point, the shader's zero and occlusion 1.
TEST_F(ProbeGlsl, ScatteredProbesThroughTheIndexAreEveryProbesBlend)
{
    const io::LightProbes scattered = scattered_probes();
    ASSERT_EQ(io::light_probes_problem(scattered), "");
    const io::ProbeIndex index = io::index_probes(scattered);
    const std::vector<glm::vec4> points = random_points(23, 3000);
    const std::vector<glm::vec4> values = shader_lookup(scattered, points);
    double worst = 0.0;
    int uncovered = 0, blended = 0, occluded = 0;
    for (size_t i = 0; i < points.size(); ++i)
    {
        const glm::vec3 p(points[i]);
        bool reached = false;
        for (size_t q = 0; q < scattered.size(); ++q)
            reached |= scattered.valid[q] &&
                       glm::distance(glm::vec3(scattered.points[q]), p) < scattered.points[q].w;
        const std::array<glm::vec3, 9> want = scattered.at(p), indexed = scattered.at(p, &index);
        for (size_t j = 0; j < 9; ++j)
            ASSERT_EQ(indexed[j], want[j]) << "point " << i;
        const io::LightProbes::Blend b = scattered.blend(p);
        if (!reached)
        {
            ++uncovered;
            for (size_t j = 0; j < 10; ++j)
                EXPECT_EQ(values[i * 11 + j], j < 9 ? glm::vec4(0.0f) : glm::vec4(1.0f)) << "point " << i;
            continue;
        }
        blended += b.count() > 1;
        for (size_t n = 0; n < b.count(); ++n)
            if (scattered.visibility(b.probe[n], p) < 0.01f)
            {
                ++occluded;
                break;
            }
        const std::array<float, 4> occlusion = scattered.occlusion_at(p);
        for (size_t j = 0; j < 9; ++j)
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, double(std::abs(values[i * 11 + j][c] - want[j][c])));
        for (int c = 0; c < 4; ++c)
            worst = std::max(worst, double(std::abs(values[i * 11 + 9][c] - occlusion[size_t(c)])));
    }
    std::printf("scattered probes, the shader against the CPU: largest difference %.2e over %zu points (%d "
                "blending several probes, %d with one that does not see them, %d beyond every reach)\n",
                worst, points.size(), blended, occluded, uncovered);
    EXPECT_LT(worst, 1e-4);
    EXPECT_GT(blended, 1500) << "the points no longer blend scattered probes";
    EXPECT_GT(occluded, 200) << "the probes no longer exercise visibility";
    EXPECT_GT(uncovered, 20) << "no point lies beyond every probe's reach";
}
