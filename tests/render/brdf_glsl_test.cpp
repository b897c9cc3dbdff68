// Heidrich & Seidel's models in the shader (shaders/include/hemi/brdf/factored.glsl): the GLSL evaluated
// analytically equals hemi's C++ (math/brdf.h), and the product of the tables sampled by the GPU's own
// bilinear filter (half-float textures) equals the model within the tolerance the README states for the CPU
// lookups (0.5% of max(value, 1% of the peak) with cos_alpha, cos_beta >= 0.1, 2% in the grazing band), at
// 200,000 random pairs, under the validation layer.
#include "../gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/math/brdf.h>

#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace
{
class BrdfGlsl : public hemi::test::GpuTest
{
};

// The tables as RGBA16F texels: table k's channel c into texel channel c, one table after another (layers).
std::vector<uint16_t> half_texels(const std::vector<const hemi::math::BrdfTable*>& tables)
{
    std::vector<uint16_t> out;
    for (const hemi::math::BrdfTable* t : tables)
        for (size_t i = 0; i < size_t(t->size) * t->size; ++i)
            for (uint32_t c = 0; c < 4; ++c)
                out.push_back(glm::packHalf1x16(c < t->channels ? t->values[i * t->channels + c] : 0.0f));
    return out;
}
} // namespace

TEST_F(BrdfGlsl, AnalyticAndTableLookupsMatchTheModels)
{
    auto& dev = hemi::test::device();
    const uint32_t size = 256;
    const double m = 0.2, ior = 1.5, e = 50.0;
    const hemi::math::TorranceSparrow model(hemi::math::FacetDistribution::Beckmann, m, ior);
    const auto ts = hemi::math::torrance_sparrow_tables(model, size);
    const auto banks = hemi::math::banks_table(e, size);
    const auto phong = hemi::math::lobe_table(hemi::math::LobeModel::Phong, e, size);

    hemi::gpu::UploadBatch upload(dev);
    const VkFormat format = VK_FORMAT_R16G16B16A16_SFLOAT;
    hemi::gpu::Image ts_image =
        hemi::gpu::create_image(dev, {size, size, format, VK_IMAGE_USAGE_SAMPLED_BIT, 1, 2, true});
    hemi::gpu::Image banks_image = hemi::gpu::create_image(dev, {size, size, format});
    hemi::gpu::Image phong_image = hemi::gpu::create_image(dev, {size, size, format});
    const auto ts_texels = half_texels({&ts[0], &ts[1]});
    const auto banks_texels = half_texels({&banks});
    const auto phong_texels = half_texels({&phong});
    upload.image(ts_image, ts_texels.data(), ts_texels.size() * 2);
    upload.image(banks_image, banks_texels.data(), banks_texels.size() * 2);
    upload.image(phong_image, phong_texels.data(), phong_texels.size() * 2);
    upload.submit_and_wait();
    hemi::gpu::Sampler sampler = hemi::gpu::create_sampler(
        dev, {VK_FILTER_LINEAR, VK_SAMPLER_MIPMAP_MODE_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, 0.0f});

    // Pairs of directions over the hemisphere (n = +z), random.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto direction = [&]
    {
        const double z = u(rng), phi = 2 * M_PI * u(rng), s = std::sqrt(1 - z * z);
        return glm::dvec3(s * std::cos(phi), s * std::sin(phi), z);
    };
    const uint32_t count = 200000;
    std::vector<glm::vec4> dirs;
    std::vector<glm::dvec3> ls, vs;
    for (uint32_t i = 0; i < count; ++i)
    {
        const glm::dvec3 l = direction(), v = direction();
        ls.push_back(l);
        vs.push_back(v);
        dirs.emplace_back(glm::vec3(l), 0.0f);
        dirs.emplace_back(glm::vec3(v), 0.0f);
    }
    hemi::gpu::Buffer in =
        hemi::gpu::create_buffer(dev, {dirs.size() * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    hemi::gpu::write_buffer(dev, in, dirs.data(), dirs.size() * 16);
    const VkDeviceSize out_bytes = VkDeviceSize(count) * 6 * 4;
    hemi::gpu::Buffer out = hemi::gpu::create_buffer(dev, {out_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});

    const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
    std::vector<hemi::gpu::Binding> bindings = {{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
                                                {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
                                                {2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs},
                                                {3, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs},
                                                {4, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs}};
    struct Push
    {
        uint32_t count;
        float roughness, ior, exponent, size;
    } push{count, float(m), float(ior), float(e), float(size)};
    hemi::gpu::Program program = hemi::gpu::create_compute_program(
        dev, {hemi::test::test_spirv("brdf_eval.comp"), bindings, uint32_t(sizeof(Push)), {}});
    hemi::gpu::DescriptorPool pool = hemi::gpu::create_descriptor_pool(dev, bindings, 1);
    VkDescriptorSet set = hemi::gpu::allocate_descriptor_set(dev, pool, program.set_layout);
    hemi::gpu::DescriptorWrite writes[5];
    writes[0].binding = 0;
    writes[0].buffer = {in, 0, VK_WHOLE_SIZE};
    writes[1].binding = 1;
    writes[1].buffer = {out, 0, VK_WHOLE_SIZE};
    const hemi::gpu::Image* images[3] = {&ts_image, &banks_image, &phong_image};
    for (int k = 0; k < 3; ++k)
    {
        writes[2 + k].binding = uint32_t(2 + k);
        writes[2 + k].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        writes[2 + k].image = {sampler, images[k]->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    hemi::gpu::write_descriptors(dev, set, writes);
    hemi::gpu::one_shot(dev,
                        [&](VkCommandBuffer cmd)
                        {
                            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.pipeline);
                            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.layout, 0, 1,
                                                    &set, 0, nullptr);
                            vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof(Push),
                                               &push);
                            vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
                        });
    std::vector<float> values(size_t(count) * 6);
    hemi::gpu::read_buffer(dev, out, values.data(), out_bytes);

    const glm::dvec3 n(0, 0, 1), t(1, 0, 0);
    struct Worst
    {
        double analytic = 0, bulk = 0, grazing = 0;
    } worst[3];
    double peak[3] = {0, 0, 0};
    std::vector<double> direct(size_t(count) * 3);
    for (uint32_t i = 0; i < count; ++i)
    {
        direct[i * 3 + 0] = model.eval_cos(n, ls[i], vs[i]);
        direct[i * 3 + 1] = hemi::math::banks_eval_cos(n, t, ls[i], vs[i], 1.0, 1.0, e);
        direct[i * 3 + 2] = hemi::math::lobe_eval_cos(hemi::math::LobeModel::Phong, e, n, ls[i], vs[i]);
        for (int k = 0; k < 3; ++k)
            peak[k] = std::max(peak[k], direct[i * 3 + k]);
    }
    for (uint32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k)
        {
            const double d = direct[i * 3 + k], floor = std::max(d, 0.01 * peak[k]);
            worst[k].analytic = std::max(worst[k].analytic, std::abs(values[i * 6 + 2 * k] - d) / floor);
            const double rel = std::abs(values[i * 6 + 2 * k + 1] - d) / floor;
            double& w = ls[i].z < 0.1 || vs[i].z < 0.1 ? worst[k].grazing : worst[k].bulk;
            w = std::max(w, rel);
        }
    const char* names[3] = {"torrance-sparrow", "banks", "phong"};
    for (int k = 0; k < 3; ++k)
    {
        EXPECT_LT(worst[k].analytic, 1e-3) << names[k] << ": the GLSL twin";
        EXPECT_LT(worst[k].bulk, 0.005) << names[k] << ": the tables, bulk";
        EXPECT_LT(worst[k].grazing, 0.02) << names[k] << ": the tables, grazing";
        std::printf("%s: GLSL analytic %.2e, tables bulk %.4f%%, grazing %.4f%%\n", names[k],
                    worst[k].analytic, 100 * worst[k].bulk, 100 * worst[k].grazing);
    }
}
