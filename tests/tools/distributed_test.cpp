// hemi-bake under mpirun (Open MPI, on this machine, oversubscribed): the same bytes as the one-process tool
// for any number of ranks, the work shared among them, and a job killed mid-pass resumed with another rank
// count to the same bytes. Built when hemi-bake is (HEMI_HAS_MPI); Debian's openmpi-bin runs it.
#include "../png_writer.h"
#include "../temp_dir.h"
#include "models.h"
#include "post_scene.h"
#include "run_tool.h"

#include <hemi/io/asset.h>
#include <hemi/io/lightmap_asset.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <thread>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("distributed_test");
}

using hemi::test::q;
using hemi::test::Result;

// mpirun as CI runs it: as root (allowed by its variables), more ranks than cores, each rank free to use
// every core (mpirun binds a rank to one core by default), shared memory between ranks. Under the sanitize
// preset, AddressSanitizer's leak check is off for the ranks: Open MPI leaves allocations at exit in
// components it has unloaded, which LeakSanitizer cannot attribute or suppress by name; every other check
// (and the leak check of every other test of the same bake code) stays on.
constexpr const char* kEnvironment = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
                                     "OMPI_MCA_btl=self,vader ASAN_OPTIONS=detect_leaks=0:halt_on_error=1";
Result mpirun(int ranks, const std::string& args)
{
    std::string command = "300 ";
    command.append(q(HEMI_MPIEXEC));
    command.append(" --oversubscribe --bind-to none -np " + std::to_string(ranks) + " ");
    command.append(q(HEMI_BAKE_EXE) + " " + args);
    return hemi::test::run(dir(), "timeout", command, kEnvironment); // a job that hangs fails, after 5 min
}

// The bake: two bounces and probes, a sun and a sky, 1024 rays a texel so that each pass has 8
// slices to share. The sun is mixed (issue 43): the ranks gather its shadowmask and direct light, in tiles
// too, and a checkpoint carries them (the denoised bake below keeps a baked sun).
std::string lightmap_args(const fs::path& scene, const fs::path& asset, const fs::path& json)
{
    return "lightmap " + q(scene) + " -o " + q(asset) + " --json " + q(json) +
           " --env uniform --env-scale 0.5 --sun 0.4,0.3,1,4,3.6,3 --bounces 2 --size 128 --rays 1024 "
           "--probes 3,2,2 --sun-mode mixed";
}

} // namespace

TEST(DistributedBake, LightmapGivesTheSameBytesOnOneTwoAndThreeRanks)
{
    const fs::path scene = dir() / "post.glb";
    hemi::test::write_post_scene(scene);
    const fs::path single = dir() / "single.hemi";
    const Result s =
        hemi::test::run(dir(), HEMI_BAKE_EXE, lightmap_args(scene, single, dir() / "single.json"));
    ASSERT_EQ(s.status, 0) << s.err;
    const std::string expected = hemi::test::slurp(single);
    ASSERT_FALSE(expected.empty());
    const nlohmann::json single_json = nlohmann::json::parse(hemi::test::slurp(dir() / "single.json"));
    for (int ranks : {1, 2, 3})
    {
        const fs::path asset = dir() / ("ranks" + std::to_string(ranks) + ".hemi"),
                       json = dir() / ("ranks" + std::to_string(ranks) + ".json");
        // Two ranks under a memory budget that the whole atlas does not fit: in tiles, each shared among
        // the ranks like a pass, the sums on rank 0's disk.
        const Result r = mpirun(
            ranks, lightmap_args(scene, asset, json) +
                       (ranks == 2 ? hemi::test::tiling_budget(
                                         [&](const std::string& extra)
                                         { return mpirun(2, lightmap_args(scene, asset, json) + extra); })
                                   : ""));
        ASSERT_EQ(r.status, 0) << r.err << r.out;
        EXPECT_TRUE(hemi::test::slurp(asset) == expected) << ranks << " rank(s): the asset's bytes differ";
        const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(json));
        // Three ranks in memory share the outputs (each makes every third and sends it to rank 0): the
        // asset's bytes above, and the seams' report of every output the same as one process's.
        EXPECT_EQ(j["seams"], single_json["seams"]) << ranks << " rank(s)";
        EXPECT_EQ(j["stored_blocks"], single_json["stored_blocks"]) << ranks << " rank(s)";
        if (ranks == 2)
        {
            EXPECT_GT(j["tiles_per_pass"].get<uint32_t>(), 1u) << "a budget that leaves the bake in memory";
        }
        EXPECT_EQ(j["ranks"], ranks);
        const std::vector<uint64_t> by_rank = j["texels_by_rank"];
        ASSERT_EQ(by_rank.size(), size_t(ranks));
        EXPECT_EQ(std::accumulate(by_rank.begin(), by_rank.end(), uint64_t(0)),
                  uint64_t(j["covered_texels"]) * 5)
            << "every texel of the origin search, the test of those inside geometry and the three passes "
               "once";
        for (int k = 0; k < ranks; ++k)
            EXPECT_GT(by_rank[size_t(k)], 0u) << "rank " << k << " computed nothing";
        // Only rank 0 reports: one summary line.
        EXPECT_EQ(r.out.find("baked "), r.out.rfind("baked ")) << r.out;
    }
}

// Denoising on a shared bake (issue 25: the filter must give the same bytes for any rank count, in tiles or
// not): --denoise by one process, by 2 ranks under a memory budget (the bake in tiles with its halves in the
// tile file, then filtered by rank 0 in bands of rows read from it) and by 3 ranks in memory (the halves
// computed by every rank and gathered on rank 0, which filters the whole atlas) writes the same asset, every
// covered texel filtered.
TEST(DistributedBake, DenoisedLightmapGivesTheSameBytesOnOneTwoAndThreeRanks)
{
    const fs::path scene = dir() / "post_denoise.glb";
    hemi::test::write_post_scene(scene);
    const std::string args =
        " --env uniform --sun 0.4,0.3,1,4,3.6,3 --bounces 1 --size 128 --rays 64 --denoise";
    const fs::path single = dir() / "denoised_single.hemi";
    const Result s = hemi::test::run(dir(), HEMI_BAKE_EXE,
                                     "lightmap " + q(scene) + " -o " + q(single) + " --json " +
                                         q(dir() / "denoised_single.json") + args);
    ASSERT_EQ(s.status, 0) << s.err;
    const std::string expected = hemi::test::slurp(single);
    ASSERT_FALSE(expected.empty());
    const nlohmann::json single_json =
        nlohmann::json::parse(hemi::test::slurp(dir() / "denoised_single.json"));
    EXPECT_EQ(single_json["denoised_texels"], single_json["covered_texels"]);
    for (const int ranks : {2, 3})
    {
        const fs::path asset = dir() / "denoised_ranks.hemi", json = dir() / "denoised_ranks.json";
        // Two ranks under a budget the whole bake (17.4 MiB) does not fit: the bake in tiles, then the
        // filter in bands of rows from the tile file on rank 0.
        const std::string bake = "lightmap " + q(scene) + " -o " + q(asset) + " --json " + q(json) + args;
        const std::string budget = ranks == 2 ? hemi::test::tiling_budget([&](const std::string& extra)
                                                                          { return mpirun(2, bake + extra); })
                                              : "";
        const Result r = mpirun(ranks, bake + budget);
        ASSERT_EQ(r.status, 0) << r.err << r.out;
        EXPECT_TRUE(hemi::test::slurp(asset) == expected) << ranks << " ranks: the asset's bytes differ";
        const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(json));
        EXPECT_EQ(j["ranks"], ranks);
        EXPECT_EQ(j["denoised_texels"], single_json["denoised_texels"]) << ranks << " ranks";
        EXPECT_EQ(j["seams"], single_json["seams"]) << ranks << " ranks";
        if (ranks == 2)
        {
            EXPECT_GT(j["tiles_per_pass"].get<uint32_t>(), 1u) << "a budget that leaves the bake in memory";
        }
    }
}

// A 2-rank job killed once its checkpoint is in the first bounce, then resumed with 3 ranks: the same bytes
// as the one-process tool (the resumed ranks get the previous pass, the valid texels and the finished slices
// from rank 0's checkpoint), the JSON says it resumed, and it traced fewer rays than the whole bake (a
// restart from scratch gives the same bytes too). The kill is deterministic (issue 41: polling the
// checkpoint raced the job on a loaded machine): HEMI_TEST_KILL_AFTER_PASS=1 makes rank 0 kill itself with
// SIGKILL, as a machine failure would, right after its first checkpoint in pass 1 is saved, and mpirun ends
// the other rank.
TEST(DistributedBake, AJobKilledMidPassResumesWithAnotherRankCountToTheSameBytes)
{
    const fs::path scene = dir() / "post_resume.glb";
    hemi::test::write_post_scene(scene);
    const fs::path single = dir() / "resume_single.hemi", asset = dir() / "resume.hemi",
                   json = dir() / "resume.json", partial = dir() / "resume.hemi.partial";
    const Result s = hemi::test::run(dir(), HEMI_BAKE_EXE, lightmap_args(scene, single, dir() / "rs.json"));
    ASSERT_EQ(s.status, 0) << s.err;

    const Result killed = hemi::test::run(
        dir(), "timeout",
        "300 " + q(HEMI_MPIEXEC) + " --oversubscribe --bind-to none -np 2 " + q(HEMI_BAKE_EXE) + " " +
            lightmap_args(scene, asset, json) + " --checkpoint-interval 0",
        std::string(kEnvironment) + " HEMI_TEST_KILL_AFTER_PASS=1");
    EXPECT_NE(killed.status, 0) << "the job was not killed";
    ASSERT_FALSE(fs::exists(asset)) << "the job finished before it was killed";
    const std::vector<uint32_t> state = hemi::io::AssetReader(partial).array<uint32_t>("ckpt.state");
    ASSERT_FALSE(state.empty());
    EXPECT_EQ(state[0], 1u) << "the checkpoint is not in the first bounce";

    const Result r = mpirun(3, lightmap_args(scene, asset, json));
    ASSERT_EQ(r.status, 0) << r.err << r.out;
    EXPECT_TRUE(hemi::test::slurp(asset) == hemi::test::slurp(single)) << "the resumed asset's bytes differ";
    EXPECT_EQ(hemi::io::read_lightmap_asset(asset).shadowmask.k, 4u);
    const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(json));
    EXPECT_EQ(j["resumed"], true);
    EXPECT_EQ(j["ranks"], 3);
    // It went on from the checkpoint: the direct pass and the finished slices were not traced again.
    const nlohmann::json whole = nlohmann::json::parse(hemi::test::slurp(dir() / "rs.json"));
    std::printf("rays: %.0f the whole bake, %.0f resumed\n", whole["rays"].get<double>(),
                j["rays"].get<double>());
    EXPECT_GT(j["rays"].get<double>(), 0.0);
    EXPECT_LT(j["rays"].get<double>(), 0.8 * whole["rays"].get<double>());
    EXPECT_FALSE(fs::exists(partial)) << "the checkpoint is removed once the asset is written";
}

// SSBump (rows) and PRT (vertices, with a bounce) under 1, 2 and 3 ranks: the one-process tool's bytes,
// every rank working.
TEST(DistributedBake, SsbumpAndPrtGiveTheSameBytesOnOneTwoAndThreeRanks)
{
    // A 256 x 256 height map of bumps: 300 rays a texel make 54-row slices, five of them.
    std::vector<uint16_t> heights(256 * 256);
    for (uint32_t y = 0; y < 256; ++y)
        for (uint32_t x = 0; x < 256; ++x)
            heights[y * 256 + x] =
                uint16_t(127.5 + 127.5 * std::sin(0.15 * double(x)) * std::cos(0.11 * double(y)));
    const fs::path height = dir() / "bumps.png";
    {
        const std::vector<uint8_t> png = hemi::test::encode_png_samples(256, 256, 1, 8, heights);
        std::ofstream(height, std::ios::binary)
            .write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
    }
    // A trefoil knot that shadows itself (1,220 vertices): 4096 rays a vertex make 256-vertex slices.
    const fs::path knot =
        hemi::samples::write_prt_model(dir() / "models", "knot", hemi::samples::PrtModel::Complex, 0.2f);
    const std::string ssbump = "ssbump " + q(height) + " --rays 300 -o ",
                      prt = "prt " + q(knot) + " --rays 4096 --bounces 1 --bases gs,h4 -o ";
    const Result a = hemi::test::run(dir(), HEMI_BAKE_EXE, ssbump + q(dir() / "bumps_1.png"));
    ASSERT_EQ(a.status, 0) << a.err;
    const Result b = hemi::test::run(dir(), HEMI_BAKE_EXE, prt + q(dir() / "knot_1.hemi"));
    ASSERT_EQ(b.status, 0) << b.err;
    for (int ranks : {1, 2, 3})
    {
        const std::string n = std::to_string(ranks);
        const fs::path sb_json = dir() / ("bumps_" + n + ".json"), prt_json = dir() / ("knot_" + n + ".json");
        const Result sb =
            mpirun(ranks, ssbump + q(dir() / ("bumps_" + n + ".png")) + " --json " + q(sb_json));
        ASSERT_EQ(sb.status, 0) << sb.err;
        EXPECT_TRUE(hemi::test::slurp(dir() / ("bumps_" + n + ".png")) ==
                    hemi::test::slurp(dir() / "bumps_1.png"))
            << ranks << " ranks: the SSBump map's bytes differ";
        const Result pr = mpirun(ranks, prt + q(dir() / ("knot_" + n + ".hemi")) + " --json " + q(prt_json));
        ASSERT_EQ(pr.status, 0) << pr.err;
        EXPECT_TRUE(hemi::test::slurp(dir() / ("knot_" + n + ".hemi")) ==
                    hemi::test::slurp(dir() / "knot_1.hemi"))
            << ranks << " ranks: the PRT asset's bytes differ";
        for (const auto& [file, key] :
             {std::pair{sb_json, "rows_by_rank"}, std::pair{prt_json, "vertices_by_rank"}})
        {
            const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(file));
            EXPECT_EQ(j["ranks"], ranks) << file;
            const std::vector<uint64_t> by_rank = j[key];
            ASSERT_EQ(by_rank.size(), size_t(ranks)) << file;
            for (int k = 0; k < ranks; ++k)
                EXPECT_GT(by_rank[size_t(k)], 0u) << file << ": rank " << k << " computed nothing";
        }
    }
}

// Bad use: a bake that is not shared (reference) under several ranks is refused, naming why, and the job
// ends instead of hanging.
TEST(DistributedBake, RefusesBakesThatDoNotShareTheirWorkYet)
{
    const fs::path scene = dir() / "post_reference.glb";
    hemi::test::write_post_scene(scene);
    const Result r = mpirun(2, "reference " + q(scene) + " -o " + q(dir() / "post_reference.exr") +
                                   " --env uniform --size 32x32 --rays 4");
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("only lightmap, prt and ssbump"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir() / "post_reference.exr"));
}
