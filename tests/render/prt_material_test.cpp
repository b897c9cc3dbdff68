// The PRT material end to end on lavapipe: unshadowed transfer folded per basis -> transfer pass ->
// per-vertex coefficients -> per-pixel basis evaluation at the normal-map normal. White furnace for every
// basis that holds a constant, and the GPU frame against a CPU evaluation of the same material.
#include "../gpu_fixture.h"

#include "normal_map_lookup.h"
#include "scene.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/gpu/commands.h>
#include <hemi/math/basis.h>
#include <hemi/math/sh.h>
#include <hemi/render/view/offscreen.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/view/prt_view.h>
#include <hemi/render/transfer.h>

#include "engine_pass.h"
#include "surface_object.h"

#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace
{

class PrtMaterial : public hemi::test::GpuTest
{
};

struct Rendered
{
    hemi::io::ImageRgba color, aux;
};

// Unshadowed transfer of lighting order 3 (L = 9), folded by the bake for `basis` (any technique), for every
// vertex of the mesh.
std::vector<float> folded_matrices(const hemi::io::Mesh& mesh, const hemi::math::BasisDesc& basis)
{
    hemi::bake::PrtBakeOptions o;
    o.kind = hemi::bake::TransferKind::Unshadowed;
    o.order = 3;
    return hemi::bake::fold_technique(hemi::bake::bake_prt_transfer(mesh, o), mesh, basis.name);
}

Rendered render(const hemi::samples::ShNormalMapScene& scene, const hemi::math::BasisDesc& basis,
                const std::vector<glm::vec3>& lighting, glm::vec3 albedo, uint32_t w, uint32_t h)
{
    auto& dev = hemi::test::device();
    hemi::render::TransferMatrices m(uint32_t(scene.mesh.vertex_count()), uint32_t(basis.size), 9,
                                     folded_matrices(scene.mesh, basis));
    hemi::render::TransferPass pass(dev, m);
    hemi::render::OffscreenTarget target(dev, w, h);
    hemi::render::MaterialSystem system(dev, target.desc());
    const hemi::io::ImageRgba8 normal_map{scene.map_width, scene.map_height, scene.normal_map};
    hemi::test::SurfaceObject object(system, scene.mesh, normal_map, hemi::test::normal_mapped(albedo), basis, &pass);
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection = hemi::render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f, float(w) / float(h));
    hemi::gpu::one_shot(dev, [&](VkCommandBuffer cmd) {
        object.upload.record(cmd);
        pass.record(cmd, lighting);
        hemi::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                                  VK_PIPELINE_STAGE_VERTEX_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
        frame.record_update(cmd, f);
        target.begin(cmd);
        object.draw(cmd, frame.set());
        target.end(cmd);
    });
    return {target.read_color(), target.read_aux()};
}

} // namespace

// Constant radiance 1, albedo 1: every covered pixel is exactly 1 for the bases that hold a constant,
// whatever the (strong, brick) normal map does, to 1e-5 on the 32-bit float target (the README's figure;
// measured at most 2e-6). HL2 and the 4-term separable basis cannot, and their worst errors are held to the
// README's digits: HL2's least-squares constant is 1.5 cos(theta) (Sloan's Table 2), so a pixel whose
// normal-map normal is the surface normal renders 1.5, an error of 0.50; sep4's worst pixel is 0.032 off.
TEST_F(PrtMaterial, WhiteFurnaceRendersOneForBasesThatHoldAConstant)
{
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Uniform);
    scene.mesh = hemi::io::make_uv_sphere(1.0f, 48, 24);
    std::vector<glm::vec3> lighting(9, glm::vec3(0.0f));
    lighting[0] = glm::vec3(2.0f * std::sqrt(float(M_PI)));
    for (const hemi::math::BasisDesc& b : hemi::math::bases())
    {
        Rendered r = render(scene, b, lighting, glm::vec3(1.0f), 96, 72);
        size_t covered = 0;
        double worst = 0;
        for (uint32_t y = 0; y < 72; ++y)
            for (uint32_t x = 0; x < 96; ++x)
                if (r.aux.at(x, y)[3] == 1.0f)
                {
                    ++covered;
                    for (int c = 0; c < 3; ++c)
                        worst = std::max(worst, double(std::abs(r.color.at(x, y)[c] - 1.0f)));
                }
        EXPECT_GT(covered, 1000u) << b.name;
        char value[32];
        std::snprintf(value, sizeof value, "%.3g", worst);
        ::testing::Test::RecordProperty(std::string("furnace_worst_") + std::string(b.name), value);
        if (b.name == "hl2")
            EXPECT_NEAR(worst, 0.50, 0.005) << "HL2's constant is 1.5 cos(theta)";
        else if (b.name == "sep4")
            EXPECT_NEAR(worst, 0.032, 0.0005) << "sep4's worst furnace pixel";
        else
            EXPECT_LT(worst, 1e-5) << b.name;
    }
}

// Under the analytic sky, each sampled interior pixel equals the CPU evaluation of the same material at the
// UV the GPU reports: the transfer folded at the exact surface point (the GPU interpolates per-vertex
// coefficients, hence the tolerance), the bilinear normal-map normal, the basis, albedo / pi.
TEST_F(PrtMaterial, FrameMatchesCpuEvaluationForEveryBasis)
{
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Sky);
    hemi::math::AnalyticSky sky;
    std::vector<glm::vec3> lighting = hemi::math::project_sh(3, [&](const glm::vec3& d) { return sky.radiance(d); }, 64);
    // Every entry of math::bases() (a new basis is covered with no edit here) and classic PRT.
    std::vector<const hemi::math::BasisDesc*> techniques;
    for (const hemi::math::BasisDesc& b : hemi::math::bases())
        techniques.push_back(&b);
    techniques.push_back(&hemi::math::vertex_irradiance_basis());
    for (const hemi::math::BasisDesc* technique : techniques)
    {
        const hemi::math::BasisDesc& b = *technique;
        const std::string name(b.name);
        const bool classic = b.id == HEMI_BASIS_VERTEX_IRRADIANCE;
        const hemi::bake::TransferFold fold(classic ? hemi::math::basis("sh9") : b);
        const uint32_t W = 160, H = 120;
        Rendered r = render(scene, b, lighting, scene.albedo, W, H);
        int compared = 0, failures = 0;
        for (uint32_t y = 3; y + 3 < H; y += 9)
            for (uint32_t x = 3; x + 3 < W; x += 9)
            {
                bool interior = true;
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dx = -2; dx <= 2; ++dx)
                        interior = interior && r.aux.at(x + dx, y + dy)[3] == 1.0f;
                glm::vec2 uv(r.aux.at(x, y)[0], r.aux.at(x, y)[1]);
                if (!interior || uv.y < 0.1f || uv.y > 0.9f || uv.x < 0.01f || uv.x > 0.99f)
                    continue;
                float phi = 2.0f * float(M_PI) * uv.x, theta = float(M_PI) * uv.y;
                glm::vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
                glm::vec3 t(-std::sin(phi), std::cos(phi), 0.0f);
                std::vector<float> tm =
                    fold.apply(hemi::bake::unshadowed_transfer(hemi::bake::object_to_tangent(n, t, 1.0f), 3), 9);
                if (classic)
                {
                    // Classic PRT: the irradiance at the surface normal, A_l y_lm(n); the normal map is ignored.
                    float ylm[9];
                    hemi::math::sh_eval(3, n, ylm);
                    for (int j = 0; j < 9; ++j)
                        tm[j] = float(hemi::math::clamped_cosine_factor(j == 0 ? 0 : (j < 4 ? 1 : 2))) * ylm[j];
                }
                glm::vec3 nt = glm::normalize(hemi::test::sample_bilinear(scene, uv) * 2.0f - 1.0f);
                float v[HEMI_BASIS_MAX_SIZE];
                b.eval(nt, v);
                glm::vec3 e(0.0f);
                for (int k = 0; k < b.size; ++k)
                {
                    glm::vec3 c(0.0f);
                    for (int j = 0; j < 9; ++j)
                        c += tm[size_t(k) * 9 + j] * lighting[j];
                    e += c * v[k];
                }
                glm::vec3 want = scene.albedo * e / float(M_PI);
                ++compared;
                for (int ch = 0; ch < 3; ++ch)
                    if (std::abs(r.color.at(x, y)[ch] - want[ch]) > 0.03f * std::abs(want[ch]) + 0.01f && failures++ < 5)
                        ADD_FAILURE() << name << " pixel " << x << "," << y << " uv " << uv.x << "," << uv.y << " ch " << ch
                                      << ": GPU " << r.color.at(x, y)[ch] << ", CPU " << want[ch];
            }
        EXPECT_GT(compared, 60) << name;
    }
}

// An engine draws the material into its own render pass: one RGBA16F colour attachment and a depth buffer,
// no aux attachment, the engine's own clear colour. The covered pixels equal those hemi's OffscreenTarget
// renders from the same frame (white furnace, albedo 1: exactly 1 for SH9), the background keeps the
// engine's clear colour, and the validation layer stays silent about the unused second output.
TEST_F(PrtMaterial, DrawsIntoAnEnginesOwnRenderPass)
{
    auto& dev = hemi::test::device();
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Uniform);
    scene.mesh = hemi::io::make_uv_sphere(1.0f, 48, 24);
    const hemi::math::BasisDesc& basis = hemi::math::basis("sh9");
    std::vector<glm::vec3> lighting(9, glm::vec3(0.0f));
    lighting[0] = glm::vec3(2.0f * std::sqrt(float(M_PI)));
    const uint32_t w = 96, h = 72;
    const Rendered reference = render(scene, basis, lighting, glm::vec3(1.0f), w, h);

    // The engine's pass.
    const hemi::test::EnginePass engine(w, h, {VK_FORMAT_R16G16B16A16_SFLOAT});
    const hemi::gpu::Image& color = engine.colors[0];

    hemi::render::TransferMatrices m(uint32_t(scene.mesh.vertex_count()), uint32_t(basis.size), 9,
                                     folded_matrices(scene.mesh, basis));
    hemi::render::TransferPass pass(dev, m);
    const hemi::io::ImageRgba8 normal_map{scene.map_width, scene.map_height, scene.normal_map};
    hemi::render::RenderTargetDesc target;
    target.render_pass = engine.render_pass;
    target.color_attachments = 1;
    hemi::render::MaterialSystem system(dev, target);
    hemi::test::SurfaceObject object(system, scene.mesh, normal_map, hemi::test::normal_mapped(glm::vec3(1.0f)), basis,
                                     &pass);
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection = hemi::render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f, float(w) / float(h));
    const float clear[4] = {0.25f, 0.5f, 0.75f, 1.0f};
    hemi::gpu::one_shot(dev, [&](VkCommandBuffer cmd) {
        pass.record(cmd, lighting);
        hemi::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                                  VK_PIPELINE_STAGE_VERTEX_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
        object.upload.record(cmd);
        frame.record_update(cmd, f);
        engine.begin(cmd, clear);
        object.draw(cmd, frame.set());
        vkCmdEndRenderPass(cmd);
    });
    const std::vector<std::byte> bytes = hemi::gpu::read_image(dev, color, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    ASSERT_EQ(bytes.size(), size_t(w) * h * 8);
    auto half = [&](size_t i) {
        uint16_t bits;
        std::memcpy(&bits, bytes.data() + i * 2, 2);
        return glm::unpackHalf1x16(bits);
    };
    size_t covered = 0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const size_t p = size_t(y) * w + x;
            if (reference.aux.at(x, y)[3] == 1.0f)
            {
                ++covered;
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(half(p * 4 + c), reference.color.at(x, y)[c], 2e-3f) << x << "," << y;
            }
            else
                for (int c = 0; c < 4; ++c)
                    ASSERT_EQ(half(p * 4 + c), clear[c]) << "background " << x << "," << y;
        }
    EXPECT_GT(covered, 1000u);
}

// The constant technique (hemi-bench's baseline) renders exactly its base colour factor, whatever the
// coefficients and the normal map: every covered pixel, to float precision.
TEST_F(PrtMaterial, ConstantTechniqueRendersItsFactor)
{
    auto& dev = hemi::test::device();
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Uniform);
    scene.mesh = hemi::io::make_uv_sphere(1.0f, 32, 16);
    const uint32_t w = 64, h = 48;
    hemi::render::OffscreenTarget target(dev, w, h);
    hemi::render::MaterialSystem system(dev, target.desc());
    const hemi::io::ImageRgba8 normal_map{scene.map_width, scene.map_height, scene.normal_map};
    const glm::vec3 factor(0.3f, 0.55f, 0.8f);
    hemi::test::SurfaceObject object(system, scene.mesh, normal_map, hemi::test::normal_mapped(factor),
                                     hemi::math::basis("sh9"), nullptr);
    hemi::render::MaterialKey key;
    key.technique = hemi::render::Technique::Constant;
    key.source = hemi::render::CoefficientSourceKind::Uniform;
    key.frame = hemi::render::ShadingFrame::World;
    object.type = &system.type(key);
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection = hemi::render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f, float(w) / float(h));
    const std::vector<glm::vec3> probe(9, glm::vec3(100.0f)); // would light the sphere far above the factor
    hemi::gpu::one_shot(dev, [&](VkCommandBuffer cmd) {
        object.upload.record(cmd);
        frame.record_update(cmd, f);
        object.probe->record_update(cmd, probe);
        target.begin(cmd);
        object.draw(cmd, frame.set());
        target.end(cmd);
    });
    const hemi::io::ImageRgba color = target.read_color(), aux = target.read_aux();
    size_t covered = 0;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            if (aux.at(x, y)[3] == 1.0f)
            {
                ++covered;
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(color.at(x, y)[c], factor[c]) << x << "," << y;
            }
    EXPECT_GT(covered, 300u);
}

// The per-texel coefficient source (directional lightmaps): K = 9 SH9 maps of 16 x 8 half-float texels
// sampled at TEXCOORD_1, bilinear and clamped. Every sampled pixel equals a CPU evaluation: the bilinear
// interpolation of the half-rounded texels at the pixel's UV, times the SH9 basis at the (flat) normal,
// times albedo / pi.
TEST_F(PrtMaterial, TexelCoefficientMapsMatchCpuEvaluation)
{
    auto& dev = hemi::test::device();
    const uint32_t mw = 16, mh = 8, K = 9, w = 96, h = 96;
    std::vector<float> maps(size_t(mw) * mh * K * 3);
    for (uint32_t k = 0; k < K; ++k)
        for (uint32_t y = 0; y < mh; ++y)
            for (uint32_t x = 0; x < mw; ++x)
            {
                float* t = &maps[((size_t(k) * mh + y) * mw + x) * 3];
                const float scale = k == 0 ? 3.0f : 1.0f / float(k);
                t[0] = scale * (0.6f + 0.3f * std::sin(0.4f * x + float(k)));
                t[1] = scale * (0.5f + 0.2f * std::cos(0.5f * y + 0.7f * float(k)));
                t[2] = scale * (0.4f + 0.02f * float(x + y));
            }
    hemi::render::OffscreenTarget target(dev, w, h);
    hemi::render::MaterialSystem system(dev, target.desc());
    const hemi::io::ImageRgba8 flat{1, 1, {128, 128, 255, 255}};
    const glm::vec3 albedo(0.9f, 0.7f, 0.5f);
    hemi::io::Material material;
    material.base_color_factor = glm::vec4(albedo, 1.0f);
    hemi::test::SurfaceObject object(system, hemi::test::quad(), flat, material, hemi::math::basis("sh9"), nullptr);
    hemi::render::TexelCoefficients coefficients(system, mw, mh, K, maps, object.upload);
    hemi::render::MaterialKey key;
    key.source = hemi::render::CoefficientSourceKind::Texel;
    key.basis = HEMI_BASIS_SH9;
    key.frame = hemi::render::ShadingFrame::Tangent;
    object.type = &system.type(key);
    object.source_set = coefficients.set();
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection = hemi::render::look_at_projection(glm::vec3(0, -3.2f, 0), glm::vec3(0), 40.0f, 1.0f);
    hemi::gpu::one_shot(dev, [&](VkCommandBuffer cmd) {
        object.upload.record(cmd);
        frame.record_update(cmd, f);
        target.begin(cmd);
        object.draw(cmd, frame.set());
        target.end(cmd);
    });
    const hemi::io::ImageRgba color = target.read_color(), aux = target.read_aux();

    auto texel = [&](uint32_t k, int x, int y) {
        x = std::clamp(x, 0, int(mw) - 1), y = std::clamp(y, 0, int(mh) - 1);
        const float* t = &maps[((size_t(k) * mh + uint32_t(y)) * mw + uint32_t(x)) * 3];
        return glm::vec3(glm::unpackHalf1x16(glm::packHalf1x16(t[0])), glm::unpackHalf1x16(glm::packHalf1x16(t[1])),
                         glm::unpackHalf1x16(glm::packHalf1x16(t[2])));
    };
    float y9[9];
    hemi::math::sh_eval(3, glm::vec3(0, 0, 1), y9);
    int compared = 0, failures = 0;
    for (uint32_t py = 1; py < h; py += 4)
        for (uint32_t px = 1; px < w; px += 4)
        {
            if (aux.at(px, py)[3] != 1.0f)
                continue;
            const glm::vec2 uv(aux.at(px, py)[0], aux.at(px, py)[1]);
            const float fx = uv.x * mw - 0.5f, fy = uv.y * mh - 0.5f;
            const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
            const float ax = fx - float(x0), ay = fy - float(y0);
            glm::vec3 e(0.0f);
            for (uint32_t k = 0; k < K; ++k)
            {
                const glm::vec3 c = glm::mix(glm::mix(texel(k, x0, y0), texel(k, x0 + 1, y0), ax),
                                             glm::mix(texel(k, x0, y0 + 1), texel(k, x0 + 1, y0 + 1), ax), ay);
                e += c * y9[k];
            }
            const glm::vec3 want = albedo * e / float(M_PI);
            ++compared;
            for (int ch = 0; ch < 3; ++ch)
                if (std::abs(color.at(px, py)[ch] - want[ch]) > 0.005f * std::abs(want[ch]) + 1e-3f && failures++ < 5)
                    ADD_FAILURE() << "pixel " << px << "," << py << " uv " << uv.x << "," << uv.y << " ch " << ch
                                  << ": GPU " << color.at(px, py)[ch] << ", CPU " << want[ch];
        }
    EXPECT_GT(compared, 150);
}
