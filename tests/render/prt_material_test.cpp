// The PRT material end to end on lavapipe: unshadowed transfer folded per basis -> transfer pass ->
// per-vertex coefficients -> per-pixel basis evaluation at the normal-map normal. White furnace for every
// basis that holds a constant, and the GPU frame against a CPU evaluation of the same material.
#include "../gpu_fixture.h"

#include "normal_map_lookup.h"
#include "scene.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/gpu/commands.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/basis.h>
#include <hemi/math/sh.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/transfer.h>
#include <hemi/render/view/offscreen.h>
#include <hemi/render/view/prt_view.h>

#include "../temp_dir.h"
#include "engine_pass.h"
#include "surface_object.h"

#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

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
    hemi::test::SurfaceObject object(system, scene.mesh, normal_map, hemi::test::normal_mapped(albedo), basis,
                                     &pass);
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection =
        hemi::render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f, float(w) / float(h));
    hemi::gpu::one_shot(dev,
                        [&](VkCommandBuffer cmd)
                        {
                            object.upload.record(cmd);
                            pass.record(cmd, lighting);
                            hemi::gpu::memory_barrier(
                                cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
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

namespace
{

// DESIGN.md Sec. 3's SH9 table and the clamped-cosine factors A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4, typed
// here: the irradiance of SH9 lighting at unit direction d, E(d) = sum_lm A_l L_lm y_lm(d) (Funk-Hecke).
glm::dvec3 typed_irradiance(const std::vector<glm::vec3>& lighting, glm::dvec3 d)
{
    const double x = d.x, y = d.y, z = d.z;
    const double y9[9] = {0.282095,
                          -0.488603 * y,
                          0.488603 * z,
                          -0.488603 * x,
                          1.092548 * x * y,
                          -1.092548 * y * z,
                          0.315392 * (3 * z * z - 1),
                          -1.092548 * x * z,
                          0.546274 * (x * x - y * y)};
    const double a[9] = {M_PI,     2 * M_PI / 3, 2 * M_PI / 3, 2 * M_PI / 3, M_PI / 4,
                         M_PI / 4, M_PI / 4,     M_PI / 4,     M_PI / 4};
    glm::dvec3 e(0.0);
    for (int j = 0; j < 9; ++j)
        e += a[j] * y9[j] * glm::dvec3(lighting[size_t(j)]);
    return e;
}

// The shading the PRT material should produce for unshadowed transfer on a convex object, computed by brute
// force and sharing no code with the bake: at a surface point with frame (T, B, N), the pixel basis holds the
// hemispherical least-squares fit of g(w) = E(w.x T + w.y B + w.z N), the irradiance as a function of the
// tangent-space normal; the fit is evaluated at the normal-map normal. The fit solves G c = int_H b g with
// G = int_H b b^T, both by a midpoint rule in (s, phi) with z = sin^2 s (every basis, the sqrt(z) of the
// shifted ones included, is smooth in s). Classic PRT is E(N): the normal map plays no part.
class BruteForceShading
{
  public:
    explicit BruteForceShading(const hemi::math::BasisDesc& b) : basis_(b)
    {
        const int ns = 160, np = 160, k = b.size;
        for (int i = 0; i < ns; ++i)
            for (int j = 0; j < np; ++j)
            {
                const double s = (i + 0.5) * (M_PI / 2) / ns, phi = (j + 0.5) * 2 * M_PI / np;
                const double z = std::sin(s) * std::sin(s), r = std::sqrt(std::max(0.0, 1 - z * z));
                dirs_.push_back(glm::dvec3(r * std::cos(phi), r * std::sin(phi), z));
                weights_.push_back(2 * std::sin(s) * std::cos(s) * (M_PI / 2 / ns) * (2 * M_PI / np));
                float v[HEMI_BASIS_MAX_SIZE];
                b.eval(glm::vec3(dirs_.back()), v);
                values_.insert(values_.end(), v, v + k);
            }
        gram_.assign(size_t(k) * k, 0.0);
        for (size_t p = 0; p < dirs_.size(); ++p)
            for (int a = 0; a < k; ++a)
                for (int c = 0; c < k; ++c)
                    gram_[size_t(a) * k + c] += weights_[p] * values_[p * k + a] * values_[p * k + c];
    }

    // The exit radiance albedo / pi * fit(nt) at the surface point with frame (t, b, n).
    glm::dvec3 shade(const std::vector<glm::vec3>& lighting, glm::dvec3 t, glm::dvec3 b, glm::dvec3 n,
                     glm::dvec3 nt, glm::dvec3 albedo) const
    {
        if (basis_.id == HEMI_BASIS_VERTEX_IRRADIANCE)
            return albedo * typed_irradiance(lighting, n) / M_PI;
        const int k = basis_.size;
        std::vector<glm::dvec3> rhs(size_t(k), glm::dvec3(0.0));
        for (size_t p = 0; p < dirs_.size(); ++p)
        {
            const glm::dvec3 w = dirs_[p];
            const glm::dvec3 g = weights_[p] * typed_irradiance(lighting, w.x * t + w.y * b + w.z * n);
            for (int a = 0; a < k; ++a)
                rhs[size_t(a)] += values_[p * k + a] * g;
        }
        // Gauss-Jordan elimination with partial pivoting on [G | rhs].
        std::vector<double> g = gram_;
        for (int col = 0; col < k; ++col)
        {
            int pivot = col;
            for (int r = col + 1; r < k; ++r)
                if (std::abs(g[size_t(r) * k + col]) > std::abs(g[size_t(pivot) * k + col]))
                    pivot = r;
            for (int c = 0; c < k; ++c)
                std::swap(g[size_t(col) * k + c], g[size_t(pivot) * k + c]);
            std::swap(rhs[size_t(col)], rhs[size_t(pivot)]);
            for (int r = 0; r < k; ++r)
                if (r != col)
                {
                    const double f = g[size_t(r) * k + col] / g[size_t(col) * k + col];
                    for (int c = 0; c < k; ++c)
                        g[size_t(r) * k + c] -= f * g[size_t(col) * k + c];
                    rhs[size_t(r)] -= f * rhs[size_t(col)];
                }
        }
        float v[HEMI_BASIS_MAX_SIZE];
        basis_.eval(glm::vec3(nt), v);
        glm::dvec3 e(0.0);
        for (int a = 0; a < k; ++a)
            e += double(v[a]) * rhs[size_t(a)] / g[size_t(a) * k + a];
        return albedo * e / M_PI;
    }

  private:
    const hemi::math::BasisDesc& basis_;
    std::vector<glm::dvec3> dirs_;
    std::vector<double> weights_, values_, gram_;
};

// Worst relative error |GPU - reference| / |reference| over the sampled interior pixels of `r` (aux = UV and
// coverage) on the UV sphere; `compared` receives the number of pixels.
double worst_against_brute_force(const hemi::io::ImageRgba& color, const hemi::io::ImageRgba& aux,
                                 const hemi::samples::ShNormalMapScene& scene,
                                 const BruteForceShading& reference, const std::vector<glm::vec3>& lighting,
                                 int& compared, std::string& where)
{
    double worst = 0.0;
    compared = 0;
    for (uint32_t y = 3; y + 3 < color.height; y += 9)
        for (uint32_t x = 3; x + 3 < color.width; x += 9)
        {
            glm::vec2 uv;
            if (!hemi::test::comparable_sphere_pixel(aux, x, y, uv))
                continue;
            // make_uv_sphere: u = phi / 2 pi, v = theta / pi, tangent d/d(phi), bitangent N x T (w = +1).
            const double phi = 2 * M_PI * uv.x, theta = M_PI * uv.y;
            const glm::dvec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta));
            const glm::dvec3 t(-std::sin(phi), std::cos(phi), 0.0);
            const glm::dvec3 nt =
                glm::normalize(glm::dvec3(hemi::test::sample_bilinear(scene, uv)) * 2.0 - 1.0);
            const glm::dvec3 want =
                reference.shade(lighting, t, glm::cross(n, t), n, nt, glm::dvec3(scene.albedo));
            ++compared;
            for (int ch = 0; ch < 3; ++ch)
            {
                const double e = std::abs(double(color.at(x, y)[ch]) - want[ch]) / std::abs(want[ch]);
                if (e > worst)
                {
                    worst = e;
                    where = "pixel " + std::to_string(x) + "," + std::to_string(y) + " channel " +
                            std::to_string(ch) + ": GPU " + std::to_string(color.at(x, y)[ch]) +
                            ", reference " + std::to_string(want[ch]);
                }
            }
        }
    return worst;
}

} // namespace

// Under the analytic sky, each sampled interior pixel equals the brute-force shading above (the irradiance
// by Funk-Hecke from the typed SH9 table, fitted on the hemisphere in the analytic frame of the UV sphere at
// the UV the GPU reports, evaluated at the bilinear normal-map normal): for every technique of math::bases()
// (a new basis is covered with no edit here) and classic PRT, both through the transfer pass the test feeds
// with the bake's folded matrices and through a baked asset written to a file, read back and drawn by
// render::PrtView. What remains is the GPU interpolating per-vertex coefficients over the 128 x 64 sphere's
// triangles, which classic PRT (no normal map) shows alone: 0.1% relative (measured 0.034%); and the
// normal-map lookup, whose bilinear weights lavapipe rounds to 8 bits, which moves the pixels on a brick's
// bevel: 0.6% relative for the normal-mapped techniques (measured at most 0.45%, HL2; 0.22% for SH9).
TEST_F(PrtMaterial, FrameMatchesBruteForceShadingForEveryTechnique)
{
    auto scene = hemi::samples::make_sh_normalmap_scene(hemi::samples::Environment::Sky);
    hemi::math::AnalyticSky sky;
    std::vector<glm::vec3> lighting = hemi::math::project_sh(
        3, [&](const glm::vec3& d) { return sky.radiance(d); }, 64);
    std::vector<const hemi::math::BasisDesc*> techniques;
    std::vector<std::string> names;
    for (const hemi::math::BasisDesc& b : hemi::math::bases())
    {
        techniques.push_back(&b);
        names.push_back(std::string(b.name));
    }
    techniques.push_back(&hemi::math::vertex_irradiance_basis());
    names.push_back("prt");
    for (const char* required :
         {"sh9", "sh4ls", "hl2", "sal4", "h4", "h6", "sep4", "zernike3", "zernike6", "prt"})
        EXPECT_NE(std::find(names.begin(), names.end(), required), names.end()) << required;

    // The baked asset: the sphere's unshadowed order-3 bake for every technique, with the brick normal map as
    // the material's normal texture, through the .hemi file.
    hemi::bake::PrtAssetOptions options;
    options.bake.kind = hemi::bake::TransferKind::Unshadowed;
    options.bake.order = 3;
    options.techniques = names;
    hemi::bake::PrtBakeSummary summary;
    hemi::io::PrtAsset baked = hemi::bake::make_prt_asset(scene.mesh, options, summary);
    baked.materials = {hemi::test::normal_mapped(scene.albedo)};
    baked.images = {hemi::io::EncodedImage{
        "bricks", "image/png",
        hemi::io::encode_png(hemi::io::ImageRgba8{scene.map_width, scene.map_height, scene.normal_map})}};
    const std::filesystem::path file = hemi::test::temp_dir("prt_material_test") / "sphere.hemi";
    hemi::io::write_prt_asset(file, baked);
    const hemi::io::PrtAsset asset = hemi::io::read_prt_asset(file);

    const uint32_t W = 160, H = 120;
    for (size_t i = 0; i < techniques.size(); ++i)
    {
        const hemi::math::BasisDesc& b = *techniques[i];
        const double tolerance = b.id == HEMI_BASIS_VERTEX_IRRADIANCE ? 1e-3 : 6e-3;
        const BruteForceShading reference(b);
        Rendered r = render(scene, b, lighting, scene.albedo, W, H);
        int compared = 0;
        std::string where;
        double worst = worst_against_brute_force(r.color, r.aux, scene, reference, lighting, compared, where);
        EXPECT_GT(compared, 60) << names[i];
        EXPECT_LT(worst, tolerance) << names[i] << " (transfer pass), worst " << where;

        hemi::render::PrtView view(hemi::test::device(), asset, names[i], false, W, H);
        hemi::render::PrtFrame frame;
        frame.world_lighting = lighting;
        frame.model = glm::mat4(1.0f); // the sphere as it is: world = object space
        frame.camera = hemi::render::PrtCamera{scene.eye, glm::vec3(0.0f), 40.0f};
        const hemi::io::ImageRgba color = view.render(frame);
        const double worst_view = worst_against_brute_force(color, view.target().read_aux(), scene, reference,
                                                            lighting, compared, where);
        EXPECT_GT(compared, 60) << names[i];
        EXPECT_LT(worst_view, tolerance) << names[i] << " (PrtView), worst " << where;
        char value[64];
        std::snprintf(value, sizeof value, "%.3g %.3g", worst, worst_view);
        ::testing::Test::RecordProperty("worst_relative_" + names[i], value);
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
    hemi::test::SurfaceObject object(system, scene.mesh, normal_map,
                                     hemi::test::normal_mapped(glm::vec3(1.0f)), basis, &pass);
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection =
        hemi::render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f, float(w) / float(h));
    const float clear[4] = {0.25f, 0.5f, 0.75f, 1.0f};
    hemi::gpu::one_shot(dev,
                        [&](VkCommandBuffer cmd)
                        {
                            pass.record(cmd, lighting);
                            hemi::gpu::memory_barrier(
                                cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                                VK_PIPELINE_STAGE_VERTEX_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
                            object.upload.record(cmd);
                            frame.record_update(cmd, f);
                            engine.begin(cmd, clear);
                            object.draw(cmd, frame.set());
                            vkCmdEndRenderPass(cmd);
                        });
    const std::vector<std::byte> bytes =
        hemi::gpu::read_image(dev, color, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    ASSERT_EQ(bytes.size(), size_t(w) * h * 8);
    auto half = [&](size_t i)
    {
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

// Every pixel the mesh covers (the target's aux attachment) is `want` within `relative` of it (0: exactly),
// every channel; returns how many are covered. Stops after the first few failures.
static size_t covered_pixels_equal(hemi::render::OffscreenTarget& target, const glm::vec3& want,
                                   float relative)
{
    const hemi::io::ImageRgba color = target.read_color(), aux = target.read_aux();
    size_t covered = 0;
    int failures = 0;
    for (uint32_t y = 0; y < color.height; ++y)
        for (uint32_t x = 0; x < color.width; ++x)
            if (aux.at(x, y)[3] == 1.0f)
            {
                ++covered;
                for (int c = 0; c < 3; ++c)
                    if (!(std::abs(color.at(x, y)[c] - want[c]) <= relative * std::abs(want[c])) &&
                        failures++ < 5)
                        ADD_FAILURE() << "pixel " << x << "," << y << " ch " << c << ": " << color.at(x, y)[c]
                                      << ", want " << want[c];
            }
    return covered;
}

// The constant technique (a debug view) renders exactly its base colour factor, whatever the
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
    f.view_projection =
        hemi::render::look_at_projection(scene.eye, glm::vec3(0.0f), 40.0f, float(w) / float(h));
    const std::vector<glm::vec3> probe(9, glm::vec3(100.0f)); // would light the sphere far above the factor
    hemi::gpu::one_shot(dev,
                        [&](VkCommandBuffer cmd)
                        {
                            object.upload.record(cmd);
                            frame.record_update(cmd, f);
                            object.probe->record_update(cmd, 0, 0, probe);
                            target.begin(cmd);
                            object.draw(cmd, frame.set());
                            target.end(cmd);
                        });
    EXPECT_GT(covered_pixels_equal(target, factor, 0.0f), 300u);
}

// The per-texel coefficient source (directional lightmaps), packed: K RGB maps of 16 x 8 half-float texels
// go to the GPU as ceil(3K / 4) RGBA layers and come back through hemi_lightmap_coefficients, bilinear and
// clamped at TEXCOORD_1, for every basis (K = 1, 3, 4, 6 and 9: every way a packed layer is shared). Every
// sampled pixel equals a CPU evaluation from the unpacked maps: the bilinear interpolation of the
// half-rounded texels at the pixel's UV, times the basis at the normal-map normal (tilted, so that every
// function of the basis counts), times albedo / pi. A layout that puts any float in the wrong channel or
// layer, or drops the last partial layer, moves pixels by tens of percent.
TEST_F(PrtMaterial, PackedTexelCoefficientMapsMatchCpuEvaluationForEveryBasis)
{
    auto& dev = hemi::test::device();
    const uint32_t mw = 16, mh = 8, w = 96, h = 96;
    const uint8_t bump[4] = {176, 96, 230, 255};
    const hemi::io::ImageRgba8 tilted{1, 1, {bump[0], bump[1], bump[2], bump[3]}};
    const glm::vec3 n = glm::normalize(glm::vec3(bump[0], bump[1], bump[2]) / 255.0f * 2.0f - 1.0f);
    const glm::vec3 albedo(0.9f, 0.7f, 0.5f);
    std::vector<const hemi::math::BasisDesc*> bases = {&hemi::math::vertex_irradiance_basis()};
    for (const hemi::math::BasisDesc& b : hemi::math::bases())
        bases.push_back(&b);
    hemi::render::OffscreenTarget target(dev, w, h);
    hemi::render::MaterialSystem system(dev, target.desc());
    for (const hemi::math::BasisDesc* basis : bases)
    {
        SCOPED_TRACE(std::string(basis->name));
        const uint32_t K = uint32_t(basis->size);
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
        const hemi::io::Material material = hemi::test::normal_mapped(albedo);
        // (Made as an SH9 probe-lit object; its type and source set are replaced below.)
        hemi::test::SurfaceObject object(system, hemi::test::quad(), tilted, material,
                                         hemi::math::basis("sh9"), nullptr);
        hemi::render::TexelCoefficients coefficients(system, mw, mh, K, maps, object.upload);
        EXPECT_EQ(coefficients.pages().layers(), (3 * K + 3) / 4);
        hemi::render::MaterialKey key;
        key.source = hemi::render::CoefficientSourceKind::Texel;
        key.basis = basis->id;
        key.frame = hemi::render::ShadingFrame::Tangent;
        object.type = &system.type(key);
        object.source_set = coefficients.set();
        hemi::render::FrameSet frame(system);
        hemi::render::FrameData f;
        f.view_projection =
            hemi::render::look_at_projection(glm::vec3(0, -3.2f, 0), glm::vec3(0), 40.0f, 1.0f);
        hemi::gpu::one_shot(dev,
                            [&](VkCommandBuffer cmd)
                            {
                                object.upload.record(cmd);
                                frame.record_update(cmd, f);
                                target.begin(cmd);
                                object.draw(cmd, frame.set());
                                target.end(cmd);
                            });
        const hemi::io::ImageRgba color = target.read_color(), aux = target.read_aux();

        auto texel = [&](uint32_t k, int x, int y)
        {
            x = std::clamp(x, 0, int(mw) - 1), y = std::clamp(y, 0, int(mh) - 1);
            const float* t = &maps[((size_t(k) * mh + uint32_t(y)) * mw + uint32_t(x)) * 3];
            return glm::vec3(glm::unpackHalf1x16(glm::packHalf1x16(t[0])),
                             glm::unpackHalf1x16(glm::packHalf1x16(t[1])),
                             glm::unpackHalf1x16(glm::packHalf1x16(t[2])));
        };
        float b[HEMI_BASIS_MAX_SIZE];
        basis->eval(n, b);
        int compared = 0;
        double worst = 0.0;
        for (uint32_t py = 1; py < h; py += 4)
            for (uint32_t px = 1; px < w; px += 4)
            {
                if (aux.at(px, py)[3] != 1.0f)
                    continue;
                const glm::vec2 uv(aux.at(px, py)[0], aux.at(px, py)[1]);
                const float fx = uv.x * mw - 0.5f, fy = uv.y * mh - 0.5f;
                const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
                const float ax = fx - float(x0), ay = fy - float(y0);
                glm::vec3 e(0.0f), scale(0.0f);
                for (uint32_t k = 0; k < K; ++k)
                {
                    const glm::vec3 c =
                        glm::mix(glm::mix(texel(k, x0, y0), texel(k, x0 + 1, y0), ax),
                                 glm::mix(texel(k, x0, y0 + 1), texel(k, x0 + 1, y0 + 1), ax), ay);
                    e += c * b[k];
                    scale += glm::abs(c * b[k]);
                }
                const glm::vec3 want = albedo * e / float(M_PI);
                ++compared;
                // Relative to the sum of the terms' magnitudes: what rounding in any one term can move.
                for (int ch = 0; ch < 3; ++ch)
                    worst = std::max(worst, std::abs(double(color.at(px, py)[ch]) - want[ch]) /
                                                (albedo[ch] * scale[ch] / M_PI));
            }
        EXPECT_GT(compared, 150);
        // Both sides filter the same half-rounded texels, so only float arithmetic and the sampler's weights
        // differ: half-float precision (2^-11) bounds it (lavapipe: 3.4e-7 at worst).
        EXPECT_LT(worst, 0x1p-11) << "worst error relative to the terms' magnitude";
        std::printf("%s: K = %u, %d pixels, worst %.2e\n", std::string(basis->name).c_str(), K, compared,
                    worst);
    }
}

namespace
{
// The lambert tests' quad: a tilted normal map (glTF frame: t = +x, b = n x t = +z, n = -y) and albedo,
// drawn by Technique::Lambert with a probe of 100s (which must not show) and the frame's lights.
struct LambertQuad
{
    static constexpr uint8_t kBump[3] = {176, 96, 230};
    const glm::vec3 albedo{0.9f, 0.7f, 0.5f};
    hemi::render::OffscreenTarget target{hemi::test::device(), 64, 64};
    hemi::render::MaterialSystem system{hemi::test::device(), target.desc()};
    hemi::test::SurfaceObject object{system,
                                     hemi::test::quad(),
                                     hemi::io::ImageRgba8{1, 1, {kBump[0], kBump[1], kBump[2], 255}},
                                     hemi::test::normal_mapped(albedo),
                                     hemi::math::basis("sh9"),
                                     nullptr};
    hemi::render::FrameSet frame{system};
    hemi::render::FrameData f;

    LambertQuad()
    {
        hemi::render::MaterialKey key = object.type->key;
        key.technique = hemi::render::Technique::Lambert;
        key.frame = hemi::render::ShadingFrame::Tangent;
        object.type = &system.type(key);
        f.view_projection =
            hemi::render::look_at_projection(glm::vec3(0, -3.2f, 0), glm::vec3(0), 40.0f, 1.0f);
    }
    // The normal map's normal in the world, from the glTF convention.
    static glm::vec3 world_normal()
    {
        const glm::vec3 nt = glm::normalize(glm::vec3(kBump[0], kBump[1], kBump[2]) / 255.0f * 2.0f - 1.0f);
        return nt.x * glm::vec3(1, 0, 0) + nt.y * glm::vec3(0, 0, 1) + nt.z * glm::vec3(0, -1, 0);
    }
    void draw(const hemi::render::ProbeBuffer::Occlusion& occlusion = {1.0f, 1.0f, 1.0f, 1.0f})
    {
        const std::vector<glm::vec3> probe(9, glm::vec3(100.0f));
        hemi::gpu::one_shot(hemi::test::device(),
                            [&](VkCommandBuffer cmd)
                            {
                                object.upload.record(cmd);
                                object.probe->record_update(cmd, 0, 0, probe, occlusion);
                                frame.record_update(cmd, f);
                                target.begin(cmd);
                                object.draw(cmd, frame.set());
                                target.end(cmd);
                            });
    }
};
} // namespace

// The fair baseline of hemi-bench (Technique::Lambert): the material's textures lit by the frame's dynamic
// lights alone. A tilted normal map on a quad (glTF frame: t = +x, b = n x t = +z, n = -y), three
// directional lights, one of them behind the tilted normal: every covered pixel is
// albedo * sum_i E_i max(0, N . l_i) / pi with N the normal map's normal in the world, computed here from the
// glTF convention. Coefficients (a probe of 100s) must not show; a technique that ignores the normal map, a
// light or the clamp fails it.
TEST_F(PrtMaterial, LambertBaselineIsTheTexturesLitByTheFramesLightsAlone)
{
    LambertQuad q;
    hemi::render::FrameData& f = q.f;
    const glm::vec3 world_normal = LambertQuad::world_normal(), albedo = q.albedo;
    auto light = [](glm::vec3 towards, glm::vec3 e)
    {
        hemi::render::DynamicLight l;
        l.position = glm::normalize(towards);
        l.irradiance = e;
        return l;
    };
    f.lights = {light({0.3f, -1.0f, 0.2f}, {1.0f, 2.0f, 3.0f}),
                light({-0.5f, -0.4f, 0.7f}, {2.0f, 1.0f, 0.5f}),
                light({0.2f, 1.0f, 0.1f}, {9.0f, 9.0f, 9.0f})}; // behind
    q.draw();
    glm::vec3 e(0.0f);
    for (const hemi::render::DynamicLight& l : f.lights)
        e += l.irradiance * std::max(0.0f, glm::dot(world_normal, l.position));
    const glm::vec3 want = albedo * e / float(M_PI);
    EXPECT_GT(covered_pixels_equal(q.target, want, 2e-3f), 1000u);
}

// A probe-lit object under a lightmap's mixed lights (issue 43): each frame light with a shadowmask channel
// is times that channel of the probe's occlusion (ProbeBuffer's fourth components), a light without one is
// not. Three lights in channels R and B and none, the probe's occlusion (1, 0.25, 0.5, 0): every covered
// pixel is albedo * sum_i E_i o_i max(0, N . l_i) / pi. Fails if the occlusion is ignored or read from the
// wrong component.
TEST_F(PrtMaterial, ProbeLitObjectsTakeTheMixedLightsTimesTheirOcclusion)
{
    LambertQuad q;
    hemi::render::FrameData& f = q.f;
    const glm::vec3 world_normal = LambertQuad::world_normal(), albedo = q.albedo;
    auto light = [](glm::vec3 towards, glm::vec3 e, int channel)
    {
        hemi::render::DynamicLight l;
        l.position = glm::normalize(towards);
        l.irradiance = e;
        l.shadowmask_channel = channel;
        return l;
    };
    f.lights = {light({0.3f, -1.0f, 0.2f}, {1.0f, 2.0f, 3.0f}, 0),
                light({-0.5f, -0.4f, 0.7f}, {2.0f, 1.0f, 0.5f}, 2),
                light({0.1f, -1.0f, -0.3f}, {0.5f, 0.5f, 0.5f}, -1)};
    const hemi::render::ProbeBuffer::Occlusion occlusion = {1.0f, 0.25f, 0.5f, 0.0f};
    q.draw(occlusion);
    glm::vec3 e(0.0f);
    for (const hemi::render::DynamicLight& l : f.lights)
        e += l.irradiance * std::max(0.0f, glm::dot(world_normal, l.position)) *
             (l.shadowmask_channel < 0 ? 1.0f : occlusion[size_t(l.shadowmask_channel)]);
    const glm::vec3 want = albedo * e / float(M_PI);
    EXPECT_GT(covered_pixels_equal(q.target, want, 2e-3f), 1000u);
}
