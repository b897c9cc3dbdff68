// The command lines pipelines script against, run as processes: hemi-bake prt and hemi-render with the
// issue's exact forms, their outputs, and their errors on bad input (exit status 1, a message naming the
// file and the problem, no output file left behind).
#include "../temp_dir.h"
#include "models.h"

#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("cli_test");
}

struct Result
{
    int status;
    std::string out, err;
};

std::string slurp(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

Result run(const std::string& exe, const std::string& args, const std::string& environment = "")
{
    const fs::path out = dir() / "stdout.txt", err = dir() / "stderr.txt";
    const std::string command =
        environment + " '" + exe + "' " + args + " > '" + out.string() + "' 2> '" + err.string() + "'";
    const int raw = std::system(command.c_str());
    return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

Result bake(const std::string& args) { return run(HEMI_BAKE_EXE, "prt " + args); }
// Every render runs with the Khronos validation layer: hemi-render exits 2 if it reports anything.
Result render(const std::string& args) { return run(HEMI_RENDER_EXE, args, "HEMI_VALIDATION=1"); }

std::string q(const fs::path& p)
{
    std::string quoted(1, '\'');
    quoted.append(p.string());
    quoted.push_back('\'');
    return quoted;
}

const fs::path& knot()
{
    static const fs::path p = hemi::samples::write_prt_model(dir() / "models", "knot", hemi::samples::PrtModel::Complex, 0.2f);
    return p;
}

} // namespace

// The command forms end to end: bake with CPCA and a JSON report, then render the lighting-only
// white furnace to EXR (linear, alpha = coverage) and a colour view to PNG.
TEST(Cli, BakeThenRenderEndToEnd)
{
    const fs::path asset = dir() / "knot.hemi", json = dir() / "knot.json";
    const Result b = bake(q(knot()) + " -o " + q(asset) +
                          " --bases gs,hl2,sal4,h4,h6,sep4,prt --transfer unshadowed --order 4 --rays 16 --seed 3"
                          " --cpca 1x8 --json " + q(json));
    ASSERT_EQ(b.status, 0) << b.err;
    EXPECT_FALSE(fs::exists(asset.string() + ".partial")) << "the checkpoint outlived a finished bake";
    EXPECT_NE(b.out.find("Mrays/s"), std::string::npos) << b.out;
    EXPECT_NE(b.out.find("CPCA"), std::string::npos) << b.out;
    const nlohmann::json report = nlohmann::json::parse(slurp(json));
    EXPECT_EQ(report["transfer"], "unshadowed");
    EXPECT_EQ(report["order"], 4);
    EXPECT_EQ(report["techniques"].size(), 7u);
    EXPECT_GT(report["techniques"][0]["cpca_rms_error"].get<double>(), 0.0);
    // The surfaces the asset carries: the sample's one material, one primitive and two PNGs; nothing
    // simplified.
    EXPECT_EQ(report["materials"], 1);
    EXPECT_EQ(report["primitives"], 1);
    EXPECT_EQ(report["images"], 2);
    ASSERT_TRUE(report["warnings"].is_array());
    EXPECT_TRUE(report["warnings"].empty()) << report["warnings"];
    EXPECT_EQ(b.err.find("warning"), std::string::npos) << b.err;

    const fs::path exr = dir() / "white.exr";
    const Result r = render(q(asset) + " --technique h4 --env uniform --white --size 96x64 -o " + q(exr));
    ASSERT_EQ(r.status, 0) << r.err;
    const hemi::io::ImageRgba img = hemi::io::read_exr(exr);
    ASSERT_EQ(img.width, 96u);
    ASSERT_EQ(img.height, 64u);
    size_t covered = 0, empty = 0;
    for (size_t i = 0; i < img.pixels.size(); i += 4)
    {
        if (img.pixels[i + 3] == 1.0f)
        {
            ++covered;
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(img.pixels[i + c], 1.0f, 0.01f) << "pixel " << i / 4;
        }
        else
        {
            ASSERT_EQ(img.pixels[i + 3], 0.0f);
            ++empty;
        }
    }
    EXPECT_GT(covered, 500u);
    EXPECT_GT(empty, 500u);

    // An EXR environment of radiance 1 everywhere is the uniform environment: the furnace again.
    const fs::path env = dir() / "white_env.exr", exr_env = dir() / "white_from_exr.exr";
    hemi::io::write_exr(env, hemi::io::ImageRgba{64, 32, std::vector<float>(64 * 32 * 4, 1.0f)});
    const Result e = render(q(asset) + " --technique sal4 --env " + q(env) + " --white --rotate 33 --size 96x64 -o " +
                            q(exr_env));
    ASSERT_EQ(e.status, 0) << e.err;
    const hemi::io::ImageRgba from_exr = hemi::io::read_exr(exr_env);
    for (size_t i = 0; i < from_exr.pixels.size(); i += 4)
    {
        if (from_exr.pixels[i + 3] == 1.0f)
        {
            ASSERT_NEAR(from_exr.pixels[i], 1.0f, 0.01f) << "pixel " << i / 4;
        }
    }

    const fs::path png = dir() / "sky.png";
    const Result c = render(q(asset) + " --technique gs --cpca --env sky --rotate 90 --size 64x48 "
                                       "--camera 0,-4,1,0,0,0 -o " + q(png));
    ASSERT_EQ(c.status, 0) << c.err;
    EXPECT_EQ(hemi::io::read_png(png).width, 64u);
}

// What the scene reader simplifies is printed as a warning naming the file, and listed in the JSON report.
TEST(Cli, BakeWarnsAboutWhatTheSceneReaderSimplifies)
{
    nlohmann::json scene = nlohmann::json::parse(slurp(knot()));
    scene["materials"][0]["alphaMode"] = "BLEND";
    const fs::path blend = knot().parent_path() / "blend.gltf"; // beside the knot's textures
    std::ofstream(blend) << scene.dump();
    const fs::path asset = dir() / "blend.hemi", json = dir() / "blend.json";
    const Result r =
        bake(q(blend) + " -o " + q(asset) + " --bases prt --transfer unshadowed --order 3 --json " + q(json));
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("hemi-bake: warning: " + blend.string() + ": alphaMode BLEND drawn opaque"),
              std::string::npos)
        << r.err;
    const nlohmann::json report = nlohmann::json::parse(slurp(json));
    ASSERT_EQ(report["warnings"].size(), 1u);
    EXPECT_NE(report["warnings"][0].get<std::string>().find("alphaMode BLEND"), std::string::npos);
    EXPECT_EQ(hemi::io::read_prt_asset(asset).images.size(), 2u);
}

TEST(Cli, SameSeedSameBytes)
{
    const fs::path a = dir() / "a.hemi", b = dir() / "b.hemi", c = dir() / "c.hemi";
    const std::string args = " --bases gs,prt --transfer interreflected --bounces 1 --rays 8 --order 3";
    ASSERT_EQ(bake(q(knot()) + " -o " + q(a) + args + " --seed 5").status, 0);
    ASSERT_EQ(bake(q(knot()) + " -o " + q(b) + args + " --seed 5").status, 0);
    ASSERT_EQ(bake(q(knot()) + " -o " + q(c) + args + " --seed 6").status, 0);
    EXPECT_EQ(slurp(a), slurp(b));
    EXPECT_NE(slurp(a), slurp(c));
}

TEST(Cli, BadInputNamesTheFileAndLeavesNoOutput)
{
    const fs::path out = dir() / "never.hemi";
    auto expect_failure = [&](const Result& r, const std::string& part) {
        EXPECT_EQ(r.status, 1) << r.err;
        EXPECT_NE(r.err.find(part), std::string::npos) << "stderr: " << r.err;
        EXPECT_FALSE(fs::exists(out));
    };
    // Malformed glTF.
    const fs::path garbage = dir() / "garbage.gltf";
    std::ofstream(garbage) << "{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ { \"primitives\": [ { ";
    expect_failure(bake(q(garbage) + " -o " + q(out)), garbage.string());
    // A normal map the glTF references but that does not exist.
    fs::path missing = hemi::samples::write_prt_model(dir() / "missing", "m", hemi::samples::PrtModel::Simple, 0.3f);
    fs::remove(dir() / "missing" / "m_normal.png");
    expect_failure(bake(q(missing) + " -o " + q(out)), "m_normal.png");
    // Bad options.
    expect_failure(bake(q(knot()) + " -o " + q(out) + " --cpca 24"), "CLUSTERSxVECTORS");
    expect_failure(bake(q(knot()) + " -o " + q(out) + " --bases gs,phong"), "phong");
    expect_failure(bake(q(knot()) + " -o " + q(out) + " --transfer ambient"), "ambient");

    // hemi-render: a truncated asset, a corrupted one, a technique the asset lacks, a missing environment.
    const fs::path good = dir() / "small.hemi";
    ASSERT_EQ(bake(q(knot()) + " -o " + q(good) + " --bases hl2 --transfer unshadowed").status, 0);
    const std::string bytes = slurp(good);
    const fs::path cut = dir() / "cut.hemi", flipped = dir() / "flipped.hemi";
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    std::string f = bytes;
    f[f.size() / 2] = char(f[f.size() / 2] ^ 0x01);
    std::ofstream(flipped, std::ios::binary) << f;
    const fs::path png = dir() / "never.png";
    auto expect_render_failure = [&](const Result& r, const std::string& part) {
        EXPECT_EQ(r.status, 1) << r.err;
        EXPECT_NE(r.err.find(part), std::string::npos) << "stderr: " << r.err;
        EXPECT_FALSE(fs::exists(png));
    };
    expect_render_failure(render(q(cut) + " --technique hl2 --env sky -o " + q(png)), cut.string());
    expect_render_failure(render(q(flipped) + " --technique hl2 --env sky -o " + q(png)), "checksum");
    expect_render_failure(render(q(good) + " --technique gs --env sky -o " + q(png)), "no technique 'gs'");
    expect_render_failure(render(q(good) + " --technique hl2 --env " + q(dir() / "nope.exr") + " -o " + q(png)),
                          "nope.exr");
    expect_render_failure(render(q(good) + " --technique hl2 --env sky --size 0x5 -o " + q(png)), "--size");
    // No Vulkan device matching the selector.
    expect_render_failure(run(HEMI_RENDER_EXE, q(good) + " --technique hl2 --env sky -o " + q(png),
                              "HEMI_VALIDATION=1 HEMI_DEVICE=no-such-gpu"),
                          "no-such-gpu");
}

// A render target larger than the device can hold is refused before any Vulkan call fails, naming the size
// and the limit (lavapipe allows 2 GiB per allocation; a 16384 x 16384 RGBA32F attachment is 4 GiB).
TEST(Cli, RenderTargetsTooLargeForTheDeviceAreRefusedNamingTheLimit)
{
    const fs::path asset = dir() / "large.hemi";
    ASSERT_EQ(bake(q(knot()) + " -o " + q(asset) + " --bases gs --transfer unshadowed --order 3").status, 0);
    const fs::path out = dir() / "large.png";
    const Result r = render(q(asset) + " --size 16384x16384 -o " + q(out));
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_NE(r.err.find("16384x16384"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("maxMemoryAllocationSize"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("VK_ERROR"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

// A bake to a place it cannot write fails before any work, naming the cause (no progress line: no pass
// started); a folder where the checkpoint would go is named too; and a temporary file that a bake killed
// during its final write left beside the asset is gone after the next bake.
TEST(Cli, BakesFailFastOnUnwritableOutputsAndLeaveNoTemporaries)
{
    const Result missing = bake(q(knot()) + " -o " + q(dir() / "no_such_folder" / "x.hemi") + " --rays 512");
    EXPECT_EQ(missing.status, 1) << missing.err;
    EXPECT_NE(missing.err.find("does not exist"), std::string::npos) << missing.err;
    EXPECT_NE(missing.err.find("no_such_folder"), std::string::npos) << missing.err;
    EXPECT_EQ(missing.err.find("pass 1"), std::string::npos) << "the bake started before the output was checked";
    const Result json = bake(q(knot()) + " -o " + q(dir() / "json_out.hemi") + " --json " +
                             q(dir() / "no_such_folder" / "report.json"));
    EXPECT_EQ(json.status, 1) << json.err;
    EXPECT_NE(json.err.find("report.json"), std::string::npos) << json.err;
    EXPECT_EQ(json.err.find("pass 1"), std::string::npos) << "the bake started before its report's folder was checked";

    const fs::path blocked = dir() / "blocked.hemi";
    fs::create_directories(blocked.string() + ".partial");
    const Result folder = bake(q(knot()) + " -o " + q(blocked) + " --bases gs --transfer unshadowed --order 3");
    EXPECT_EQ(folder.status, 1) << folder.err;
    EXPECT_NE(folder.err.find("blocked.hemi.partial"), std::string::npos) << folder.err;
    EXPECT_NE(folder.err.find("folder"), std::string::npos) << folder.err;
    EXPECT_FALSE(fs::exists(blocked));
    fs::remove_all(blocked.string() + ".partial");

    const fs::path asset = dir() / "after_kill.hemi";
    const fs::path left = asset.string() + ".tmp4194303.0"; // a pid that no process has
    std::ofstream(left) << "half an asset";
    const Result b = bake(q(knot()) + " -o " + q(asset) + " --bases gs --transfer unshadowed --order 3");
    ASSERT_EQ(b.status, 0) << b.err;
    EXPECT_TRUE(fs::exists(asset));
    EXPECT_FALSE(fs::exists(left)) << "the killed write's temporary file outlived the next bake";
}
