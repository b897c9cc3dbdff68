// Light at the magnitudes users bring (issue 41): Blender's own sunset.exr at scale 1 (a sun pixel of 6,520
// in a 1024 x 512 world, from Debian's blender-data), a glTF sun of 100,000 lux and an environment with a
// pixel of 10^5 bake through hemi-bake lightmap with a bounce, the denoiser, light probes, --non-negative and
// in tiles (--memory-budget), export with hemi-bake export and render with hemi-render; each equals the same
// scene with every light scaled down by 10^4 and the result scaled back up, value by value. The bake is
// linear in its lights and traces the same rays either way, so the two differ by float rounding and the
// halves' rounding (2^-11 of each value); a store that clipped, overflowed or lost the scale differs by
// orders of magnitude. The 100,000-lux sun is beyond the halves' 65504 at scale 1, so its outputs carry a
// power-of-two scale (io/half_scale.h) that the asset, the runtime's page table and the export apply.
#include "../temp_dir.h"
#include "post_scene.h"
#include "run_tool.h"

#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>

#include <glm/gtc/packing.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("light_range_test");
}

using hemi::test::q;
using hemi::test::Result;
using hemi::test::slurp;

Result run(const std::string& exe, const std::string& args, const std::string& environment = "")
{
    return hemi::test::run(dir(), exe, args, environment);
}

constexpr double kFactor = 1e4; // the dim bake's lights are the bright one's / kFactor

// The post scene (a floor with a post: shadow and bounce) as .gltf, with a KHR_lights_punctual directional
// light of `lux` shining down at 60 degrees from the horizon when lux > 0.
fs::path post_scene(const std::string& name, double lux)
{
    static const fs::path base = hemi::test::write_post_scene(dir() / "range_post.gltf");
    if (lux <= 0.0)
        return base;
    nlohmann::json j = nlohmann::json::parse(slurp(base));
    j["extensionsUsed"].push_back("KHR_lights_punctual");
    j["extensions"]["KHR_lights_punctual"]["lights"] = {
        {{"type", "directional"}, {"intensity", lux}, {"color", {1.0, 0.95, 0.85}}, {"name", "Daylight"}}};
    // The light shines along its node's -Z: turned by -60 degrees about x, that is (0, -0.866, -0.5).
    j["nodes"].push_back({{"rotation", {-0.5, 0.0, 0.0, 0.8660254}},
                          {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    j["scenes"][0]["nodes"].push_back(int(j["nodes"].size()) - 1);
    const fs::path p = dir() / name;
    std::ofstream(p) << j.dump();
    return p;
}

// A 64 x 32 sky of radiance 0.3 with one pixel of `sun` above the horizon.
fs::path sun_pixel_exr(const std::string& name, float sky, float sun)
{
    hemi::io::ImageRgba img{64, 32, std::vector<float>(64 * 32 * 4, sky)};
    float* p = &img.pixels[(size_t(9) * 64 + 40) * 4];
    p[0] = p[1] = p[2] = sun;
    const fs::path path = dir() / name;
    hemi::io::write_exr(path, img);
    return path;
}

struct Bake
{
    fs::path asset;
    hemi::io::LightmapAsset lightmap;
    nlohmann::json report;
};

Bake bake(const std::string& name, const fs::path& scene, const std::string& lights)
{
    Bake b{dir() / (name + ".hemi"), {}, {}};
    const fs::path json = dir() / (name + ".json");
    // Every option of the issue: a bounce, the denoiser, probes, --non-negative and the bake in tiles.
    const std::string command = "lightmap " + q(scene) + " " + lights +
                                " --size 128 --rays 16 --bounces 1 --denoise --probes 3,3,3 --probe-rays 64 "
                                "--non-negative --bases plain,rnm,sh9,h6 -o " +
                                q(b.asset) + " --json " + q(json);
    const Result r = run(
        HEMI_BAKE_EXE, command + hemi::test::tiling_budget([&](const std::string& extra)
                                                           { return run(HEMI_BAKE_EXE, command + extra); }));
    EXPECT_EQ(r.status, 0) << name << ": " << r.err;
    if (r.status != 0)
        return b;
    b.lightmap = hemi::io::read_lightmap_asset(b.asset);
    b.report = nlohmann::json::parse(slurp(json));
    EXPECT_GT(b.report["tiles_per_pass"].get<int>(), 1) << name << ": baked in tiles";
    return b;
}

// |a - kFactor b| against the magnitude of what is compared (the texel's largest coefficient, the probe's,
// the pixel's): the worst relative difference over every value.
constexpr double kTolerance = 2e-3;
struct Worst
{
    double relative = 0.0;
    std::string where;
    size_t compared = 0, over = 0; // values compared, and beyond kTolerance
    void add(double a, double b, double magnitude, const std::function<std::string()>& at)
    {
        const double d = std::abs(a - kFactor * b) / std::max(magnitude, 1e-30);
        ++compared;
        over += d > kTolerance;
        if (d > relative)
        {
            relative = d;
            char values[96];
            std::snprintf(values, sizeof values, ": %.6g against %.6g scaled back", a, kFactor * b);
            where = at() + values;
        }
    }
};

// The halves' rounding is 2^-11 of each value on either side; float sums in another order add less. Every
// value is within kTolerance but for a few near a threshold of --non-negative's lift (it raises a texel's
// lowest normal in steps while it is below a floor, so a float's rounding can add or save a step): at most
// one in a thousand, and those within 10%, far inside the noise of 16 rays.
void expect_within(const Worst& worst, const std::string& what)
{
    EXPECT_LE(worst.over, worst.compared / 1000) << what << ": values beyond " << kTolerance;
    EXPECT_LE(worst.relative, 0.1) << what << " at " << worst.where;
}

// What the dim bake's halves resolve near 0, in the bright bake's units: the smallest half (2^-24) times
// the output's scale, scaled back; a texel within 1 / kTolerance of that is compared against that.
double dim_floor(const Bake& dim, const std::string& output)
{
    return kFactor * std::ldexp(1.0, -24) * dim.report["output_scales"][output].get<double>() / kTolerance;
}

void expect_scaled(const Bake& bright, const Bake& dim, const std::string& what)
{
    const hemi::io::LightmapAsset &a = bright.lightmap, &b = dim.lightmap;
    ASSERT_EQ(a.outputs.size(), b.outputs.size()) << what;
    for (size_t i = 0; i < a.outputs.size(); ++i)
    {
        const hemi::io::BlockMaps &ma = a.outputs[i].maps, &mb = b.outputs[i].maps;
        ASSERT_EQ(ma.grid.blocks(), mb.grid.blocks()) << what << " " << a.outputs[i].name;
        Worst worst;
        double largest = 0.0;
        for (float v : ma.values)
            largest = std::max(largest, double(std::abs(v)));
        for (size_t s = 0; s < ma.grid.slots(); ++s)
        {
            // A texel's own magnitude, or what the dim bake's halves resolve for a texel darker than that (a
            // dim texel of 1e-9 reads 0 from halves of scale 1).
            double magnitude = dim_floor(dim, a.outputs[i].name);
            for (uint32_t k = 0; k < ma.k; ++k)
                for (int c = 0; c < 3; ++c)
                    magnitude = std::max(magnitude, double(std::abs(ma.values[ma.index(k, s) + c])));
            for (uint32_t k = 0; k < ma.k; ++k)
                for (int c = 0; c < 3; ++c)
                    worst.add(ma.values[ma.index(k, s) + c], mb.values[mb.index(k, s) + c], magnitude,
                              [&]
                              { return "slot " + std::to_string(s) + " coefficient " + std::to_string(k); });
        }
        std::printf("%s, %s: largest value %.4g, worst difference %.2e of the texel (%s), %zu of %zu values "
                    "beyond %.0e\n",
                    what.c_str(), a.outputs[i].name.c_str(), largest, worst.relative, worst.where.c_str(),
                    worst.over, worst.compared, kTolerance);
        EXPECT_GT(largest, 0.0) << what;
        expect_within(worst, what + " " + a.outputs[i].name);
    }
    ASSERT_EQ(a.probes.irradiance.size(), b.probes.irradiance.size()) << what;
    ASSERT_FALSE(a.probes.empty()) << what;
    EXPECT_EQ(a.probes.valid, b.probes.valid) << what;
    Worst worst;
    for (size_t p = 0; p < a.probes.irradiance.size(); ++p)
    {
        double magnitude = 0.0;
        for (const glm::vec3& c : a.probes.irradiance[p])
            magnitude =
                std::max({magnitude, double(std::abs(c.x)), double(std::abs(c.y)), double(std::abs(c.z))});
        for (int j = 0; j < 9; ++j)
            for (int c = 0; c < 3; ++c)
                worst.add(a.probes.irradiance[p][j][c], b.probes.irradiance[p][j][c], magnitude,
                          [&] { return "probe " + std::to_string(p); });
    }
    std::printf("%s, probes: worst difference %.2e (%s)\n", what.c_str(), worst.relative,
                worst.where.c_str());
    EXPECT_LE(worst.relative, 1e-4) << what << " probes at " << worst.where;
}

// hemi-bake export of both: every output's halves times its scale, and the RGBM lightmap's range.
void expect_exports_scaled(const Bake& bright, const Bake& dim, const std::string& what, bool scaled)
{
    auto load = [&](const Bake& b, tinygltf::Model& m)
    {
        const fs::path glb = b.asset.string() + ".glb";
        const Result r = run(HEMI_BAKE_EXE, "export " + q(b.asset) + " -o " + q(glb));
        ASSERT_EQ(r.status, 0) << what << ": " << r.err;
        tinygltf::TinyGLTF loader;
        std::string err, warn;
        ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, glb.string())) << err;
    };
    tinygltf::Model ma, mb;
    load(bright, ma);
    load(dim, mb);
    if (::testing::Test::HasFatalFailure())
        return;
    const tinygltf::Value &ea = ma.extensions.at("HEMI_lightmaps"), &eb = mb.extensions.at("HEMI_lightmaps");
    EXPECT_NEAR(ea.Get("rgbm").Get("range").GetNumberAsDouble() /
                    (kFactor * eb.Get("rgbm").Get("range").GetNumberAsDouble()),
                1.0, kTolerance)
        << what << ": the RGBM range follows the light";
    const tinygltf::Value &oa = ea.Get("outputs"), &ob = eb.Get("outputs");
    ASSERT_EQ(oa.ArrayLen(), ob.ArrayLen());
    bool any_scaled = false;
    for (int i = 0; i < int(oa.ArrayLen()); ++i)
    {
        auto values = [&](const tinygltf::Model& m, const tinygltf::Value& out)
        {
            const tinygltf::BufferView& v = m.bufferViews[size_t(out.Get("bufferView").GetNumberAsInt())];
            const double scale = out.Get("scale").GetNumberAsDouble();
            std::vector<double> f(v.byteLength / 2);
            for (size_t j = 0; j < f.size(); ++j)
            {
                uint16_t h;
                std::memcpy(&h, m.buffers[0].data.data() + v.byteOffset + j * 2, 2);
                f[j] = double(glm::unpackHalf1x16(h)) * scale;
            }
            return f;
        };
        const std::vector<double> va = values(ma, oa.Get(i)), vb = values(mb, ob.Get(i));
        any_scaled |= oa.Get(i).Get("scale").GetNumberAsDouble() != 1.0;
        ASSERT_EQ(va.size(), vb.size());
        double largest = 0.0;
        for (double v : va)
            largest = std::max(largest, std::abs(v));
        Worst worst;
        for (size_t j = 0; j < va.size(); ++j)
            worst.add(va[j], vb[j], largest, [&] { return "value " + std::to_string(j); });
        std::printf("%s, export %s: worst difference %.2e of the largest value (%s)\n", what.c_str(),
                    oa.Get(i).Get("name").Get<std::string>().c_str(), worst.relative, worst.where.c_str());
        expect_within(worst, what + " export " + oa.Get(i).Get("name").Get<std::string>());
    }
    EXPECT_EQ(any_scaled, scaled) << what << ": the outputs' scales";
}

// hemi-render of both to EXR (validation on): each technique's radiance, pixel by pixel, with a sphere lit by
// the probes in view.
void expect_renders_scaled(const Bake& bright, const Bake& dim, const std::string& what)
{
    for (const std::string technique : {"plain", "sh9", "h6", "rnm"})
    {
        auto render = [&](const Bake& b)
        {
            const fs::path exr = b.asset.string() + "." + technique + ".exr";
            const Result r = run(HEMI_RENDER_EXE,
                                 q(b.asset) + " --technique " + technique +
                                     " --size 96x72 --sphere 0.5,0.5,0.3,0.2 -o " + q(exr),
                                 "HEMI_VALIDATION=1");
            EXPECT_EQ(r.status, 0) << what << " " << technique << ": " << r.err;
            return hemi::io::read_exr(exr);
        };
        const hemi::io::ImageRgba a = render(bright), b = render(dim);
        ASSERT_EQ(a.pixels.size(), b.pixels.size());
        double largest = 0.0;
        for (size_t i = 0; i < a.pixels.size(); ++i)
            if (i % 4 != 3)
                largest = std::max(largest, double(a.pixels[i]));
        Worst worst;
        size_t lit = 0;
        for (size_t i = 0; i < a.pixels.size(); i += 4)
        {
            const double magnitude = std::max({a.pixels[i], a.pixels[i + 1], a.pixels[i + 2]});
            lit += magnitude > 1e-3 * largest;
            // Pixels far darker than the image compare against the image's 1e-3 (rasterised the same, an
            // edge's coverage differs by nothing; a dark pixel's few half-float steps are not its light).
            for (int c = 0; c < 3; ++c)
                worst.add(a.pixels[i + c], b.pixels[i + c], std::max(magnitude, 1e-3 * largest),
                          [&] { return "pixel " + std::to_string(i / 4); });
        }
        std::printf("%s, hemi-render %s: brightest %.4g, worst difference %.2e (%s)\n", what.c_str(),
                    technique.c_str(), largest, worst.relative, worst.where.c_str());
        EXPECT_GT(lit, a.pixels.size() / 4 / 10)
            << what << " " << technique << ": the level is in view and lit";
        EXPECT_LE(worst.relative, 5e-3) << what << " " << technique << " at " << worst.where;
    }
}

void expect_equal_to_scaled_down(const Bake& bright, const Bake& dim, const std::string& what, bool scaled)
{
    if (bright.report.is_null() || dim.report.is_null())
        return;
    for (const auto& [name, scale] : bright.report["output_scales"].items())
        EXPECT_EQ(scale.get<double>() > 1.0, scaled) << what << " " << name << ": scale " << scale;
    EXPECT_NEAR(bright.report["irradiance_bound"].get<double>() /
                    (kFactor * dim.report["irradiance_bound"].get<double>()),
                1.0, 1e-6)
        << what;
    expect_scaled(bright, dim, what);
    expect_exports_scaled(bright, dim, what, scaled);
    expect_renders_scaled(bright, dim, what);
}

} // namespace

TEST(LightRange, BlendersSunsetHdriBakesAtScaleOne)
{
    const fs::path hdri = "/usr/share/blender/datafiles/studiolights/world/sunset.exr";
    ASSERT_TRUE(fs::exists(hdri)) << "cmake/install_deps.sh installs blender-data";
    const fs::path scene = post_scene("", 0.0);
    const Bake bright = bake("sunset", scene, "--env " + q(hdri));
    const Bake dim = bake("sunset_dim", scene, "--env " + q(hdri) + " --env-scale 1e-4");
    expect_equal_to_scaled_down(bright, dim, "sunset.exr", false);
}

TEST(LightRange, AGltfSunOf100000LuxBakes)
{
    const Bake bright = bake("daylight", post_scene("daylight.gltf", 1e5), "--env-scale 2000");
    const Bake dim = bake("daylight_dim", post_scene("daylight_dim.gltf", 10.0), "--env-scale 0.2");
    expect_equal_to_scaled_down(bright, dim, "a 100,000 lux sun", true);
}

TEST(LightRange, AnEnvironmentWithA1e5PixelBakes)
{
    const fs::path scene = post_scene("", 0.0);
    const Bake bright = bake("sun_pixel", scene, "--env " + q(sun_pixel_exr("sun_pixel.exr", 0.3f, 1e5f)));
    const Bake dim =
        bake("sun_pixel_dim", scene, "--env " + q(sun_pixel_exr("sun_pixel_dim.exr", 0.3e-4f, 10.0f)));
    expect_equal_to_scaled_down(bright, dim, "a 1e5 sun pixel", false);
}
