// render::EnvironmentLighting's refusals (environment_lighting.h), under validation: every
// std::invalid_argument the constructor and record_update() throw, each made by one change to a set-up that
// is accepted (and uploads and updates cleanly), so that each refusal is the change's doing. The inconsistent
// assets are a few of io::envmap_problem's (tests/io/envmap_asset_test.cpp goes through every one).
#include "../gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/math/brdf.h>
#include <hemi/render/material/environment_lighting.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/view/offscreen.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
class EnvironmentLightingRefusals : public hemi::test::GpuTest
{
};

hemi::math::ParabolicImage map(uint32_t size, float value)
{
    hemi::math::ParabolicImage m;
    m.size = size;
    m.extent = 1.0;
    m.rgb.assign(size_t(2) * size * size * 3, value);
    return m;
}

// A 4 x 4 mirror chain, glossy maps at exponents 8 and 30, Fresnel tables at 1.5 and 2.4.
hemi::io::EnvmapAsset environment()
{
    hemi::io::EnvmapAsset a;
    a.mirror = {map(4, 1.0f), map(2, 1.0f), map(1, 1.0f)};
    a.exponents = {8.0f, 30.0f};
    a.glossy = {map(4, 0.5f), map(2, 0.25f)};
    a.diffuse = map(2, 0.2f);
    a.iors = {1.5f, 2.4f};
    a.fresnel_samples = 3;
    a.fresnel = {1.0f, 0.5f, 0.04f, 1.0f, 0.6f, 0.17f};
    return a;
}
} // namespace

TEST_F(EnvironmentLightingRefusals, EveryRefusalNamesTheProblem)
{
    const hemi::gpu::Device& dev = hemi::test::device();
    hemi::render::OffscreenTarget target(dev, 8, 8);
    hemi::render::MaterialSystem system(dev, target.desc());
    const hemi::io::EnvmapAsset env = environment();
    const std::vector<hemi::math::BrdfTable> ts = hemi::math::torrance_sparrow_tables(
        hemi::math::TorranceSparrow(hemi::math::FacetDistribution::Beckmann, 0.3, 1.5), 8);
    const std::vector<hemi::math::BrdfTable> banks = {hemi::math::banks_table(30.0, 8)};
    hemi::render::EnvironmentMaterial material;
    material.glossy = 1;
    material.fresnel = 1;
    material.world_to_env = glm::mat3(glm::rotate(glm::mat4(1.0f), 0.7f, glm::vec3(0.3f, 0.4f, 0.8f)));

    // Accepted as they are: Torrance-Sparrow's tables, Banks' table and none; uploaded and updated.
    for (const std::vector<hemi::math::BrdfTable>* brdf :
         {&ts, &banks, static_cast<const std::vector<hemi::math::BrdfTable>*>(nullptr)})
    {
        hemi::gpu::UploadBatch upload(dev);
        const hemi::render::EnvironmentLighting lighting(system, env,
                                                         brdf ? std::span<const hemi::math::BrdfTable>(*brdf)
                                                              : std::span<const hemi::math::BrdfTable>(),
                                                         material, upload);
        EXPECT_NE(lighting.set(), VkDescriptorSet(VK_NULL_HANDLE));
        hemi::gpu::one_shot(dev,
                            [&](VkCommandBuffer cmd)
                            {
                                upload.record(cmd);
                                lighting.record_update(cmd, material);
                            });
    }

    struct Case
    {
        const char* name;
        std::function<void(hemi::io::EnvmapAsset&, std::vector<hemi::math::BrdfTable>&,
                           hemi::render::EnvironmentMaterial&)>
            change;
        std::string what;
    };
    using Env = hemi::io::EnvmapAsset;
    using Tables = std::vector<hemi::math::BrdfTable>;
    using Material = hemi::render::EnvironmentMaterial;
    const Case cases[] = {
        {"no_mirror", [](Env& e, Tables&, Material&) { e.mirror.clear(); },
         "an inconsistent environment: no mirror map"},
        {"mirror_level", [](Env& e, Tables&, Material&) { e.mirror[1].rgb.pop_back(); },
         "an inconsistent environment: mirror level 1 has the wrong size"},
        {"exponent", [](Env& e, Tables&, Material&) { e.exponents[0] = -1.0f; },
         "an inconsistent environment: a glossy map's exponent is not > 0"},
        {"fresnel_sizes", [](Env& e, Tables&, Material&) { e.fresnel.pop_back(); },
         "an inconsistent environment: the Fresnel tables' sizes disagree"},
        {"glossy_index", [](Env&, Tables&, Material& m) { m.glossy = 2; },
         "glossy map 2 of an environment with 2"},
        {"fresnel_index", [](Env&, Tables&, Material& m) { m.fresnel = 7; },
         "Fresnel table 7 of an environment with 2"},
        {"table_sizes", [](Env&, Tables& t, Material&) { t[1] = hemi::math::banks_table(30.0, 16); },
         "the BRDF tables of one material must all have one size (>= 2)"},
        {"table_of_1",
         [](Env&, Tables& t, Material&)
         {
             for (hemi::math::BrdfTable& table : t)
             {
                 table.size = 1;
                 table.values.resize(table.channels);
             }
         },
         "must all have one size (>= 2)"},
        {"table_short", [](Env&, Tables& t, Material&) { t[1].values.pop_back(); }, "channels holds"},
        {"three_tables", [](Env&, Tables& t, Material&) { t.push_back(t[0]); },
         "BRDF tables must be Torrance-Sparrow's two (FD, G) or Banks' one"},
        {"one_channel_alone", [](Env&, Tables& t, Material&) { t.pop_back(); },
         "BRDF tables must be Torrance-Sparrow's two (FD, G) or Banks' one"},
        {"table_nan", [](Env&, Tables& t, Material&) { t[1].values[5] = NAN; },
         "a BRDF table value does not fit a half float"},
        {"table_1e5", [](Env&, Tables& t, Material&) { t[0].values[0] = 1e5f; },
         "a BRDF table value does not fit a half float"},
        {"kd_nan", [](Env&, Tables&, Material& m) { m.kd = NAN; }, "kd and ks must be finite"},
        {"ks_inf", [](Env&, Tables&, Material& m) { m.ks = INFINITY; }, "kd and ks must be finite"},
        {"scaled", [](Env&, Tables&, Material& m) { m.world_to_env *= 1.01f; }, "must be a rotation"},
        {"sheared", [](Env&, Tables&, Material& m) { m.world_to_env[1][0] += 0.1f; }, "must be a rotation"},
        {"rotation_nan", [](Env&, Tables&, Material& m) { m.world_to_env[2][2] = NAN; },
         "must be a rotation"},
        {"box_without_probes", [](Env&, Tables&, Material& m) { m.box_projection = true; },
         "box projection needs 1 to 4 probes, not 0"},
        {"box_inverted",
         [](Env&, Tables&, Material& m)
         {
             m.box_projection = true;
             m.probes = {{glm::vec3(0.0f), glm::vec3(1.0f), glm::vec3(-1.0f)}};
         },
         "a box whose minimum is below its maximum"},
        {"box_fade",
         [](Env&, Tables&, Material& m)
         {
             m.box_projection = true;
             m.probes = {{glm::vec3(0.0f), glm::vec3(-1.0f), glm::vec3(1.0f), -0.5f}};
         },
         "a fade of 0 or more"},
        {"two_boxes_one_probe",
         [](Env&, Tables&, Material& m)
         {
             m.box_projection = true;
             m.probes = {{glm::vec3(0.0f), glm::vec3(-1.0f), glm::vec3(1.0f)},
                         {glm::vec3(0.5f), glm::vec3(-1.0f), glm::vec3(2.0f)}};
         },
         "the environment's maps hold 1 reflection probes and the material gives 2 probes' boxes"},
    };
    for (const Case& c : cases)
    {
        Env e = env;
        Tables t = ts;
        Material m = material;
        c.change(e, t, m);
        hemi::gpu::UploadBatch upload(dev); // never recorded: a refused set-up's images are gone
        try
        {
            const hemi::render::EnvironmentLighting lighting(system, e, t, m, upload);
            ADD_FAILURE() << c.name << " was accepted";
        }
        catch (const std::invalid_argument& x)
        {
            EXPECT_NE(std::string(x.what()).find(c.what), std::string::npos) << c.name << ": " << x.what();
        }
    }

    // record_update() refuses what the constructor refuses of a material, and records nothing then.
    hemi::gpu::UploadBatch upload(dev);
    const hemi::render::EnvironmentLighting lighting(system, env, ts, material, upload);
    hemi::gpu::one_shot(dev,
                        [&](VkCommandBuffer cmd)
                        {
                            upload.record(cmd);
                            for (const Case& c : cases)
                            {
                                const std::string name = c.name;
                                if (name != "kd_nan" && name != "ks_inf" && name != "scaled" &&
                                    name != "sheared" && name != "rotation_nan")
                                    continue;
                                Env e = env;
                                Tables t = ts;
                                Material m = material;
                                c.change(e, t, m);
                                try
                                {
                                    lighting.record_update(cmd, m);
                                    ADD_FAILURE() << "record_update accepted " << c.name;
                                }
                                catch (const std::invalid_argument& x)
                                {
                                    EXPECT_NE(std::string(x.what()).find(c.what), std::string::npos)
                                        << c.name << ": " << x.what();
                                }
                            }
                            lighting.record_update(cmd, material);
                        });
}

namespace
{
class EnvironmentMapsSharing : public hemi::test::GpuTest
{
};
} // namespace

// Materials lit by one environment share its maps (render::EnvironmentMaps): the maps are uploaded once,
// each material adds only its BRDF tables and uniform block (exactly the bytes a material with maps of its
// own adds beyond those maps), and each binds the glossy map of its own exponent. A library that uploaded
// the maps per material would add their bytes for each of the 8 materials.
TEST_F(EnvironmentMapsSharing, MaterialsShareOneUploadOfTheMaps)
{
    const hemi::gpu::Device& dev = hemi::test::device();
    hemi::render::OffscreenTarget target(dev, 8, 8);
    hemi::render::MaterialSystem system(dev, target.desc());
    const hemi::io::EnvmapAsset env = environment();
    const std::vector<hemi::math::BrdfTable> ts = hemi::math::torrance_sparrow_tables(
        hemi::math::TorranceSparrow(hemi::math::FacetDistribution::Beckmann, 0.3, 1.5), 8);
    hemi::gpu::UploadBatch upload(dev);
    auto used = [&] { return dev.allocator().stats().used_bytes; };

    const VkDeviceSize before = used();
    const auto maps = std::make_shared<const hemi::render::EnvironmentMaps>(dev, env, upload);
    const VkDeviceSize maps_bytes = used() - before;
    std::vector<std::unique_ptr<hemi::render::EnvironmentLighting>> materials;
    const VkDeviceSize before_materials = used();
    for (uint32_t i = 0; i < 8; ++i)
    {
        hemi::render::EnvironmentMaterial m;
        m.kd = 0.1f * float(i);
        m.glossy = i % 2;
        m.fresnel = i % 2;
        materials.push_back(std::make_unique<hemi::render::EnvironmentLighting>(system, maps, ts, m, upload));
        EXPECT_EQ(materials.back()->mirror_map().handle(), maps->mirror_map().handle());
        EXPECT_EQ(materials.back()->glossy_map().handle(), maps->glossy_map(i % 2).handle());
        EXPECT_EQ(materials.back()->maps().get(), maps.get());
    }
    const VkDeviceSize per_material = (used() - before_materials) / 8;
    EXPECT_NE(maps->glossy_map(0).handle(), maps->glossy_map(1).handle());

    const VkDeviceSize before_own = used();
    const hemi::render::EnvironmentLighting own(system, env, ts, hemi::render::EnvironmentMaterial{}, upload);
    EXPECT_NE(own.mirror_map().handle(), maps->mirror_map().handle());
    EXPECT_EQ(used() - before_own, maps_bytes + per_material)
        << "a material over shared maps should add only its own tables and uniforms";
    hemi::gpu::one_shot(dev, [&](VkCommandBuffer cmd) { upload.record(cmd); });
}
