// hemi-bake export: a baked level as glTF, read back with tinygltf's own loader (which decodes the PNGs with
// its stb_image, not hemi's reader) and the RGBM formula typed here, against the asset the bake wrote. With
// HEMI_GLTF_VALIDATOR set (CI's .ci/gltf_export sets it to a script that runs the Khronos glTF validator
// from npm), the file must also pass the validator with no error and no warning; with HEMI_THREEJS_SHOT set
// (docs/threejs/shot.mjs, which the same script installs), three.js must draw it as hemi-render draws the
// asset.
#include "../temp_dir.h"
#include "post_scene.h"
#include "run_tool.h"

#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>

#include <glm/gtc/packing.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("export_test");
}

using hemi::test::q;
using hemi::test::Result;

Result bake(const std::string& args)
{
    return hemi::test::run(dir(), HEMI_BAKE_EXE, args);
}

// The glTF file as the Khronos validator's JSON report sees it: its error and warning counts.
std::pair<int, int> validate(const fs::path& file, const std::string& validator)
{
    const fs::path report = dir() / "validator_report.json";
    const Result r = hemi::test::run(dir(), "node", q(validator) + " " + q(file) + " " + q(report));
    EXPECT_EQ(r.status, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(report));
    return {j["issues"]["numErrors"].get<int>(), j["issues"]["numWarnings"].get<int>()};
}

} // namespace

// The form: a level baked with a sun, a bounce and probes, exported; every material names the RGBM
// lightmap on TEXCOORD_1 with its range, every texel decodes within RGBM's stated precision, and every output
// and the probes are the asset's own values, bit for bit.
TEST(HemiBakeExport, WritesTheLevelsLightmapsIntoAGlbThatDecodesBack)
{
    const fs::path scene = hemi::test::write_post_scene(dir() / "post.glb"), asset = dir() / "post.hemi",
                   glb = dir() / "post_lit.glb";
    const Result b =
        bake("lightmap " + q(scene) + " -o " + q(asset) +
             " --env uniform --env-scale 0.5 --sun 0.4,0.3,1,4,3.6,3 --bounces 1 --size 64 --rays "
             "32 --probes 3,2,2 --probe-rays 64 --reflection-probe 0.2,1,0.3 --reflection-size 16 "
             "--reflection-rays 1 --reflection-exponents 10,50");
    ASSERT_EQ(b.status, 0) << b.err;
    const Result e = bake("export " + q(asset) + " -o " + q(glb));
    ASSERT_EQ(e.status, 0) << e.err;
    EXPECT_EQ(e.err, "") << "nothing clipped with the default range";
    EXPECT_NE(e.out.find("wrote"), std::string::npos) << e.out;
    const hemi::io::LightmapAsset a = hemi::io::read_lightmap_asset(asset);

    tinygltf::Model m;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, glb.string())) << err;
    EXPECT_EQ(err, "");
    EXPECT_EQ(warn, "");

    // The lightmap: one texture, named by every material with the same range.
    ASSERT_EQ(m.materials.size(), 2u);
    int texture = -1;
    double range = 0.0;
    for (const tinygltf::Material& mat : m.materials)
    {
        ASSERT_TRUE(mat.extras.Has("lightmap")) << mat.name;
        const tinygltf::Value& l = mat.extras.Get("lightmap");
        EXPECT_EQ(l.Get("texCoord").GetNumberAsInt(), 1);
        EXPECT_EQ(l.Get("encoding").Get<std::string>(), "RGBM");
        if (texture < 0)
        {
            texture = l.Get("index").GetNumberAsInt();
            range = l.Get("range").GetNumberAsDouble();
        }
        EXPECT_EQ(l.Get("index").GetNumberAsInt(), texture);
        EXPECT_EQ(l.Get("range").GetNumberAsDouble(), range);
    }
    EXPECT_EQ(m.materials[0].extras.Get("hemi_technique").Get<std::string>(), "sh9")
        << "the scene's extras kept";
    ASSERT_GE(texture, 0);
    ASSERT_LT(size_t(texture), m.textures.size());
    const tinygltf::Image& image = m.images[size_t(m.textures[size_t(texture)].source)];
    ASSERT_EQ(image.width, int(a.width));
    ASSERT_EQ(image.height, int(a.height));
    ASSERT_EQ(image.component, 4);
    ASSERT_EQ(image.bits, 8);
    const tinygltf::Sampler& sampler = m.samplers[size_t(m.textures[size_t(texture)].sampler)];
    EXPECT_EQ(sampler.minFilter, TINYGLTF_TEXTURE_FILTER_LINEAR) << "no mipmaps across charts";
    EXPECT_EQ(sampler.wrapS, TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE);

    // Every texel: E = rgb / 255 * a / 255 * range, within (brightest channel + range / 255) / 510.
    const hemi::io::LightmapOutput& plain = a.output("plain");
    float brightest = 0.0f;
    size_t lit = 0;
    for (uint32_t y = 0; y < a.height; ++y)
        for (uint32_t x = 0; x < a.width; ++x)
        {
            const glm::vec3 baked = plain.maps.at(0, x, y);
            const unsigned char* p = &image.image[(size_t(y) * a.width + x) * 4];
            const float mx = std::max({baked.r, baked.g, baked.b});
            brightest = std::max(brightest, mx);
            lit += mx > 0.0f;
            const double bound = (mx + range / 255.0) / 510.0 * (1.0 + 1e-5);
            for (int c = 0; c < 3; ++c)
            {
                const double decoded = p[c] / 255.0 * (p[3] / 255.0) * range;
                ASSERT_NEAR(decoded, baked[c], bound) << "texel " << x << ", " << y << " channel " << c;
            }
        }
    EXPECT_EQ(float(range), brightest) << "the default range is the brightest channel";
    EXPECT_GT(lit, size_t(a.covered_texels)) << "covered and dilated texels are lit";

    // The base colour image, byte for byte.
    const tinygltf::Material& floor = m.materials[0];
    const int base = m.textures[size_t(floor.pbrMetallicRoughness.baseColorTexture.index)].source;
    const tinygltf::BufferView& bv = m.bufferViews[size_t(m.images[size_t(base)].bufferView)];
    const std::vector<uint8_t> stored(m.buffers[0].data.begin() + long(bv.byteOffset),
                                      m.buffers[0].data.begin() + long(bv.byteOffset + bv.byteLength));
    EXPECT_EQ(stored, a.images[0].bytes);

    // HEMI_lightmaps: every output of the asset, its half floats as the asset holds them.
    EXPECT_NE(std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), "HEMI_lightmaps"),
              m.extensionsUsed.end());
    EXPECT_TRUE(m.extensionsRequired.empty());
    ASSERT_TRUE(m.extensions.count("HEMI_lightmaps"));
    const tinygltf::Value& ext = m.extensions.at("HEMI_lightmaps");
    EXPECT_EQ(ext.Get("width").GetNumberAsInt(), int(a.width));
    EXPECT_EQ(ext.Get("height").GetNumberAsInt(), int(a.height));
    EXPECT_EQ(ext.Get("rgbm").Get("index").GetNumberAsInt(), texture);
    const tinygltf::Value& outputs = ext.Get("outputs");
    ASSERT_EQ(outputs.ArrayLen(), a.outputs.size());
    for (size_t i = 0; i < a.outputs.size(); ++i)
    {
        const hemi::io::LightmapOutput& o = a.outputs[i];
        const tinygltf::Value& out = outputs.Get(int(i));
        EXPECT_EQ(out.Get("name").Get<std::string>(), o.name);
        ASSERT_EQ(out.Get("coefficients").GetNumberAsInt(), int(o.k));
        EXPECT_EQ(out.Get("format").Get<std::string>(), "RGB16F");
        const float scale = float(out.Get("scale").GetNumberAsDouble());
        EXPECT_EQ(scale, 1.0f) << o.name << ": light in the ordinary range is stored as it is";
        const tinygltf::BufferView& v = m.bufferViews[size_t(out.Get("bufferView").GetNumberAsInt())];
        ASSERT_EQ(v.byteLength, size_t(o.k) * a.width * a.height * 6) << o.name;
        const uint8_t* bytes = m.buffers[0].data.data() + v.byteOffset;
        size_t differ = 0;
        for (uint32_t k = 0; k < o.k; ++k)
            for (uint32_t y = 0; y < a.height; ++y)
                for (uint32_t x = 0; x < a.width; ++x)
                    for (int c = 0; c < 3; ++c)
                    {
                        uint16_t h;
                        std::memcpy(&h, bytes + (((size_t(k) * a.height + y) * a.width + x) * 3 + c) * 2, 2);
                        differ += glm::unpackHalf1x16(h) * scale != o.maps.at(k, x, y)[c];
                    }
        EXPECT_EQ(differ, 0u) << o.name;
    }
    // The probes, as the asset has them.
    const tinygltf::Value& probes = ext.Get("probes");
    ASSERT_TRUE(probes.IsObject());
    EXPECT_EQ(probes.Get("count").Get(0).GetNumberAsInt(), 3);
    EXPECT_EQ(probes.Get("count").Get(1).GetNumberAsInt(), 2);
    EXPECT_EQ(probes.Get("count").Get(2).GetNumberAsInt(), 2);
    for (int c = 0; c < 3; ++c)
    {
        EXPECT_FLOAT_EQ(float(probes.Get("min").Get(c).GetNumberAsDouble()), a.probes.lo[c]);
        EXPECT_FLOAT_EQ(float(probes.Get("max").Get(c).GetNumberAsDouble()), a.probes.hi[c]);
    }
    const tinygltf::BufferView& valid = m.bufferViews[size_t(probes.Get("valid").GetNumberAsInt())];
    ASSERT_EQ(valid.byteLength, a.probes.valid.size());
    EXPECT_EQ(
        std::memcmp(m.buffers[0].data.data() + valid.byteOffset, a.probes.valid.data(), valid.byteLength), 0);
    const tinygltf::BufferView& pv = m.bufferViews[size_t(probes.Get("irradiance").GetNumberAsInt())];
    ASSERT_EQ(pv.byteLength, a.probes.irradiance.size() * 9 * 12);
    EXPECT_EQ(
        std::memcmp(m.buffers[0].data.data() + pv.byteOffset, a.probes.irradiance.data(), pv.byteLength), 0);
    // Their depth maps, as the asset has them (8 x 8 texels of mean and deviation a probe).
    const tinygltf::Value& depth = probes.Get("depth");
    ASSERT_TRUE(depth.IsObject());
    EXPECT_EQ(depth.Get("resolution").GetNumberAsInt(), 8);
    EXPECT_FLOAT_EQ(float(depth.Get("maxDistance").GetNumberAsDouble()), a.probes.max_distance);
    const tinygltf::BufferView& dv = m.bufferViews[size_t(depth.Get("bufferView").GetNumberAsInt())];
    ASSERT_EQ(dv.byteLength, a.probes.depth.size() * 8);
    ASSERT_EQ(a.probes.depth.size(), 12u * 64u);
    EXPECT_EQ(std::memcmp(m.buffers[0].data.data() + dv.byteOffset, a.probes.depth.data(), dv.byteLength), 0);

    // The reflection probe (issue 44): its centre, box and maps, the asset's floats bit for bit.
    const tinygltf::Value& reflections = ext.Get("reflectionProbes");
    ASSERT_TRUE(reflections.IsArray());
    ASSERT_EQ(reflections.ArrayLen(), 1u);
    ASSERT_EQ(a.reflections.size(), 1u);
    const tinygltf::Value& r = reflections.Get(0);
    for (int c = 0; c < 3; ++c)
    {
        EXPECT_FLOAT_EQ(float(r.Get("centre").Get(c).GetNumberAsDouble()), a.reflections[0].centre[c]);
        EXPECT_FLOAT_EQ(float(r.Get("boxMin").Get(c).GetNumberAsDouble()), a.reflections[0].box_min[c]);
        EXPECT_FLOAT_EQ(float(r.Get("boxMax").Get(c).GetNumberAsDouble()), a.reflections[0].box_max[c]);
    }
    auto same_map = [&](const tinygltf::Value& v, const hemi::math::ParabolicImage& map, const char* what)
    {
        EXPECT_EQ(v.Get("size").GetNumberAsInt(), int(map.size)) << what;
        EXPECT_DOUBLE_EQ(v.Get("extent").GetNumberAsDouble(), map.extent) << what;
        const tinygltf::BufferView& view = m.bufferViews[size_t(v.Get("bufferView").GetNumberAsInt())];
        ASSERT_EQ(view.byteLength, size_t(2) * map.size * map.size * 3 * 4) << what;
        EXPECT_EQ(std::memcmp(m.buffers[0].data.data() + view.byteOffset, map.rgb.data(), view.byteLength), 0)
            << what;
    };
    same_map(r.Get("mirror"), a.reflections[0].maps.mirror[0], "mirror");
    ASSERT_EQ(r.Get("glossy").ArrayLen(), 2u);
    for (int g = 0; g < 2; ++g)
    {
        EXPECT_DOUBLE_EQ(r.Get("glossy").Get(g).Get("exponent").GetNumberAsDouble(), g == 0 ? 10.0 : 50.0);
        same_map(r.Get("glossy").Get(g), a.reflections[0].maps.glossy[size_t(g)], "glossy");
    }
    same_map(r.Get("diffuse"), a.reflections[0].maps.diffuse, "diffuse");

    // The geometry reads back (hemi's reader) with the asset's lightmap UVs.
    const hemi::io::GltfScene back = hemi::io::read_gltf(glb);
    EXPECT_EQ(back.mesh.uvs1, a.mesh.uvs1);
    EXPECT_EQ(back.mesh.positions, a.mesh.positions);

    if (const char* validator = std::getenv("HEMI_GLTF_VALIDATOR"))
    {
        const auto [errors, warnings] = validate(glb, validator);
        EXPECT_EQ(errors, 0) << "Khronos glTF validator, " << glb;
        EXPECT_EQ(warnings, 0) << "Khronos glTF validator, " << glb;
    }

    // An independent renderer: three.js (docs/threejs/index.html, the loader docs/gltf_export.md shows) draws
    // the .glb as hemi-render draws the asset's plain lightmap, from the same camera. three.js's diffuse
    // gives the share its specular layer reflects (F0 = 0.04) to that layer, so it is a few per cent darker.
    if (const char* shot = std::getenv("HEMI_THREEJS_SHOT"))
    {
        const fs::path ours = dir() / "post_hemi.png", theirs = dir() / "post_three.png";
        const Result h = hemi::test::run(dir(), HEMI_RENDER_EXE,
                                         q(asset) +
                                             " --technique plain --camera 1.2,-1.7,1.3,0,0,0.3 --size "
                                             "320x200 -o " +
                                             q(ours),
                                         "HEMI_VALIDATION=1");
        ASSERT_EQ(h.status, 0) << h.err;
        // The same camera in the glTF's frame (world (x, y, z) is glTF (x, z, -y)).
        const Result t = hemi::test::run(
            dir(), "node", q(shot) + " " + q(glb) + " " + q(theirs) + " 320x200 1.2,1.3,1.7 0,0.3,0");
        ASSERT_EQ(t.status, 0) << t.err << t.out;
        const hemi::io::ImageRgba8 a8 = hemi::io::read_png(ours), b8 = hemi::io::read_png(theirs);
        ASSERT_EQ(a8.width, b8.width);
        ASSERT_EQ(a8.height, b8.height);
        auto linear = [](uint8_t c)
        {
            const double v = c / 255.0;
            return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
        };
        double sum_a = 0.0, sum_b = 0.0;
        std::vector<std::array<double, 2>> pairs;
        for (size_t i = 0; i < a8.pixels.size(); i += 4)
        {
            const uint8_t* pa = &a8.pixels[i];
            const uint8_t* pb = &b8.pixels[i];
            const uint8_t ma = std::max({pa[0], pa[1], pa[2]}), mb = std::max({pb[0], pb[1], pb[2]});
            if (mb < 5 || ma == 255 || mb == 255)
                continue; // three.js's black background, or clipped in either
            for (int c = 0; c < 3; ++c)
            {
                pairs.push_back({linear(pa[c]), linear(pb[c])});
                sum_a += pairs.back()[0];
                sum_b += pairs.back()[1];
            }
        }
        ASSERT_GT(pairs.size(), size_t(3 * 320 * 200 / 4)) << "the level fills the view";
        const double ratio = sum_b / sum_a;
        EXPECT_GT(ratio, 0.92) << "three.js / hemi-render, linear";
        EXPECT_LT(ratio, 1.0) << "three.js / hemi-render, linear";
        // Past that one factor, pixel for pixel (texture filtering and edges differ a little).
        std::vector<double> relative;
        for (const auto& [ours_value, theirs_value] : pairs)
            relative.push_back(std::abs(theirs_value / ratio - ours_value) / (ours_value + 1e-3));
        std::nth_element(relative.begin(), relative.begin() + long(relative.size() / 2), relative.end());
        EXPECT_LT(relative[relative.size() / 2], 0.02) << "median relative difference per pixel";
    }

    // --outputs none: the RGBM lightmap alone; a smaller --rgbm-range clips and says how much.
    const fs::path small = dir() / "post_small.gltf";
    const Result n = bake("export " + q(asset) + " -o " + q(small) + " --outputs none --rgbm-range 1");
    ASSERT_EQ(n.status, 0) << n.err;
    EXPECT_NE(n.err.find("clipped"), std::string::npos) << n.err;
    tinygltf::Model s;
    ASSERT_TRUE(loader.LoadASCIIFromFile(&s, &err, &warn, small.string())) << err;
    EXPECT_FALSE(s.extensions.at("HEMI_lightmaps").Has("outputs")) << "none stored, none listed";
    EXPECT_EQ(s.materials[1].extras.Get("lightmap").Get("range").GetNumberAsDouble(), 1.0);
    if (const char* validator = std::getenv("HEMI_GLTF_VALIDATOR"))
    {
        EXPECT_EQ(validate(small, validator), std::make_pair(0, 0)) << small;
    }
}

// Issue 43 item 6: a level baked with a mixed sun exports its shadowmask (an RGBA8 PNG of the atlas under
// HEMI_lightmaps, the asset's bytes in every texel, the post's shadow in channel R) and its lights with their
// bake modes and channels, in the glTF's frame; the file passes the Khronos validator.
TEST(HemiBakeExport, AMixedSunsShadowmaskAndLightsTravelInTheExtension)
{
    const fs::path scene = hemi::test::write_post_scene(dir() / "post_mixed.glb"),
                   asset = dir() / "post_mixed.hemi", glb = dir() / "post_mixed_lit.glb";
    const Result b = bake("lightmap " + q(scene) + " -o " + q(asset) +
                          " --env-scale 0.5 --sun 0.4,0.3,1,4,3.6,3 --sun-mode mixed --size 64 --rays 16");
    ASSERT_EQ(b.status, 0) << b.err;
    const Result e = bake("export " + q(asset) + " -o " + q(glb));
    ASSERT_EQ(e.status, 0) << e.err;
    const hemi::io::LightmapAsset a = hemi::io::read_lightmap_asset(asset);
    ASSERT_EQ(a.shadowmask.k, 4u);
    tinygltf::Model m;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, glb.string())) << err;
    const tinygltf::Value& ext = m.extensions.at("HEMI_lightmaps");
    ASSERT_TRUE(ext.Has("shadowmask"));
    const int texture = ext.Get("shadowmask").Get("index").GetNumberAsInt();
    EXPECT_EQ(ext.Get("shadowmask").Get("texCoord").GetNumberAsInt(), 1);
    ASSERT_LT(size_t(texture), m.textures.size());
    const tinygltf::Image& image = m.images[size_t(m.textures[size_t(texture)].source)];
    ASSERT_EQ(image.width, int(a.width));
    ASSERT_EQ(image.height, int(a.height));
    ASSERT_EQ(image.component, 4);
    size_t shadowed = 0, lit = 0;
    for (uint32_t y = 0; y < a.height; ++y)
        for (uint32_t x = 0; x < a.width; ++x)
            for (uint32_t c = 0; c < 4; ++c)
            {
                const int stored = int(std::lround(a.shadowmask.at(c, x, y).x * 255.0f));
                ASSERT_EQ(int(image.image[(size_t(y) * a.width + x) * 4 + c]), stored)
                    << "texel " << x << ", " << y << " channel " << c;
                if (c == 0 && a.output("plain").maps.at(0, x, y).x > 0.0f)
                {
                    shadowed += stored == 0;
                    lit += stored == 255;
                }
            }
    EXPECT_GT(shadowed, 20u) << "the post's shadow";
    EXPECT_GT(lit, 1000u);
    ASSERT_TRUE(ext.Has("lights"));
    const tinygltf::Value& sun = ext.Get("lights").Get(0);
    EXPECT_EQ(sun.Get("name").Get<std::string>(), "sun");
    EXPECT_EQ(sun.Get("type").Get<std::string>(), "directional");
    EXPECT_EQ(sun.Get("mode").Get<std::string>(), "mixed");
    EXPECT_EQ(sun.Get("shadowmaskChannel").GetNumberAsInt(), 0);
    EXPECT_NEAR(sun.Get("angularDiameter").GetNumberAsDouble(), 0.53, 1e-6);
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(sun.Get("direction").Get(i).GetNumberAsDouble(), double(a.lights[0].light.direction[i]),
                    1e-6);
    if (const char* validator = std::getenv("HEMI_GLTF_VALIDATOR"))
    {
        EXPECT_EQ(validate(glb, validator), std::make_pair(0, 0)) << glb;
    }
}

// Bad input: exit status 1, a message naming the file and the problem, no output left behind.
TEST(HemiBakeExport, RefusesWhatIsNotALightmapLevelWithTheFileNamed)
{
    const fs::path scene = hemi::test::write_post_scene(dir() / "post_bad.glb"),
                   asset = dir() / "post_sh9.hemi", out = dir() / "bad.glb";
    ASSERT_EQ(
        bake("lightmap " + q(scene) + " -o " + q(asset) + " --env uniform --size 16 --rays 4 --bases sh9")
            .status,
        0);
    const Result no_plain = bake("export " + q(asset) + " -o " + q(out));
    EXPECT_EQ(no_plain.status, 1);
    EXPECT_NE(no_plain.err.find("no \"plain\" output"), std::string::npos) << no_plain.err;
    const Result unknown = bake("export " + q(asset) + " -o " + q(out) + " --outputs sh9,h7");
    EXPECT_EQ(unknown.status, 1);
    EXPECT_NE(unknown.err.find("h7"), std::string::npos) << unknown.err;
    const Result extension = bake("export " + q(asset) + " -o " + q(dir() / "bad.obj"));
    EXPECT_EQ(extension.status, 1);
    EXPECT_NE(extension.err.find(".glb or .gltf"), std::string::npos) << extension.err;

    // Not a lightmap asset: a PRT asset.
    const fs::path prt = dir() / "post_prt.hemi";
    ASSERT_EQ(bake("prt " + q(scene) + " -o " + q(prt) + " --rays 16 --bases gs").status, 0);
    const Result kind = bake("export " + q(prt) + " -o " + q(out));
    EXPECT_EQ(kind.status, 1);
    EXPECT_NE(kind.err.find(prt.string()), std::string::npos) << kind.err;
    EXPECT_NE(kind.err.find("prt asset"), std::string::npos) << kind.err;

    // A truncated asset.
    const fs::path cut = dir() / "post_cut.hemi";
    {
        const std::string bytes = hemi::test::slurp(asset);
        std::ofstream(cut, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() / 2));
    }
    const Result truncated = bake("export " + q(cut) + " -o " + q(out));
    EXPECT_EQ(truncated.status, 1);
    EXPECT_NE(truncated.err.find(cut.string()), std::string::npos) << truncated.err;
    EXPECT_FALSE(fs::exists(out));
}
