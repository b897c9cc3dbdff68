// One loaded level in every pass of an engine's frame (render::PassDesc): a depth prepass, a colour pass
// testing EQUAL against it, and a shadow map from a light's view, all from one LightmapModel; and glTF's
// alpha modes: MASK cuts at alphaCutoff (in colour and depth passes), BLEND blends over what is there.
// Known pixels: analytic depths of the level's planes, the clear colour, the texture's colours.
#include "../gpu_fixture.h"

#include "depth_pass.h"
#include "engine_pass.h"
#include "table_level.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/gpu/commands.h>
#include <hemi/io/image.h>
#include <hemi/math/camera.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/probe_object.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <thread>

namespace
{
using namespace hemi;

class Passes : public test::GpuTest
{
};

constexpr uint32_t kSize = 64;

using DepthPass = test::DepthPass;

// The tests' table level (table_level.h), baked into H6.
io::LightmapAsset level()
{
    io::Material floor, top;
    floor.base_color_factor = glm::vec4(0.8f, 0.7f, 0.6f, 1.0f);
    top.base_color_factor = glm::vec4(0.3f, 0.5f, 0.8f, 1.0f);
    return test::table_level(floor, top, {}, {"h6"});
}

// Vulkan clip space from a light straight above, looking down -z: x right, y down, depth (2 - z - 0.5) / 2.5
// (z = 0.5: 0.4, z = 0: 0.6) over [-1.25, 1.25]^2.
glm::mat4 light_view_projection()
{
    glm::mat4 m(0.0f);
    m[0][0] = 1.0f / 1.25f;  // x
    m[1][1] = -1.0f / 1.25f; // y down
    m[2][2] = -1.0f / 2.5f;  // depth = (1.5 - z) / 2.5
    m[3][2] = 1.5f / 2.5f;
    m[3][3] = 1.0f;
    return m;
}

// A model drawn three ways into `pass`: the plain colour pass 0 (the reference), the colour pass `equal`
// (depth EQUAL, no writes) after the depth prepass `prepass`, and `equal` without the prepass. `draw(cmd,
// index)` records the model with the pipelines of pass `index`; `setup(cmd)`, when given, what comes before
// the render pass (uploads, frame data). Counts the covered pixels of the reference, the channels after the
// prepass more than 0.5% from it, and the pixels drawn without the prepass.
struct PrepassAgreement
{
    int covered = 0, different = 0, drawn_without = 0;
};
constexpr float kClearColour[4] = {0, 0, 0, 0};
PrepassAgreement prepass_agreement(const test::EnginePass& pass, size_t prepass, size_t equal,
                                   const std::function<void(VkCommandBuffer, size_t)>& draw,
                                   const std::function<void(VkCommandBuffer)>& setup = {})
{
    auto colour = [&](bool with_prepass, size_t colour_index)
    {
        gpu::one_shot(test::device(),
                      [&](VkCommandBuffer cmd)
                      {
                          if (setup)
                              setup(cmd);
                          pass.begin(cmd, kClearColour);
                          if (with_prepass)
                              draw(cmd, prepass);
                          draw(cmd, colour_index);
                          vkCmdEndRenderPass(cmd);
                      });
        return pass.read_color();
    };
    const std::vector<float> reference = colour(false, 0);
    const std::vector<float> after_prepass = colour(true, equal);
    const std::vector<float> without_prepass = colour(false, equal);
    PrepassAgreement a;
    for (size_t p = 0; p < size_t(kSize) * kSize; ++p)
    {
        a.covered += reference[p * 4 + 3] == 1.0f;
        a.drawn_without += without_prepass[p * 4 + 3] != 0.0f;
        for (int c = 0; c < 4; ++c)
            a.different += std::abs(after_prepass[p * 4 + c] - reference[p * 4 + c]) >
                           0.005f * std::abs(reference[p * 4 + c]);
    }
    return a;
}

} // namespace

// The level drawn three ways from one LightmapModel (one load, three sets of pipelines): a colour pass with
// LESS (the reference); a depth prepass, then the colour pass with EQUAL and no depth writes, which equals
// the reference at every pixel (and draws nothing without the prepass); and a shadow map from above whose
// texels are the planes' analytic depths plus the depth bias asked for.
TEST_F(Passes, OneLevelDrawsInAPrepassAShadowPassAndTheColourPass)
{
    gpu::Device& dev = test::device();
    const io::LightmapAsset asset = level();
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    const DepthPass shadow_target;
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    render::LightmapModel model(system, asset, {"h6"}, upload);

    render::PassDesc prepass;
    prepass.kind = render::PassKind::Depth;
    prepass.target = target;
    render::PassDesc equal;
    equal.target = target;
    equal.target.depth_compare = VK_COMPARE_OP_EQUAL;
    equal.target.depth_write = false;
    render::PassDesc shadow;
    shadow.kind = render::PassKind::Shadow;
    shadow.target.render_pass = shadow_target.render_pass;
    shadow.target.color_attachments = 0;
    shadow.depth_bias_constant = 1000.0f;
    shadow.depth_bias_slope = 0.0f;
    render::PassDesc unbiased = shadow;
    unbiased.kind = render::PassKind::Depth;
    const size_t prepass_index = model.add_pass(prepass), equal_index = model.add_pass(equal),
                 shadow_index = model.add_pass(shadow), unbiased_index = model.add_pass(unbiased);
    const size_t types = system.type_count();
    // Every pass of the level is compiled once: adding the same pass again compiles nothing.
    model.add_pass(prepass);
    EXPECT_EQ(system.type_count(), types);

    render::FrameSet camera(system), light(system);
    render::FrameData view;
    view.eye = glm::vec3(0.8f, -2.2f, 2.0f);
    view.view_projection = math::look_at_projection(view.eye, glm::vec3(0.0f), 45.0f, 1.0f);
    render::FrameData from_light;
    from_light.view_projection = light_view_projection();
    const PrepassAgreement a = prepass_agreement(
        pass, prepass_index, equal_index,
        [&](VkCommandBuffer cmd, size_t index)
        { model.draw(cmd, camera.set(), "h6", glm::mat4(1.0f), index); },
        [&](VkCommandBuffer cmd)
        {
            upload.record(cmd);
            camera.record_update(cmd, view);
        });
    EXPECT_GT(a.covered, 1500);
    EXPECT_EQ(a.different, 0) << "the colour pass after the prepass differs from the plain colour pass";
    EXPECT_EQ(a.drawn_without, 0) << "EQUAL drew without a prepass: the test cannot tell the prepass's depth";

    auto depth_from_light = [&](size_t index)
    {
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          light.record_update(cmd, from_light);
                          shadow_target.begin(cmd);
                          model.draw(cmd, light.set(), "h6", glm::mat4(1.0f), index);
                          vkCmdEndRenderPass(cmd);
                      });
        return shadow_target.read();
    };
    const std::vector<float> biased = depth_from_light(shadow_index),
                             exact = depth_from_light(unbiased_index);
    // D32_SFLOAT: the bias is constant x 2^(e - 23) with e the exponent of the primitive's largest depth:
    // 2^-25 for the top (depth 0.4), 2^-24 for the floor (0.6).
    int table = 0, floor = 0;
    for (uint32_t y = 2; y + 2 < kSize; y += 3)
        for (uint32_t x = 2; x + 2 < kSize; x += 3)
        {
            // The texel centre's world position under the light.
            const float wx = ((x + 0.5f) / kSize * 2.0f - 1.0f) * 1.25f,
                        wy = -((y + 0.5f) / kSize * 2.0f - 1.0f) * 1.25f;
            const float e = exact[y * kSize + x], b = biased[y * kSize + x];
            const bool on_table = std::abs(wx) < 0.48f && std::abs(wy) < 0.48f;
            const bool off_table = std::abs(wx) > 0.52f || std::abs(wy) > 0.52f;
            const bool on_floor = off_table && std::abs(wx) < 0.98f && std::abs(wy) < 0.98f;
            if (on_table)
            {
                ++table;
                EXPECT_NEAR(e, 0.4f, 1e-6f) << x << "," << y;
                EXPECT_NEAR(b - e, 1000.0f * std::ldexp(1.0f, -25), 2e-6f) << x << "," << y;
            }
            else if (on_floor)
            {
                ++floor;
                EXPECT_NEAR(e, 0.6f, 1e-6f) << x << "," << y;
                EXPECT_NEAR(b - e, 1000.0f * std::ldexp(1.0f, -24), 4e-6f) << x << "," << y;
            }
            else if (off_table && (std::abs(wx) > 1.02f || std::abs(wy) > 1.02f))
            {
                EXPECT_EQ(e, 1.0f) << "outside the level " << x << "," << y;
            }
        }
    EXPECT_GT(table, 50);
    EXPECT_GT(floor, 100);
}

namespace
{
// A quad facing the camera with a 2 x 1 base colour texture, nearest-sampled: the left texel's alpha is 0.25,
// the right one's 0.75; alphaCutoff 0.5. Lit by a white furnace probe (colour = albedo), over a clear colour.
struct AlphaQuad
{
    io::Mesh mesh;
    // Colours whose sRGB decoding is exact (0 and 1: lavapipe decodes others to within ~0.7%).
    io::ImageRgba8 texture{2, 1, {255, 0, 255, 64, 0, 255, 255, 191}};
    glm::vec3 left{0.0f}, right{0.0f}; // linear albedo of the two texels
    AlphaQuad()
    {
        mesh.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
        mesh.normals.assign(4, glm::vec3(0, -1, 0));
        mesh.tangents.assign(4, glm::vec4(1, 0, 0, 1));
        mesh.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
        mesh.indices = {0, 1, 2, 0, 2, 3};
        auto linear = [](uint8_t v)
        {
            const float c = v / 255.0f;
            return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
        };
        for (int c = 0; c < 3; ++c)
        {
            left[c] = linear(texture.pixels[size_t(c)]);
            right[c] = linear(texture.pixels[size_t(4 + c)]);
        }
    }
};

struct AlphaImages
{
    std::vector<float> color, depth;
};

AlphaImages draw_alpha(io::AlphaMode mode, const float clear[4])
{
    gpu::Device& dev = test::device();
    const AlphaQuad q;
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    const DepthPass depth;
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    const render::GpuMesh mesh(dev, q.mesh, upload);
    io::Material material;
    material.base_color.image = 0;
    material.base_color.sampler.mag_filter = io::Filter::Nearest;
    material.base_color.sampler.min_filter = io::Filter::Nearest;
    material.base_color.sampler.mipmaps = false;
    material.alpha_mode = mode;
    material.alpha_cutoff = 0.5f;
    render::TextureSet textures(dev, std::span<const io::ImageRgba8>(&q.texture, 1),
                                std::span<const io::Material>(&material, 1), upload);
    const render::MaterialInstance instance(system, textures, material, upload);
    render::ProbeBuffer probe(system, 1);
    std::vector<glm::vec3> furnace(9, glm::vec3(0.0f));
    furnace[0] = glm::vec3(float(M_PI) * 2.0f * std::sqrt(float(M_PI))); // E = pi everywhere
    render::MaterialKey key;
    key.source = render::CoefficientSourceKind::Uniform;
    key.frame = render::ShadingFrame::World;
    key.alpha = instance.alpha_mode();
    render::PassDesc depth_pass;
    depth_pass.kind = render::PassKind::Shadow;
    depth_pass.target.render_pass = depth.render_pass;
    depth_pass.target.color_attachments = 0;
    depth_pass.depth_bias_constant = depth_pass.depth_bias_slope = 0.0f;
    const render::MaterialType& colour_type = system.type(key);
    const render::MaterialType& depth_type = system.type(key, depth_pass);
    render::FrameSet frame(system);
    render::FrameData f;
    f.view_projection = math::look_at_projection(glm::vec3(0, -3, 0), glm::vec3(0.0f), 45.0f, 1.0f);
    auto draw = [&](VkCommandBuffer cmd, const render::MaterialType& type)
    {
        render::DrawBindings b;
        b.type = &type;
        b.frame = frame.set();
        b.material = instance.set();
        b.source = probe.set();
        b.push.model = glm::mat4(1.0f);
        render::bind_material(cmd, b);
        mesh.bind(cmd);
        mesh.draw(cmd, 0, mesh.index_count());
    };
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      upload.record(cmd);
                      frame.record_update(cmd, f);
                      probe.record_update(cmd, 0, 0, furnace);
                      pass.begin(cmd, clear);
                      draw(cmd, colour_type);
                      vkCmdEndRenderPass(cmd);
                      depth.begin(cmd);
                      draw(cmd, depth_type);
                      vkCmdEndRenderPass(cmd);
                  });
    return {pass.read_color(), depth.read()};
}
} // namespace

// MASK: the left half (alpha 0.25) is cut, in the colour pass and in a depth pass alike; the right half
// (0.75) is drawn opaque with its albedo. BLEND: each half is albedo * a + clear * (1 - a) (alpha a + clear
// alpha * (1 - a)), and the opaque drawing of the same quad ignores alpha.
TEST_F(Passes, MaskCutsAtAlphaCutoffAndBlendBlends)
{
    const float clear[4] = {0.1f, 0.2f, 0.9f, 0.5f};
    const AlphaQuad q;
    const AlphaImages mask = draw_alpha(io::AlphaMode::Mask, clear);
    const AlphaImages blend = draw_alpha(io::AlphaMode::Blend, clear);
    const AlphaImages opaque = draw_alpha(io::AlphaMode::Opaque, clear);
    int left = 0, right = 0;
    auto near = [](float got, float want) { return std::abs(got - want) <= 0.005f * std::abs(want) + 1e-5f; };
    for (uint32_t y = kSize / 2 - 4; y < kSize / 2 + 4; ++y)
        for (uint32_t x = 16; x < 48; ++x)
        {
            if (x >= 30 && x < 34)
                continue; // where the two texels meet
            const bool is_left = x < 32;
            const glm::vec3 albedo = is_left ? q.left : q.right;
            const float a = is_left ? 64.0f / 255.0f : 191.0f / 255.0f;
            (is_left ? left : right)++;
            const size_t p = (size_t(y) * kSize + x) * 4;
            for (int c = 0; c < 3; ++c)
            {
                EXPECT_TRUE(near(mask.color[p + c], is_left ? clear[c] : albedo[c]))
                    << "mask " << x << "," << y << " channel " << c << ": " << mask.color[p + c];
                EXPECT_TRUE(near(blend.color[p + c], albedo[c] * a + clear[c] * (1.0f - a)))
                    << "blend " << x << "," << y << " channel " << c << ": " << blend.color[p + c];
                EXPECT_TRUE(near(opaque.color[p + c], albedo[c]))
                    << "opaque " << x << "," << y << " " << opaque.color[p + c] << " vs " << albedo[c];
            }
            EXPECT_TRUE(near(mask.color[p + 3], is_left ? clear[3] : 1.0f));
            EXPECT_TRUE(near(blend.color[p + 3], a + clear[3] * (1.0f - a))) << blend.color[p + 3];
            // Depth: the cut half stays at the clear depth; the other half, and every texel of the opaque
            // and (alpha-tested in depth passes) blended quads, holds the quad's depth.
            const float d = mask.depth[size_t(y) * kSize + x];
            if (is_left)
            {
                EXPECT_EQ(d, 1.0f) << "mask depth " << x << "," << y;
            }
            else
            {
                EXPECT_LT(d, 1.0f) << "mask depth " << x << "," << y;
            }
            EXPECT_LT(opaque.depth[size_t(y) * kSize + x], 1.0f);
        }
    EXPECT_GT(left, 50);
    EXPECT_GT(right, 50);
}

// Types requested from several threads at once (an engine's loading jobs): each key is compiled once and
// every thread gets the same type; prepare() compiles a list up front.
TEST_F(Passes, TypesAreMadeOnceWhenSeveralThreadsAskAtOnce)
{
    const test::EnginePass pass(8, 8, {VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(test::device(), target);
    std::vector<render::MaterialKey> keys;
    for (int basis : {HEMI_BASIS_SH9, HEMI_BASIS_H4, HEMI_BASIS_H6, HEMI_BASIS_HL2})
    {
        render::MaterialKey key;
        key.source = render::CoefficientSourceKind::Texel;
        key.basis = basis;
        keys.push_back(key);
        key.alpha = io::AlphaMode::Mask;
        keys.push_back(key);
    }
    std::vector<std::vector<const render::MaterialType*>> got(4);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < got.size(); ++t)
        threads.emplace_back(
            [&, t]
            {
                got[t].resize(keys.size());
                for (size_t i = 0; i < keys.size(); ++i)
                {
                    const size_t k = (i + t * 3) % keys.size(); // each thread in its own order
                    got[t][k] = &system.type(keys[k]);
                }
            });
    for (std::thread& t : threads)
        t.join();
    EXPECT_EQ(system.type_count(), keys.size());
    for (size_t t = 1; t < got.size(); ++t)
        EXPECT_EQ(got[t], got[0]) << "thread " << t;
    render::PassDesc depth;
    depth.kind = render::PassKind::Depth;
    depth.target = target;
    system.prepare(keys, depth);
    // Depth pipelines ignore the basis: one for the opaque keys, one for the alpha-tested ones.
    EXPECT_EQ(system.type_count(), keys.size() + 2);
}

// A colour pass with a second colour attachment of the engine's (a G-buffer target, say) and no aux output:
// hemi's pipeline writes attachment 0 and leaves attachment 1 as the engine left it, also where it draws.
TEST_F(Passes, ExtraColourAttachmentsAreLeftToTheEngine)
{
    gpu::Device& dev = test::device();
    const AlphaQuad q;
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    target.color_attachments = 2;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    const render::GpuMesh mesh(dev, q.mesh, upload);
    const io::Material material;
    render::TextureSet textures(dev, std::span<const io::ImageRgba8>(), std::span<const io::Material>(),
                                upload);
    const render::MaterialInstance instance(system, textures, material, upload);
    render::ProbeBuffer probe(system, 1);
    std::vector<glm::vec3> furnace(9, glm::vec3(0.0f));
    furnace[0] = glm::vec3(float(M_PI) * 2.0f * std::sqrt(float(M_PI)));
    render::MaterialKey key;
    key.source = render::CoefficientSourceKind::Uniform;
    key.frame = render::ShadingFrame::World;
    render::FrameSet frame(system);
    render::FrameData f;
    f.view_projection = math::look_at_projection(glm::vec3(0, -3, 0), glm::vec3(0.0f), 45.0f, 1.0f);
    const float clear[4] = {0.25f, 0.5f, 0.75f, 0.125f};
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      upload.record(cmd);
                      frame.record_update(cmd, f);
                      probe.record_update(cmd, 0, 0, furnace);
                      pass.begin(cmd, clear);
                      render::DrawBindings b;
                      b.type = &system.type(key);
                      b.frame = frame.set();
                      b.material = instance.set();
                      b.source = probe.set();
                      b.push.model = glm::mat4(1.0f);
                      render::bind_material(cmd, b);
                      mesh.bind(cmd);
                      mesh.draw(cmd, 0, mesh.index_count());
                      vkCmdEndRenderPass(cmd);
                  });
    const std::vector<float> colour = pass.read_color();
    const std::vector<float> engine = pass.read_color(1);
    int drawn = 0;
    for (size_t p = 0; p < size_t(kSize) * kSize; ++p)
    {
        if (colour[p * 4 + 3] != 1.0f)
            continue;
        ++drawn;
        for (int c = 0; c < 4; ++c)
            ASSERT_EQ(engine[p * 4 + c], clear[c]) << "pixel " << p;
    }
    EXPECT_GT(drawn, 500);
}

// A probe-lit object (issue 42: ProbeObject had no add_pass) drawn the same three ways as the level above:
// the colour pass after a depth prepass with EQUAL equals the plain colour pass at every pixel (and draws
// nothing without the prepass), and its shadow-map depth at the sphere's top is the analytic (1.5 - r) / 2.5
// of light_view_projection(), with nothing outside the sphere's disc.
TEST_F(Passes, AProbeLitObjectDrawsInAPrepassAShadowPassAndTheColourPass)
{
    gpu::Device& dev = test::device();
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    const DepthPass shadow_target;
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    constexpr float kRadius = 0.6f;
    render::ProbeObject object(system, io::make_uv_sphere(kRadius, 48, 24), {}, std::vector<io::Material>(1),
                               {}, 1, upload);
    upload.submit_and_wait();
    std::vector<glm::vec3> sh(9, glm::vec3(0.0f));
    sh[0] = glm::vec3(1.0f);
    sh[2] = glm::vec3(0.5f); // brighter on top: a gradient the EQUAL pass must reproduce
    object.write_lighting(0, sh);

    render::PassDesc prepass;
    prepass.kind = render::PassKind::Depth;
    prepass.target = target;
    render::PassDesc equal;
    equal.target = target;
    equal.target.depth_compare = VK_COMPARE_OP_EQUAL;
    equal.target.depth_write = false;
    render::PassDesc shadow;
    shadow.kind = render::PassKind::Shadow;
    shadow.target.render_pass = shadow_target.render_pass;
    shadow.target.color_attachments = 0;
    const size_t prepass_index = object.add_pass(prepass), equal_index = object.add_pass(equal),
                 shadow_index = object.add_pass(shadow);

    render::FrameSet camera(system), light(system);
    render::FrameData view;
    view.eye = glm::vec3(0.8f, -2.2f, 1.0f);
    view.view_projection = math::look_at_projection(view.eye, glm::vec3(0.0f), 45.0f, 1.0f);
    camera.write(0, view);
    render::FrameData from_light;
    from_light.view_projection = light_view_projection();
    light.write(0, from_light);
    const PrepassAgreement a =
        prepass_agreement(pass, prepass_index, equal_index,
                          [&](VkCommandBuffer cmd, size_t index)
                          { object.draw(cmd, camera.set(), 0, glm::mat4(1.0f), 0, index); });
    EXPECT_GT(a.covered, 1000);
    EXPECT_EQ(a.different, 0) << "the colour pass after the prepass differs from the plain colour pass";
    EXPECT_EQ(a.drawn_without, 0);

    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      shadow_target.begin(cmd);
                      object.draw(cmd, light.set(), 0, glm::mat4(1.0f), 0, shadow_index);
                      vkCmdEndRenderPass(cmd);
                  });
    const std::vector<float> depth = shadow_target.read();
    // The texel at the centre sees the sphere's top: within 5e-3 of it (the facets around the pole of a 48 x
    // 24 tessellation and the shadow pass's default depth bias put it 2e-3 deeper; a radius 1% off
    // is 2.4e-3).
    const uint32_t c = kSize / 2;
    EXPECT_NEAR(depth[c * kSize + c], (1.5f - kRadius) / 2.5f, 5e-3f);
    for (uint32_t y = 0; y < kSize; y += 4)
        for (uint32_t x = 0; x < kSize; x += 4)
        {
            const float wx = ((x + 0.5f) / kSize * 2.0f - 1.0f) * 1.25f,
                        wy = -((y + 0.5f) / kSize * 2.0f - 1.0f) * 1.25f;
            if (std::hypot(wx, wy) > kRadius * 1.05f)
            {
                EXPECT_EQ(depth[y * kSize + x], 1.0f) << "outside the sphere " << x << "," << y;
            }
            else if (std::hypot(wx, wy) < kRadius * 0.9f)
            {
                EXPECT_LT(depth[y * kSize + x], (1.5f + 0.1f) / 2.5f) << "on the sphere " << x << "," << y;
            }
        }
}

// An engine that draws colour with its own shaders makes the system without a default target: loading the
// level and a probe-lit object compiles no pipeline, their first pass is the one they are given (index 0),
// only that pass's pipelines are compiled, and the level drawn into it gives the analytic shadow depths.
// type(key) without a pass is refused by name, and a pass that was never added is refused at draw time.
TEST_F(Passes, ASystemWithoutADefaultTargetCompilesOnlyThePassesItsObjectsAreGiven)
{
    gpu::Device& dev = test::device();
    const io::LightmapAsset asset = level();
    const DepthPass shadow_target;
    render::MaterialSystem system(dev);
    EXPECT_FALSE(system.has_default_pass());
    gpu::UploadBatch upload(dev);
    render::LightmapModel model(system, asset, {"h6"}, upload);
    render::ProbeObject sphere(system, io::make_uv_sphere(0.3f, 16, 8), {}, std::vector<io::Material>(1), {},
                               1, upload);
    upload.submit_and_wait();
    EXPECT_EQ(system.type_count(), 0u) << "loading compiled pipelines no pass asked for";
    EXPECT_THROW(system.type(render::MaterialKey{}), std::invalid_argument);

    render::PassDesc shadow;
    shadow.kind = render::PassKind::Depth;
    shadow.target.render_pass = shadow_target.render_pass;
    shadow.target.color_attachments = 0;
    EXPECT_EQ(model.add_pass(shadow), 0u);
    EXPECT_EQ(sphere.add_pass(shadow), 0u);
    // The level's two materials and the sphere's default one are single-sided and opaque: one depth type per
    // coefficient source (the level's texels, the sphere's uniform SH9), whatever the technique and basis.
    EXPECT_EQ(system.type_count(), 2u);

    render::FrameSet light(system);
    render::FrameData from_light;
    from_light.view_projection = light_view_projection();
    light.write(0, from_light);
    bool refused_pass_1 = true;
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      shadow_target.begin(cmd);
                      EXPECT_TRUE(model.draw(cmd, light.set(), "h6", glm::mat4(1.0f), 0));
                      refused_pass_1 = !model.draw(cmd, light.set(), "h6", glm::mat4(1.0f), 1);
                      vkCmdEndRenderPass(cmd);
                  });
    EXPECT_TRUE(refused_pass_1) << "pass 1 was never added";
    const std::vector<float> depth = shadow_target.read();
    const uint32_t c = kSize / 2, corner = 2;
    EXPECT_NEAR(depth[c * kSize + c], 0.4f, 1e-6f) << "the table's top (z = 0.5)";
    EXPECT_NEAR(depth[(c - 4) * kSize + 6], 0.6f, 1e-6f) << "the floor (z = 0)";
    EXPECT_EQ(depth[corner * kSize + corner], 1.0f) << "outside the level";
}
