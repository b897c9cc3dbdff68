// samples/engine run as CI runs it: in a window under Xvfb (xvfb-run), on lavapipe, with the Khronos
// validation layer and synchronisation validation (two frames in flight, a resize half-way), 300 frames
// without a single message; and its screenshot of the baked level alone (--baked-only: H4, the SSBump wall
// in SSBump, no dynamic light, fog or tonemap) equal to hemi-render's image of the same asset and camera,
// an independent renderer (hemi's own material shaders and pipelines, not the engine's).
#include "run_tool.h"

#include "../temp_dir.h"

#include <hemi/io/image.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

namespace
{
using hemi::test::q;
namespace fs = std::filesystem;

const std::string kCamera = "-3.5,0.8,1.6,3,-0.6,0.9"; // the sample's own camera, given to both

hemi::test::Result engine(const fs::path& dir, const std::string& args)
{
    // -a: a free display number (tests run in parallel); the screen larger than any window here.
    return hemi::test::run(dir, HEMI_XVFB_RUN,
                           "-a -s '-screen 0 1280x720x24' " + q(HEMI_ENGINE_SAMPLE_EXE) + " --assets " +
                               q(dir / "assets") + " " + args);
}

TEST(EngineSample, ThreeHundredFramesWithResizeAreSilentUnderSynchronisationValidation)
{
    const fs::path dir = hemi::test::temp_dir("engine_sample_frames");
    const hemi::test::Result r = engine(
        dir, "--frames 300 --size 480x270 --resize-at 150 --validation --screenshot " + q(dir / "last.png"));
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    // The window shrank to 3/4 at frame 150 and the swapchain followed it.
    EXPECT_NE(r.out.find("engine: 300 frames at 360x202,"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(", 0 validation message(s)"), std::string::npos) << r.out << r.err;
    const hemi::io::ImageRgba8 last = hemi::io::read_png(dir / "last.png");
    EXPECT_EQ(last.width, 360u);
    EXPECT_EQ(last.height, 202u);
    fs::remove_all(dir);
}

TEST(EngineSample, BakedLevelEqualsHemiRenderAtTheSameCamera)
{
    const fs::path dir = hemi::test::temp_dir("engine_sample_baked");
    const hemi::test::Result e =
        engine(dir, "--baked-only --frames 2 --size 480x270 --validation --camera=" + kCamera +
                        " --screenshot " + q(dir / "engine.png"));
    ASSERT_EQ(e.status, 0) << e.out << e.err;
    const hemi::test::Result r = hemi::test::run(dir, HEMI_RENDER_EXE,
                                                 q(dir / "assets" / "engine_level.hemi") +
                                                     " --technique h4 --size 480x270 --camera=" + kCamera +
                                                     " -o " + q(dir / "hemi_render.png"),
                                                 "HEMI_VALIDATION=1");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    const hemi::io::ImageRgba8 a = hemi::io::read_png(dir / "engine.png");
    const hemi::io::ImageRgba8 b = hemi::io::read_png(dir / "hemi_render.png");
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    // Both are sRGB-encoded clamps of the same radiance (exposure 1): compare the encoded values over [0, 1].
    double squared = 0.0, mean = 0.0;
    size_t off = 0, n = 0;
    for (size_t i = 0; i < a.pixels.size(); i += 4)
        for (int c = 0; c < 3; ++c)
        {
            const double d = (double(a.pixels[i + c]) - double(b.pixels[i + c])) / 255.0;
            squared += d * d;
            mean += b.pixels[i + c] / 255.0;
            off += std::abs(d) > 3.5 / 255.0;
            ++n;
        }
    const double rms = std::sqrt(squared / double(n));
    mean /= double(n);
    EXPECT_GT(mean, 0.05) << "hemi-render's image is black: nothing to compare";
    EXPECT_LE(rms, 0.01) << "mean " << mean;
    // Beyond the README's 1%: all but a few edge pixels agree to the 8-bit rounding of two renderers.
    EXPECT_LE(double(off) / double(n), 1e-3) << off << " of " << n << " values differ by more than 3/255";
    fs::remove_all(dir);
}

} // namespace

// Numbers on its command line are finite and in range, a usage error exits 1 (CLI11's own codes were 105
// and 109), and the screenshot is checked as an output, all before any asset, window or device is made.
TEST(EngineSample, UsageErrorsExitOneBeforeAnyFrame)
{
    const fs::path dir = hemi::test::temp_dir("engine_sample_usage");
    for (const std::string bad :
         {"--exposure nan", "--exposure inf", "--fog nan", "--fog -1", "--frames x", "--no-such-option"})
    {
        const hemi::test::Result r =
            hemi::test::run(dir, HEMI_ENGINE_SAMPLE_EXE, "--assets " + q(dir / "assets") + " " + bad);
        EXPECT_EQ(r.status, 1) << bad << ": " << r.out << r.err;
        EXPECT_EQ(r.out.find("frames at"), std::string::npos) << bad;
    }
    // Issue 41, defects 11 and 12: the screenshot follows the tools' output rules before any asset is baked
    // or frame drawn (it used to replace the level asset with a PNG, exit 0, and a missing folder failed
    // after every frame): an asset's name in the assets folder, a missing folder, another extension.
    fs::create_directories(dir / "assets");
    const std::string level = (dir / "assets" / "engine_level.hemi").string();
    std::ofstream(level) << "the level asset";
    for (const auto& [shot, says] :
         {std::pair{level, std::string("must end in .png")},
          std::pair{(dir / "assets" / "engine_sky.png").string(),
                    std::string("overwrite the sample's input")},
          std::pair{(dir / "no_such_folder" / "s.png").string(), std::string("no_such_folder")},
          std::pair{(dir / "s.jpg").string(), std::string("must end in .png")}})
    {
        const hemi::test::Result r =
            hemi::test::run(dir, HEMI_ENGINE_SAMPLE_EXE,
                            "--assets " + q(dir / "assets") + " --frames 100 --screenshot " + q(shot));
        EXPECT_EQ(r.status, 1) << shot << ": " << r.out << r.err;
        EXPECT_NE(r.err.find(says), std::string::npos) << shot << ": " << r.err;
        EXPECT_EQ(r.err.find("baking"), std::string::npos) << shot << ": the assets were baked first";
    }
    EXPECT_EQ(hemi::test::slurp(level), "the level asset");
    fs::remove_all(dir);
}
