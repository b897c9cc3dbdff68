// The lightmap asset (io/lightmap_asset.h): every value round-trips (coefficients through half floats, so to
// half precision); truncated, corrupted, inconsistent and other kinds of files are refused naming the file.
#include "../temp_dir.h"

#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("lightmap_asset_test");
}

hemi::io::LightmapAsset small_asset()
{
    hemi::io::LightmapAsset a;
    hemi::io::Mesh& m = a.mesh;
    for (int i = 0; i < 4; ++i)
    {
        const glm::vec2 c(float(i & 1), float(i >> 1));
        m.positions.emplace_back(c.x, c.y, 0.0f);
        m.normals.emplace_back(0, 0, 1);
        m.tangents.emplace_back(1, 0, 0, 1);
        m.uvs.push_back(c);
        m.uvs1.push_back(c * 0.9f + 0.05f);
    }
    m.indices = {0, 1, 3, 0, 3, 2};
    a.materials.emplace_back();
    a.materials[0].name = "floor";
    a.primitives.push_back({0, 6, 0});
    a.width = 5;
    a.height = 3;
    a.rays = 64;
    a.seed = 7;
    a.covered_texels = 15;
    for (const auto& [name, k] : {std::pair{"plain", 1u}, std::pair{"h4", 4u}, std::pair{"rnm", 3u}})
    {
        hemi::io::LightmapOutput o{name, k, std::vector<float>(size_t(k) * 15 * 3)};
        for (size_t i = 0; i < o.maps.size(); ++i)
            o.maps[i] = float(std::sin(double(i) * 0.7)) * 3.0f;
        a.outputs.push_back(std::move(o));
    }
    return a;
}

std::string error_of(const fs::path& p)
{
    try
    {
        hemi::io::read_lightmap_asset(p);
    }
    catch (const hemi::io::FormatError& e)
    {
        return e.what();
    }
    return "";
}

} // namespace

TEST(LightmapAsset, RoundTripKeepsEveryValueToHalfPrecision)
{
    const hemi::io::LightmapAsset a = small_asset();
    const fs::path p = dir() / "round.hemi";
    hemi::io::write_lightmap_asset(p, a);
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(p);
    EXPECT_EQ(b.width, 5u);
    EXPECT_EQ(b.height, 3u);
    EXPECT_EQ(b.rays, 64u);
    EXPECT_EQ(b.seed, 7u);
    EXPECT_EQ(b.mesh.uvs1, a.mesh.uvs1);
    EXPECT_EQ(b.mesh.indices, a.mesh.indices);
    EXPECT_EQ(b.materials[0].name, "floor");
    ASSERT_EQ(b.outputs.size(), 3u);
    for (const hemi::io::LightmapOutput& o : a.outputs)
    {
        const hemi::io::LightmapOutput& r = b.output(o.name);
        ASSERT_EQ(r.maps.size(), o.maps.size());
        for (size_t i = 0; i < o.maps.size(); ++i)
            EXPECT_NEAR(r.maps[i], o.maps[i], std::abs(o.maps[i]) * 4.9e-4 + 1e-7)
                << o.name << " " << i; // 2^-11
    }
    EXPECT_THROW(b.output("sh9"), std::invalid_argument);
    EXPECT_EQ(hemi::io::asset_kind(p), "lightmap");
}

TEST(LightmapAsset, BrokenFilesAreRefusedNamingTheFile)
{
    const fs::path good = dir() / "good.hemi";
    hemi::io::write_lightmap_asset(good, small_asset());
    std::ifstream in(good, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (size_t keep : {size_t(0), size_t(7), size_t(100), bytes.size() / 2, bytes.size() - 1})
    {
        const fs::path p = dir() / ("cut" + std::to_string(keep) + ".hemi");
        std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(keep));
        const std::string e = error_of(p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << keep << ": " << e;
    }
    std::vector<char> flipped = bytes;
    flipped[bytes.size() * 2 / 3] ^= 0x10;
    const fs::path p = dir() / "flipped.hemi";
    std::ofstream(p, std::ios::binary).write(flipped.data(), std::streamsize(flipped.size()));
    EXPECT_NE(error_of(p).find("checksum"), std::string::npos) << error_of(p);
}

TEST(LightmapAsset, WriterRefusesInconsistentAssets)
{
    auto refused = [](hemi::io::LightmapAsset a, const std::string& what)
    {
        try
        {
            hemi::io::write_lightmap_asset(dir() / "never.hemi", a);
            ADD_FAILURE() << "accepted: " << what;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(dir() / "never.hemi"));
    };
    hemi::io::LightmapAsset a = small_asset();
    a.outputs[1].maps.pop_back();
    refused(a, "values, expected");
    a = small_asset();
    a.outputs[0].maps[3] = NAN;
    refused(a, "half float");
    a = small_asset();
    a.outputs[0].maps[3] = 1e6f;
    refused(a, "half float");
    a = small_asset();
    a.outputs[0].name = "h7";
    refused(a, "unknown output 'h7'");
    a = small_asset();
    a.outputs[1].k = 6;
    refused(a, "K = 6");
    a = small_asset();
    a.mesh.uvs1.clear();
    refused(a, "lightmap UVs");
}

namespace
{
// A 2 x 2 x 2 probe grid over [0, 2] x [0, 1] x [0, 4] whose probe (i, j, k) holds coefficient c = value
// (i + 2 j + 4 k) * (c + 1) in every channel.
hemi::io::LightProbes probe_grid()
{
    hemi::io::LightProbes p;
    p.count = glm::uvec3(2, 2, 2);
    p.lo = glm::vec3(0.0f);
    p.hi = glm::vec3(2.0f, 1.0f, 4.0f);
    for (int at = 0; at < 8; ++at)
    {
        std::array<glm::vec3, 9> sh{};
        for (int c = 0; c < 9; ++c)
            sh[size_t(c)] = glm::vec3(float(at * (c + 1)));
        p.irradiance.push_back(sh);
        p.valid.push_back(1);
    }
    return p;
}
} // namespace

// Light probes round-trip exactly (32-bit floats) with their grid and valid flags; the writer refuses a grid
// whose sizes disagree or that holds NaN; interpolation is trilinear over the valid probes of a position's
// cell (weights renormalised without an invalid one), clamped outside the grid, and falls back to the
// nearest valid probe when its whole cell is invalid. Expected values are computed here from the grid.
TEST(LightmapAsset, LightProbesRoundTripAndInterpolate)
{
    hemi::io::LightmapAsset a = small_asset();
    a.probes = probe_grid();
    a.probes.valid[5] = 0;
    const fs::path p = dir() / "probes.hemi";
    hemi::io::write_lightmap_asset(p, a);
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(p);
    EXPECT_EQ(b.probes.count, a.probes.count);
    EXPECT_EQ(b.probes.lo, a.probes.lo);
    EXPECT_EQ(b.probes.hi, a.probes.hi);
    EXPECT_EQ(b.probes.irradiance, a.probes.irradiance);
    EXPECT_EQ(b.probes.valid, a.probes.valid);
    hemi::io::write_lightmap_asset(dir() / "no_probes.hemi", small_asset());
    EXPECT_TRUE(hemi::io::read_lightmap_asset(dir() / "no_probes.hemi").probes.empty());

    const hemi::io::LightProbes all = probe_grid();
    EXPECT_EQ(all.position(1, 0, 1), glm::vec3(2.0f, 0.0f, 4.0f));
    // Trilinear: the value is linear in (x / 2, y, z / 4) with weights 1, 2, 4.
    for (const glm::vec3 q :
         {glm::vec3(0.5f, 0.25f, 1.0f), glm::vec3(1.9f, 0.8f, 0.3f), glm::vec3(1.0f, 0.5f, 2.0f)})
    {
        const float expected = q.x / 2.0f + 2.0f * q.y + 4.0f * q.z / 4.0f;
        EXPECT_NEAR(all.at(q)[3].y, expected * 4.0f, 1e-5f) << q.x << "," << q.y << "," << q.z;
    }
    // Clamped to the grid outside it.
    EXPECT_NEAR(all.at(glm::vec3(-3.0f, 9.0f, 2.0f))[0].x, 0.0f + 2.0f + 2.0f, 1e-5f);
    // Probe 5 = (1, 0, 1) invalid: at the centre the mean of the other seven (28 - 5) / 7.
    EXPECT_NEAR(b.probes.at(glm::vec3(1.0f, 0.5f, 2.0f))[0].x, 23.0f / 7.0f, 1e-5f);
    // Exactly at probe 5, (2, 0, 4), every other weight is 0: the nearest valid probe, 7 at (2, 1, 4), 1 unit
    // away (4 is 2 away, 1 is 4 away).
    EXPECT_EQ(b.probes.at(glm::vec3(2.0f, 0.0f, 4.0f))[0].x, 7.0f);
    hemi::io::LightProbes lonely = probe_grid();
    lonely.valid.assign(8, 0);
    lonely.valid[6] = 1;
    EXPECT_EQ(lonely.at(glm::vec3(2.0f, 0.0f, 0.0f))[0].x, 6.0f);
    lonely.valid[6] = 0;
    EXPECT_EQ(lonely.at(glm::vec3(1.0f))[0].x, 0.0f);

    auto refused = [](hemi::io::LightmapAsset bad, const std::string& what)
    {
        try
        {
            hemi::io::write_lightmap_asset(dir() / "never_probes.hemi", bad);
            ADD_FAILURE() << "accepted: " << what;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    hemi::io::LightmapAsset bad = a;
    bad.probes.irradiance.pop_back();
    refused(bad, "probes and");
    bad = a;
    bad.probes.irradiance[2][4].z = NAN;
    refused(bad, "not finite");
    bad = a;
    bad.probes.lo.x = 5.0f;
    refused(bad, "corners");
}
