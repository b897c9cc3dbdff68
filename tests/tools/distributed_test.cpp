// hemi-bake under mpirun (Open MPI, on this machine, oversubscribed): the same bytes as the one-process tool
// for any number of ranks, the work shared among them, and a job killed mid-pass resumed with another rank
// count to the same bytes. Built when hemi-bake is (HEMI_HAS_MPI); Debian's openmpi-bin runs it.
#include "../temp_dir.h"
#include "post_scene.h"
#include "run_tool.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
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
    return hemi::test::run(dir(), HEMI_MPIEXEC,
                           "--oversubscribe --bind-to none -np " + std::to_string(ranks) + " " +
                               q(HEMI_BAKE_EXE) + " " + args,
                           kEnvironment);
}

// The bake: two bounces and probes, a sun and a sky, 1024 rays a texel so that each pass has 8
// slices to share.
std::string lightmap_args(const fs::path& scene, const fs::path& asset, const fs::path& json)
{
    return "lightmap " + q(scene) + " -o " + q(asset) + " --json " + q(json) +
           " --env uniform --env-scale 0.5 --sun 0.4,0.3,1,4,3.6,3 --bounces 2 --size 128 --rays 1024 "
           "--probes "
           "3,2,2";
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
    for (int ranks : {1, 2, 3})
    {
        const fs::path asset = dir() / ("ranks" + std::to_string(ranks) + ".hemi"),
                       json = dir() / ("ranks" + std::to_string(ranks) + ".json");
        const Result r = mpirun(ranks, lightmap_args(scene, asset, json));
        ASSERT_EQ(r.status, 0) << r.err << r.out;
        EXPECT_TRUE(hemi::test::slurp(asset) == expected) << ranks << " rank(s): the asset's bytes differ";
        const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(json));
        EXPECT_EQ(j["ranks"], ranks);
        const std::vector<uint64_t> by_rank = j["texels_by_rank"];
        ASSERT_EQ(by_rank.size(), size_t(ranks));
        EXPECT_EQ(std::accumulate(by_rank.begin(), by_rank.end(), uint64_t(0)),
                  uint64_t(j["covered_texels"]) * 3)
            << "every texel of the three passes once";
        for (int k = 0; k < ranks; ++k)
            EXPECT_GT(by_rank[size_t(k)], 0u) << "rank " << k << " computed nothing";
        // Only rank 0 reports: one summary line.
        EXPECT_EQ(r.out.find("baked "), r.out.rfind("baked ")) << r.out;
    }
}

// A 2-rank job killed (SIGTERM, as a queue's time limit does) once its checkpoint holds finished work, then
// resumed with 3 ranks: the same bytes as the one-process tool, and the JSON says it resumed.
TEST(DistributedBake, AJobKilledMidPassResumesWithAnotherRankCountToTheSameBytes)
{
    const fs::path scene = dir() / "post_resume.glb";
    hemi::test::write_post_scene(scene);
    const fs::path single = dir() / "resume_single.hemi", asset = dir() / "resume.hemi",
                   json = dir() / "resume.json", partial = dir() / "resume.hemi.partial";
    const Result s = hemi::test::run(dir(), HEMI_BAKE_EXE, lightmap_args(scene, single, dir() / "rs.json"));
    ASSERT_EQ(s.status, 0) << s.err;

    std::string command = kEnvironment;
    command.append(" exec ");
    command.append(q(HEMI_MPIEXEC));
    command.append(" --oversubscribe --bind-to none -np 2 ");
    command.append(q(HEMI_BAKE_EXE));
    command.append(" ");
    command.append(lightmap_args(scene, asset, json));
    command.append(" --checkpoint-interval 0 > ");
    command.append(q(dir() / "killed.out"));
    command.append(" 2>&1");
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0)
    {
        execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
    // Kill it once the checkpoint holds work, but before it has finished.
    const auto t0 = std::chrono::steady_clock::now();
    int status = 0;
    bool ended = false;
    while (!fs::exists(partial) && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120) &&
           !(ended = waitpid(pid, &status, WNOHANG) == pid))
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const bool saved = fs::exists(partial);
    if (!ended)
    {
        kill(pid, SIGTERM);
        waitpid(pid, &status, 0);
    }
    ASSERT_TRUE(saved) << "no checkpoint within 120 s: " << hemi::test::slurp(dir() / "killed.out");
    ASSERT_FALSE(fs::exists(asset)) << "the job finished before it was killed; the test needs a longer bake";

    const Result r = mpirun(3, lightmap_args(scene, asset, json));
    ASSERT_EQ(r.status, 0) << r.err << r.out;
    EXPECT_TRUE(hemi::test::slurp(asset) == hemi::test::slurp(single)) << "the resumed asset's bytes differ";
    const nlohmann::json j = nlohmann::json::parse(hemi::test::slurp(json));
    EXPECT_EQ(j["resumed"], true);
    EXPECT_EQ(j["ranks"], 3);
    EXPECT_FALSE(fs::exists(partial)) << "the checkpoint is removed once the asset is written";
}

// Bad use: another bake under several ranks is refused (only lightmap is shared so far), naming why, and the
// job ends instead of hanging.
TEST(DistributedBake, RefusesBakesThatDoNotShareTheirWorkYet)
{
    const fs::path scene = dir() / "post_prt.glb";
    hemi::test::write_post_scene(scene);
    const Result r =
        mpirun(2, "prt " + q(scene) + " -o " + q(dir() / "post_prt.hemi") + " --rays 16 --bases gs");
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("only lightmap"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir() / "post_prt.hemi"));
}
