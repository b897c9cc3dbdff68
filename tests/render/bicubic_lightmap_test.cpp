// The GLSL library's bicubic lightmap lookups (hemi_lightmap_coefficients_bicubic,
// hemi/lib/coefficients.glsl), paged and plain, run by a compute shader (tests/shaders/lightmap_lookup.comp)
// at a list of UVs and held to an independent CPU evaluation of the same math: the uniform cubic B-spline
// over the texels, written out here from its four weights and the texels' values with the atlas's edge
// clamped (not the GPU's four-linear-lookup form). And the reason to have it: where texels follow a smooth
// curve, the linear lookup's slope jumps at every texel centre (a crease of the whole second difference),
// the B-spline's does not. The bounds hold on devices that filter with 8-bit sub-texel weights or finer
// (subTexelPrecisionBits; lavapipe filters in float): 1e-3 relative, the creases 3% of a texel's curvature.
#include "../gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/material_system.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace
{
using namespace hemi;

class BicubicLightmap : public test::GpuTest
{
};

// A 150 x 100 atlas (3 x 2 pages of 64^2), K = 2 coefficients, smooth in both axes; coefficient 0's red is
// a cosine of period 24 texels along x (gentle slopes, for 8-bit filter weights; curved at its crests).
constexpr uint32_t kW = 150, kH = 100, kK = 2;

glm::vec3 texel(uint32_t k, int64_t x, int64_t y)
{
    x = std::clamp<int64_t>(x, 0, kW - 1); // the atlas's edge clamped, as the samplers do
    y = std::clamp<int64_t>(y, 0, kH - 1);
    const float u = float(x) / kW, v = float(y) / kH;
    if (k == 0)
        return {0.5f + 0.25f * std::cos(float(2.0 * M_PI) * float(x) / 24.0f), 0.25f + 0.7f * v,
                0.5f + 0.3f * std::sin(float(x) / 7.0f) * std::cos(float(y) / 5.0f)};
    return {0.3f + 0.5f * u * v, 0.9f - 0.6f * u, 0.4f + 0.2f * std::cos(float(x + y) / 9.0f)};
}

// The cubic B-spline's weights of the four texels around t (texel units, centres at i + 0.5): texels
// floor(t - 0.5) - 1 .. + 2.
void bspline(double t, int64_t& first, double w[4])
{
    const double s = t - 0.5, i = std::floor(s), f = s - i;
    first = int64_t(i) - 1;
    w[0] = (1 - f) * (1 - f) * (1 - f) / 6;
    w[1] = (3 * f * f * f - 6 * f * f + 4) / 6;
    w[2] = (-3 * f * f * f + 3 * f * f + 3 * f + 1) / 6;
    w[3] = f * f * f / 6;
}

glm::dvec3 cpu_bicubic(uint32_t k, glm::vec2 uv, uint32_t w, uint32_t h)
{
    int64_t x0, y0;
    double wx[4], wy[4];
    bspline(double(std::clamp(uv.x, 0.0f, 1.0f)) * w, x0, wx);
    bspline(double(std::clamp(uv.y, 0.0f, 1.0f)) * h, y0, wy);
    glm::dvec3 sum(0.0);
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i)
            sum += wx[i] * wy[j] * glm::dvec3(texel(k, x0 + i, y0 + j));
    return sum;
}

glm::dvec3 cpu_bilinear(uint32_t k, glm::vec2 uv, uint32_t w, uint32_t h)
{
    const double tx = double(std::clamp(uv.x, 0.0f, 1.0f)) * w - 0.5,
                 ty = double(std::clamp(uv.y, 0.0f, 1.0f)) * h - 0.5;
    const int64_t x = int64_t(std::floor(tx)), y = int64_t(std::floor(ty));
    const double fx = tx - double(x), fy = ty - double(y);
    return (1 - fx) * (1 - fy) * glm::dvec3(texel(k, x, y)) + fx * (1 - fy) * glm::dvec3(texel(k, x + 1, y)) +
           (1 - fx) * fy * glm::dvec3(texel(k, x, y + 1)) + fx * fy * glm::dvec3(texel(k, x + 1, y + 1));
}

// The lookups of one kind (the shader's constant 0) at `uvs`: K vec3 per UV.
struct Lookups
{
    gpu::Device& dev;
    const render::TexelCoefficients& paged;
    const gpu::Image& plain;
    VkSampler plain_sampler;

    std::vector<glm::vec3> run(uint32_t lookup, uint32_t k, const std::vector<glm::vec2>& uvs) const
    {
        const std::vector<gpu::Binding> bindings = {
            {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_COMPUTE_BIT},
            {1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_COMPUTE_BIT},
            {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_COMPUTE_BIT},
            {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
            {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT}};
        const gpu::Program program = gpu::create_compute_program(
            dev, {test::test_spirv("lightmap_lookup.comp"), bindings, 4, {lookup, k}});
        const gpu::Buffer in =
            gpu::create_buffer(dev, {uvs.size() * sizeof(glm::vec2), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        gpu::write_buffer(dev, in, uvs.data(), uvs.size() * sizeof(glm::vec2));
        const size_t out_bytes = uvs.size() * k * 16;
        const gpu::Buffer out = gpu::create_buffer(dev, {out_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        const gpu::DescriptorPool pool = gpu::create_descriptor_pool(dev, bindings, 1);
        const VkDescriptorSet set = gpu::allocate_descriptor_set(dev, pool, program.set_layout);
        gpu::DescriptorWrite writes[5];
        const VkImageLayout read = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
        writes[0] = {
            0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, {}, {paged.sampler(), paged.pages().view(), read}};
        writes[1] = {1,
                     VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                     {},
                     {paged.table_sampler(), paged.page_table().view(), read}};
        writes[2] = {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, {}, {plain_sampler, plain.view(), read}};
        writes[3] = {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, {in.handle(), 0, VK_WHOLE_SIZE}};
        writes[4] = {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, {out.handle(), 0, VK_WHOLE_SIZE}};
        gpu::write_descriptors(dev, set, writes);
        const uint32_t count = uint32_t(uvs.size());
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.pipeline);
                          vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.layout, 0, 1,
                                                  &set, 0, nullptr);
                          vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, 4, &count);
                          vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
                      });
        std::vector<glm::vec4> values(uvs.size() * k);
        gpu::read_buffer(dev, out, values.data(), out_bytes);
        std::vector<glm::vec3> rgb;
        for (const glm::vec4& v : values)
            rgb.emplace_back(v);
        return rgb;
    }
};

} // namespace

TEST_F(BicubicLightmap, EqualsTheCpuBSplineAndHasNoCreaseWhereTheLinearLookupHasOne)
{
    gpu::Device& dev = test::device();
    render::MaterialSystem system(dev);
    gpu::UploadBatch upload(dev);
    std::vector<float> rgb(size_t(kK) * kW * kH * 3);
    for (uint32_t k = 0; k < kK; ++k)
        for (uint32_t y = 0; y < kH; ++y)
            for (uint32_t x = 0; x < kW; ++x)
                for (int c = 0; c < 3; ++c)
                    rgb[((size_t(k) * kH + y) * kW + x) * 3 + c] = texel(k, x, y)[c];
    const render::TexelCoefficients paged(system, kW, kH, kK, rgb, upload, /*full_precision=*/true);
    upload.submit_and_wait();
    // The plain layout: coefficient 0 alone (K = 1, one RGBA32F layer).
    const gpu::Image plain = gpu::create_image(
        dev, {kW, kH, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT, 1, 1, true});
    std::vector<glm::vec4> texels(size_t(kW) * kH);
    for (uint32_t y = 0; y < kH; ++y)
        for (uint32_t x = 0; x < kW; ++x)
            texels[size_t(y) * kW + x] = glm::vec4(texel(0, x, y), 0.0f);
    gpu::upload_image(dev, plain, texels.data(), texels.size() * sizeof(glm::vec4),
                      VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    const gpu::Sampler sampler = gpu::create_sampler(
        dev, {VK_FILTER_LINEAR, VK_SAMPLER_MIPMAP_MODE_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, 0.0f});
    const Lookups lookups{dev, paged, plain, sampler.get()};

    // Random UVs over the atlas and a little past its edges, and UVs on the page borders (x = 64, 128;
    // y = 64), where the four linear lookups of one point fall in different pages.
    std::vector<glm::vec2> uvs;
    uint32_t seed = 7;
    auto random = [&seed] { return float((seed = seed * 1664525u + 1013904223u) >> 8) / float(1u << 24); };
    for (int i = 0; i < 4000; ++i)
        uvs.emplace_back(random() * 1.04f - 0.02f, random() * 1.04f - 0.02f);
    for (float t = -3.0f; t <= 3.0f; t += 0.125f)
    {
        uvs.emplace_back((64.0f + t) / kW, random());
        uvs.emplace_back((128.0f + t) / kW, random());
        uvs.emplace_back(random(), (64.0f + t) / kH);
    }
    struct Case
    {
        uint32_t lookup, k;
        bool bicubic;
        const char* name;
    };
    for (const Case& c : {Case{0, kK, false, "paged linear"}, Case{1, kK, true, "paged bicubic"},
                          Case{2, 1, false, "plain linear"}, Case{3, 1, true, "plain bicubic"}})
    {
        const std::vector<glm::vec3> gpu = lookups.run(c.lookup, c.k, uvs);
        double worst = 0.0;
        for (size_t i = 0; i < uvs.size(); ++i)
            for (uint32_t k = 0; k < c.k; ++k)
            {
                const glm::dvec3 want =
                    c.bicubic ? cpu_bicubic(k, uvs[i], kW, kH) : cpu_bilinear(k, uvs[i], kW, kH);
                for (int ch = 0; ch < 3; ++ch)
                    worst = std::max(worst,
                                     std::abs(double(gpu[i * c.k + k][ch]) - want[ch]) / std::abs(want[ch]));
            }
        std::printf("%s: worst relative difference from the CPU %.2e over %zu lookups\n", c.name, worst,
                    uvs.size());
        EXPECT_LT(worst, 1e-3) << c.name;
    }

    // Along row y = 40.5, at the texel centres c within a texel of the cosine's crests (x = 24 m: slopes
    // small, curvature large), the second difference (f(c + h) - 2 f(c) + f(c - h)) / h, h = 1/4 texel, is
    // the slope's jump at c. Linear: the texels' whole second difference T[c+1] - 2 T[c] + T[c-1], at any h;
    // the B-spline (smooth, its second derivative at c that same difference): h times it, 4 times less.
    std::vector<glm::vec2> row;
    std::vector<double> second_difference;
    const float h = 0.25f;
    for (int crest = 24; crest < 144; crest += 24)
        for (int x = crest - 1; x <= crest + 1; ++x)
        {
            for (float d : {-h, 0.0f, h})
                row.emplace_back((float(x) + 0.5f + d) / kW, 40.5f / kH);
            second_difference.push_back(double(texel(0, x + 1, 40).r) - 2.0 * double(texel(0, x, 40).r) +
                                        double(texel(0, x - 1, 40).r));
        }
    for (const Case& c : {Case{0, kK, false, "paged linear"}, Case{1, kK, true, "paged bicubic"},
                          Case{2, 1, false, "plain linear"}, Case{3, 1, true, "plain bicubic"}})
    {
        const std::vector<glm::vec3> gpu = lookups.run(c.lookup, c.k, row);
        double smallest = INFINITY, largest = 0.0;
        for (size_t i = 0; i < second_difference.size(); ++i)
        {
            const size_t j = i * 3;
            const double crease =
                (double(gpu[(j + 2) * c.k].r) - 2.0 * double(gpu[(j + 1) * c.k].r) + double(gpu[j * c.k].r)) /
                h;
            smallest = std::min(smallest, crease / second_difference[i]);
            largest = std::max(largest, crease / second_difference[i]);
        }
        std::printf("%s: slope jumps at texel centres %.3g .. %.3g of the texels' second difference\n",
                    c.name, smallest, largest);
        if (c.bicubic)
        {
            EXPECT_LT(largest, 0.5) << c.name << ": a crease at a texel centre";
        }
        else
        {
            EXPECT_GT(smallest, 0.75) << c.name << ": the linear lookup shows no crease";
        }
    }
}
