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
            EXPECT_NEAR(r.maps[i], o.maps[i], std::abs(o.maps[i]) * 4.9e-4 + 1e-7) << o.name << " " << i; // 2^-11
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
    auto refused = [](hemi::io::LightmapAsset a, const std::string& what) {
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
