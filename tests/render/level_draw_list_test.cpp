// A level as an engine sees it: the technique is a property of each material (io::Material::technique, from
// glTF's extras or overridden at load), the level's draw list carries each primitive's technique, pipeline
// and bounds, and draws with a lightmap scale/offset let several objects share one atlas.
#include "../gpu_fixture.h"

#include "engine_pass.h"
#include "table_level.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/gpu/commands.h>
#include <hemi/math/camera.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/scene/lightmap_model.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstring>

namespace
{
using namespace hemi;

class LevelDrawList : public test::GpuTest
{
};

constexpr uint32_t kSize = 64;

// The tests' table level (table_level.h): the floor (material "floor") and the top as a wall-like primitive
// (material "ssbump wall", its normal slot an SSBump texel, technique "ssbump"), baked into H4 and rnm.
io::LightmapAsset level()
{
    io::Material floor, wall;
    floor.name = "floor";
    floor.base_color_factor = glm::vec4(0.8f, 0.7f, 0.6f, 1.0f);
    wall.name = "ssbump wall";
    wall.base_color_factor = glm::vec4(0.6f, 0.7f, 0.8f, 1.0f);
    wall.normal.image = 0;
    wall.technique = "ssbump";
    // The SSBump texel: weights (0.2, 0.5, 0.3) of Valve's three directions.
    return test::table_level(floor, wall,
                             {{"ssbump.png", "image/png", io::encode_png({1, 1, {51, 128, 77, 255}})}},
                             {"h4", "rnm"});
}

} // namespace

// The level drawn with the default "h4": the wall's pixels are what an all-SSBump drawing gives, the floor's
// what an all-H4 drawing gives, with no per-primitive decision in the caller; the draw list says so entry by
// entry, with the primitives' bounds.
TEST_F(LevelDrawList, EachMaterialDrawsInItsOwnTechniqueThroughTheLevelsDrawList)
{
    gpu::Device& dev = test::device();
    const io::LightmapAsset asset = level();
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    const render::LightmapModel model(system, asset, {"h4"}, upload);
    // References: every material overridden to one technique.
    const render::LightmapModel all_h4(system, asset, {"h4"}, upload, {{"ssbump wall", ""}});
    const render::LightmapModel all_ssbump(system, asset, {"ssbump"}, upload, {{"floor", "ssbump"}});

    const std::vector<render::LightmapDraw> list = model.draw_list("h4");
    ASSERT_EQ(list.size(), 2u);
    EXPECT_EQ(*list[0].technique, "h4");
    EXPECT_EQ(*list[1].technique, "ssbump");
    EXPECT_EQ(list[1].material->name, "ssbump wall");
    EXPECT_NE(list[0].type, list[1].type);
    EXPECT_EQ(list[0].bounds_min, glm::vec3(-1.0f, -1.0f, 0.0f));
    EXPECT_EQ(list[0].bounds_max, glm::vec3(1.0f, 1.0f, 0.0f));
    EXPECT_EQ(list[1].bounds_min, glm::vec3(-0.5f, -0.5f, 0.5f));
    EXPECT_EQ(list[1].bounds_max, glm::vec3(0.5f, 0.5f, 0.5f));

    render::FrameSet camera(system);
    render::FrameData view;
    view.eye = glm::vec3(0.3f, -1.5f, 3.0f);
    view.view_projection = math::look_at_projection(view.eye, glm::vec3(0.0f), 45.0f, 1.0f);
    const float clear[4] = {0, 0, 0, 0};
    auto render = [&](const render::LightmapModel& m, const std::string& technique)
    {
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          upload.record(cmd);
                          camera.record_update(cmd, view);
                          pass.begin(cmd, clear);
                          m.draw(cmd, camera.set(), technique, glm::mat4(1.0f));
                          vkCmdEndRenderPass(cmd);
                      });
        return pass.read_color();
    };
    const std::vector<float> mixed = render(model, "h4"), h4 = render(all_h4, "h4"),
                             ssbump = render(all_ssbump, "ssbump");
    // Pixels classified by where the ray through them meets the level (the wall above the floor).
    const glm::mat4 inverse = glm::inverse(view.view_projection);
    int wall = 0, floor = 0;
    auto same = [](const float* a, const float* b)
    {
        for (int c = 0; c < 3; ++c)
            if (std::abs(a[c] - b[c]) > 0.005f * std::abs(b[c]) + 1e-5f)
                return false;
        return true;
    };
    for (uint32_t y = 1; y + 1 < kSize; ++y)
        for (uint32_t x = 1; x + 1 < kSize; ++x)
        {
            const glm::vec2 ndc((x + 0.5f) / kSize * 2.0f - 1.0f, (y + 0.5f) / kSize * 2.0f - 1.0f);
            const glm::vec4 a0 = inverse * glm::vec4(ndc, 0.0f, 1.0f),
                            a1 = inverse * glm::vec4(ndc, 1.0f, 1.0f);
            const glm::vec3 o = glm::vec3(a0) / a0.w, d = glm::vec3(a1) / a1.w - o;
            const glm::vec3 at_wall = o + d * ((0.5f - o.z) / d.z), at_floor = o + d * (-o.z / d.z);
            const size_t p = (size_t(y) * kSize + x) * 4;
            if (std::abs(at_wall.x) < 0.47f && std::abs(at_wall.y) < 0.47f)
            {
                ++wall;
                EXPECT_TRUE(same(&mixed[p], &ssbump[p])) << "wall pixel " << x << "," << y;
                EXPECT_FALSE(same(&mixed[p], &h4[p])) << "wall pixel " << x << "," << y << " looks H4";
            }
            else if (std::abs(at_wall.x) > 0.53f || std::abs(at_wall.y) > 0.53f)
            {
                if (std::abs(at_floor.x) > 0.97f || std::abs(at_floor.y) > 0.97f ||
                    (std::abs(at_floor.x) < 0.53f && std::abs(at_floor.y) < 0.53f))
                    continue; // off the level, or the floor under the wall
                ++floor;
                EXPECT_TRUE(same(&mixed[p], &h4[p])) << "floor pixel " << x << "," << y;
            }
        }
    EXPECT_GT(wall, 100);
    EXPECT_GT(floor, 300);
}

// One atlas, two objects: the coefficient maps hold red irradiance in their left half and blue in their
// right; two quads with TEXCOORD_1 over [0, 1]^2 drawn with the scale/offset of the left and the right
// rectangle are each lit by their own half only (without scale/offset both would show the red-to-blue ramp).
TEST_F(LevelDrawList, ObjectsSharingOneAtlasEachSampleTheirOwnRectangle)
{
    gpu::Device& dev = test::device();
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    io::Mesh quad;
    quad.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    quad.normals.assign(4, glm::vec3(0, -1, 0));
    quad.tangents.assign(4, glm::vec4(1, 0, 0, 1));
    quad.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    quad.uvs1 = quad.uvs;
    quad.indices = {0, 1, 2, 0, 2, 3};
    const render::GpuMesh mesh(dev, quad, upload);
    const io::Material white;
    render::TextureSet textures(dev, std::span<const io::ImageRgba8>(), std::span<const io::Material>(),
                                upload);
    const render::MaterialInstance instance(system, textures, white, upload);
    // 8 x 2 texels, K = 1 (the plain lightmap: the coefficient is the irradiance): columns 0-3 pi (1, 0, 0),
    // columns 4-7 pi (0, 0, 1), so colour = albedo E / pi is pure red or pure blue.
    const float pi = float(M_PI);
    std::vector<float> rgb(8 * 2 * 3, 0.0f);
    for (uint32_t y = 0; y < 2; ++y)
        for (uint32_t x = 0; x < 8; ++x)
            rgb[(y * 8 + x) * 3 + (x < 4 ? 0 : 2)] = pi;
    const render::TexelCoefficients atlas(system, 8, 2, 1, rgb, upload, true);
    render::MaterialKey key;
    key.source = render::CoefficientSourceKind::Texel;
    key.basis = HEMI_BASIS_VERTEX_IRRADIANCE;
    const render::MaterialType& type = system.type(key);
    // Room for two instance records: the same two objects are drawn again as one instanced draw.
    render::FrameSet frame(system, 1, 2);
    render::FrameData f;
    f.view_projection = math::look_at_projection(glm::vec3(0, -6, 0), glm::vec3(0.0f), 45.0f, 1.0f);
    // Left rectangle: u in [1/16, 7/16] (inside texel centres 0..3); right: u in [9/16, 15/16].
    const glm::vec4 left(0.375f, 1.0f, 0.0625f, 0.0f), right(0.375f, 1.0f, 0.5625f, 0.0f);
    auto placement = [](int object)
    { return glm::translate(glm::mat4(1.0f), glm::vec3(object ? 1.2f : -1.2f, 0, 0)); };
    const shared::DrawPush records[2] = {render::LightmapModel::instance_record(placement(0), left),
                                         render::LightmapModel::instance_record(placement(1), right)};
    frame.write_instances(0, records);
    const float clear[4] = {0, 0, 0, 0};
    auto draw = [&](bool instanced)
    {
        render::DrawStats stats;
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          upload.record(cmd);
                          frame.record_update(cmd, f);
                          pass.begin(cmd, clear);
                          if (instanced)
                          {
                              render::DrawPacket p;
                              p.type = &type;
                              p.frame = frame.set();
                              p.material = instance.set();
                              p.source = atlas.set();
                              p.mesh = &mesh.binding();
                              p.index_count = mesh.index_count();
                              render::make_instanced(p, 0, 2);
                              stats = render::record_packets(cmd, {&p, 1});
                          }
                          else
                              for (int object = 0; object < 2; ++object)
                              {
                                  render::DrawBindings b;
                                  b.type = &type;
                                  b.frame = frame.set();
                                  b.material = instance.set();
                                  b.source = atlas.set();
                                  b.push.model = placement(object);
                                  b.push.lightmap_scale_offset = object ? right : left;
                                  render::bind_material(cmd, b);
                                  mesh.bind(cmd);
                                  mesh.draw(cmd, 0, mesh.index_count());
                                  ++stats.draws;
                              }
                          vkCmdEndRenderPass(cmd);
                      });
        upload.clear();
        EXPECT_EQ(stats.draws, instanced ? 1u : 2u);
        return pass.read_color();
    };
    const std::vector<float> image = draw(false);
    // One instanced draw reading both objects' placement and rectangle from the instance records draws the
    // same pixels (a shader that read every instance's values from the push, or instance 0's for all, would
    // draw one object, or both red).
    EXPECT_EQ(draw(true), image) << "the instanced draw differs from the two draws";
    int red = 0, blue = 0;
    for (uint32_t y = 0; y < kSize; ++y)
        for (uint32_t x = 0; x < kSize; ++x)
        {
            const float* p = &image[(size_t(y) * kSize + x) * 4];
            if (p[3] == 0.0f)
                continue;
            const bool left_object = x < kSize / 2;
            const glm::vec3 want = left_object ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(p[c], want[c], 0.005f)
                    << (left_object ? "left" : "right") << " object at " << x << "," << y;
            (left_object ? red : blue)++;
        }
    EXPECT_GT(red, 200);
    EXPECT_GT(blue, 200);
}
