// The lightmap asset (io/lightmap_asset.h): every value round-trips (coefficients through half floats, so to
// half precision); truncated, corrupted, inconsistent and other kinds of files are refused naming the file;
// the coefficient maps are stored as the 8x8 blocks that hold texels (io/block_maps.h), in the layout the
// header documents, and the dense layout 1 is still read.
#include "../temp_dir.h"

#include <hemi/bake/factored.h>
#include <hemi/io/asset.h>
#include <hemi/io/block_maps.h>
#include <hemi/io/half_scale.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>

#include <glm/gtc/packing.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <tuple>

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
        std::vector<float> dense(size_t(k) * 15 * 3);
        for (size_t i = 0; i < dense.size(); ++i)
            dense[i] = float(std::sin(double(i) * 0.7)) * 3.0f;
        a.outputs.push_back({name, k, hemi::io::BlockMaps::from_dense(5, 3, k, dense)});
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
        const std::vector<float> written = o.maps.dense(), read = r.maps.dense();
        ASSERT_EQ(read.size(), written.size());
        for (size_t i = 0; i < written.size(); ++i)
            EXPECT_NEAR(read[i], written[i], std::abs(written[i]) * 4.9e-4 + 1e-7)
                << o.name << " " << i; // 2^-11
    }
    EXPECT_THROW(b.output("sh9"), std::invalid_argument);
    EXPECT_EQ(hemi::io::asset_kind(p), "lightmap");
}

// An engine's pack file hands hemi the asset's bytes: read from memory, the asset is the one read from its
// file, and a corrupted copy is refused naming the name the engine gave it.
// The outputs of an asset added one at a time (io::LightmapAssetWriter, what hemi-bake lightmap does so as to
// hold one output in floats): the file reads back with the outputs added, in their order, to half precision,
// with the rest of the asset (probes included); the writer reads none of the asset's own outputs, and refuses
// a file without outputs and an output that does not fit the atlas, naming them.
TEST(LightmapAsset, OutputsAddedOneAtATimeReadBack)
{
    hemi::io::LightmapAsset a = small_asset();
    const std::vector<hemi::io::LightmapOutput> outputs = a.outputs;
    a.outputs.resize(1); // the writer ignores them
    const fs::path p = dir() / "streamed.hemi";
    {
        hemi::io::LightmapAssetWriter writer(a);
        for (size_t i = outputs.size(); i-- > 0;)
            writer.add_output(outputs[i]);
        writer.write(p);
    }
    const hemi::io::LightmapAsset back = hemi::io::read_lightmap_asset(p);
    ASSERT_EQ(back.outputs.size(), outputs.size());
    for (const hemi::io::LightmapOutput& want : outputs)
    {
        const std::vector<float> got = back.output(want.name).maps.dense(), dense = want.maps.dense();
        ASSERT_EQ(got.size(), dense.size());
        for (size_t j = 0; j < got.size(); ++j)
            EXPECT_NEAR(got[j], dense[j], 1e-3f * std::abs(dense[j]) + 1e-6f) << want.name << " value " << j;
    }
    EXPECT_EQ(back.mesh.uvs1, a.mesh.uvs1);
    EXPECT_EQ(back.width, 5u);

    hemi::io::LightmapAssetWriter empty(a);
    try
    {
        empty.write(dir() / "no_outputs.hemi");
        ADD_FAILURE() << "an asset without outputs was written";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("no outputs"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir() / "no_outputs.hemi"));
    hemi::io::LightmapOutput wrong = outputs[0];
    wrong.maps =
        hemi::io::BlockMaps::from_dense(4, 3, wrong.k, std::vector<float>(size_t(wrong.k) * 12 * 3, 1.0f));
    try
    {
        empty.add_output(wrong);
        ADD_FAILURE() << "an output of another atlas size was taken";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("'" + wrong.name + "'"), std::string::npos) << e.what();
    }
}

TEST(LightmapAsset, ReadsFromBytesInMemory)
{
    const fs::path p = dir() / "in_memory.hemi";
    hemi::io::write_lightmap_asset(p, small_asset());
    std::ifstream f(p, std::ios::binary);
    const std::vector<char> chars((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    std::vector<std::byte> bytes(chars.size());
    std::memcpy(bytes.data(), chars.data(), chars.size());
    const hemi::io::LightmapAsset from_file = hemi::io::read_lightmap_asset(p);
    const hemi::io::LightmapAsset from_memory = hemi::io::read_lightmap_asset(bytes, "levels.pak:level.hemi");
    EXPECT_EQ(from_memory.mesh.indices, from_file.mesh.indices);
    EXPECT_EQ(from_memory.mesh.uvs1, from_file.mesh.uvs1);
    ASSERT_EQ(from_memory.outputs.size(), from_file.outputs.size());
    for (size_t i = 0; i < from_file.outputs.size(); ++i)
        EXPECT_EQ(from_memory.outputs[i].maps.dense(), from_file.outputs[i].maps.dense());
    bytes[bytes.size() / 2] ^= std::byte{0x10};
    try
    {
        hemi::io::read_lightmap_asset(bytes, "levels.pak:level.hemi");
        ADD_FAILURE() << "a corrupted copy in memory was read";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_EQ(std::string(e.what()).rfind("levels.pak:level.hemi: checksum mismatch", 0), 0u) << e.what();
    }
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
    a.outputs[1].maps.values.pop_back();
    refused(a, "values, its blocks need");
    a = small_asset();
    a.outputs[0].maps.values[3] = NAN;
    refused(a, "not finite");
    a = small_asset();
    a.outputs[0].maps.values[3] = INFINITY;
    refused(a, "not finite");
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

// ---- Block-sparse maps (io/block_maps.h) and the asset's block layout ----

// A 21 x 13 atlas (its last block column and row reach past it) with values at a few texels: exactly the
// blocks that hold one are kept, every texel reads back, and the dense array comes back unchanged. The
// expected blocks are worked out here from the texels, 3 blocks a row. Fails for a block index taken as
// bx * blocks_y + by, for partial blocks dropped, or for a slot that mixes up x and y.
TEST(BlockMaps, KeepExactlyTheBlocksThatHoldAValueAndReadBackEveryTexel)
{
    const uint32_t w = 21, h = 13, k = 2;
    std::vector<float> dense(size_t(k) * w * h * 3, 0.0f);
    const struct
    {
        uint32_t map, x, y, c;
        float v;
    } values[] = {{0, 0, 0, 0, 1.5f},
                  {0, 9, 2, 1, -2.0f},
                  {1, 20, 12, 2, 3.25f},
                  {1, 17, 3, 0, 0.5f},
                  {0, 17, 4, 2, 7.0f}};
    std::set<uint32_t> expected;
    for (const auto& t : values)
    {
        dense[((size_t(t.map) * h + t.y) * w + t.x) * 3 + t.c] = t.v;
        expected.insert(t.y / 8 * 3 + t.x / 8);
    }
    const hemi::io::BlockMaps m = hemi::io::BlockMaps::from_dense(w, h, k, dense);
    EXPECT_EQ(m.grid.blocks(), std::vector<uint32_t>(expected.begin(), expected.end()));
    EXPECT_EQ(m.values.size(), expected.size() * k * 64 * 3);
    for (uint32_t map = 0; map < k; ++map)
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
            {
                const glm::vec3 v = m.at(map, x, y);
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(v[c], dense[((size_t(map) * h + y) * w + x) * 3 + size_t(c)])
                        << map << " " << x << " " << y;
            }
    EXPECT_EQ(m.dense(), dense);
    EXPECT_EQ(m.at(0, -1, 0), glm::vec3(0.0f));
    EXPECT_EQ(m.at(1, 21, 12), glm::vec3(0.0f)); // past the atlas, inside a kept block
    for (size_t s = 0; s < m.grid.slots(); ++s)
    {
        const glm::uvec2 t = m.grid.texel(s);
        if (t.x < w && t.y < h)
        {
            EXPECT_EQ(m.grid.slot(t.x, t.y), int64_t(s));
        }
    }
    EXPECT_THROW(hemi::io::BlockGrid(w, h, {4, 2}), std::invalid_argument); // out of order
    EXPECT_THROW(hemi::io::BlockGrid(w, h, {1, 1}), std::invalid_argument); // twice
    EXPECT_THROW(hemi::io::BlockGrid(w, h, {0, 6}), std::invalid_argument); // 6 blocks in the grid
    EXPECT_THROW(hemi::io::BlockGrid(0, h, {}), std::invalid_argument);     // no texels
    EXPECT_THROW(hemi::io::BlockMaps::from_dense(w, h, 3, dense), std::invalid_argument); // wrong K
}

// bilinear() (taps() then read()) against a bilinear lookup written out here from the dense array, at points
// all over a 21 x 13 atlas whose values change from texel to texel: across block borders (one, two or four
// blocks under a lookup), at the clamped edges and over blocks that are not kept. Fails for a tap taken from
// the wrong block when the footprint straddles a border, for a kept neighbour read as 0, or for swapped
// weights.
TEST(BlockMaps, BilinearLookupsReadTheFourTexelsAroundThePoint)
{
    const uint32_t w = 21, h = 13;
    std::vector<float> dense(size_t(w) * h * 3, 0.0f);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            if (!(x >= 8 && x < 16 && y >= 8)) // block (1, 1) stays empty: it is not kept
                for (int c = 0; c < 3; ++c)
                    dense[(size_t(y) * w + x) * 3 + size_t(c)] = float(1 + x + 100 * y + 10000 * c);
    const hemi::io::BlockMaps m = hemi::io::BlockMaps::from_dense(w, h, 1, dense);
    ASSERT_EQ(m.grid.blocks().size(), 5u);
    auto texel = [&](int64_t x, int64_t y, int c)
    {
        x = std::clamp<int64_t>(x, 0, w - 1);
        y = std::clamp<int64_t>(y, 0, h - 1);
        return double(dense[(size_t(y) * w + size_t(x)) * 3 + size_t(c)]);
    };
    for (int j = 0; j <= 60; ++j)
        for (int i = 0; i <= 90; ++i)
        {
            const glm::vec2 uv(float(i) / 90.0f, float(j) / 60.0f);
            const double fx = double(uv.x) * w - 0.5, fy = double(uv.y) * h - 0.5;
            const int64_t x0 = int64_t(std::floor(fx)), y0 = int64_t(std::floor(fy));
            const double tx = fx - double(x0), ty = fy - double(y0);
            const glm::vec3 got = m.bilinear(0, uv);
            for (int c = 0; c < 3; ++c)
            {
                const double expected =
                    (texel(x0, y0, c) * (1 - tx) + texel(x0 + 1, y0, c) * tx) * (1 - ty) +
                    (texel(x0, y0 + 1, c) * (1 - tx) + texel(x0 + 1, y0 + 1, c) * tx) * ty;
                ASSERT_NEAR(got[c], expected, 1e-6 * std::max(1.0, std::abs(expected)))
                    << uv.x << " " << uv.y;
            }
        }
}

// A grid too large for the bitmap of kept blocks (over 2^28 blocks: slot() then searches the kept blocks of a
// row) answers as a small one does: the same few blocks, placed alike, give each texel the slot its block's
// rank says, and -1 around them. Fails when one of the two ways of finding a block is wrong.
TEST(BlockMaps, LargeAndSmallGridsFindTheSameSlots)
{
    const uint32_t big = 131080, small = 64; // 16385^2 blocks (over 2^28) and 8^2
    const std::vector<glm::uvec2> kept = {{0, 0}, {3, 0}, {1, 2}, {2, 2}, {7, 5}};
    std::vector<uint32_t> big_blocks, small_blocks;
    for (const glm::uvec2& b : kept)
    {
        big_blocks.push_back(b.y * ((big + 7) / 8) + b.x);
        small_blocks.push_back(b.y * (small / 8) + b.x);
    }
    const hemi::io::BlockGrid a(big, big, big_blocks), b(small, small, small_blocks);
    for (int64_t y = -1; y <= int64_t(small); ++y)
        for (int64_t x = -1; x <= int64_t(small); ++x)
        {
            int64_t expected = -1;
            for (size_t k = 0; k < kept.size(); ++k)
                if (x >= 0 && y >= 0 && uint32_t(x / 8) == kept[k].x && uint32_t(y / 8) == kept[k].y)
                    expected = int64_t(k) * 64 + (y % 8) * 8 + x % 8;
            ASSERT_EQ(b.slot(x, y), x >= int64_t(small) || y >= int64_t(small) ? -1 : expected)
                << x << " " << y;
            if (x < int64_t(small) && y < int64_t(small))
            {
                ASSERT_EQ(a.slot(x, y), expected) << x << " " << y;
            }
        }
}

namespace
{
// A 4096 x 4096 atlas whose only texel (1234, 2345) holds `plain`: one 8x8 block, made without the dense
// atlas (which would be 200 MB of floats).
hemi::io::LightmapAsset one_texel_asset(const glm::vec3& plain)
{
    hemi::io::LightmapAsset a = small_asset();
    a.width = a.height = 4096;
    a.covered_texels = 1;
    a.outputs.clear();
    const uint32_t block = 2345 / 8 * 512 + 1234 / 8;
    hemi::io::BlockMaps m(hemi::io::BlockGrid(4096, 4096, {block}), 1);
    const size_t at = m.index(0, size_t(m.grid.slot(1234, 2345)));
    m.values[at] = plain.x;
    m.values[at + 1] = plain.y;
    m.values[at + 2] = plain.z;
    a.outputs.push_back({"plain", 1, std::move(m)});
    return a;
}
} // namespace

// A 4096^2 lightmap with one covered texel is a few kilobytes (the dense layout stored 100 MB), and its
// section holds what lightmap_asset.h documents, parsed here from the bytes: K, N, the scale's exponent e,
// the block indices, then the halves, coefficient k of local texel (x, y) of block b at
// ((b * K + k) * 64 + y * 8 + x) * 3 + c, each the value / 2^e (e = 0 for these ordinary values).
TEST(LightmapAsset, StoresOnlyTheBlocksThatHoldTexelsInTheDocumentedLayout)
{
    const fs::path p = dir() / "one_texel.hemi";
    hemi::io::write_lightmap_asset(p, one_texel_asset({1.0f, 2.5f, -0.75f}));
    EXPECT_LT(fs::file_size(p), 16384u);
    const hemi::io::AssetReader r(p);
    const std::span<const std::byte> b = r.section("L.plain");
    ASSERT_EQ(b.size(), 4u + 4u + 4u + 4u + 64u * 3u * 2u);
    uint32_t head[4];
    std::memcpy(head, b.data(), 16);
    EXPECT_EQ(head[0], 1u);                                  // K
    EXPECT_EQ(head[1], 1u);                                  // N
    EXPECT_EQ(head[2], 0u);                                  // e
    EXPECT_EQ(head[3], uint32_t(2345 / 8 * 512 + 1234 / 8)); // by * ceil(W / 8) + bx
    const size_t local = size_t(2345 % 8) * 8 + 1234 % 8;
    for (size_t i = 0; i < 64 * 3; ++i)
    {
        uint16_t half;
        std::memcpy(&half, b.data() + 16 + 2 * i, 2);
        const float expected = i / 3 == local ? std::array<float, 3>{1.0f, 2.5f, -0.75f}[i % 3] : 0.0f;
        EXPECT_EQ(glm::unpackHalf1x16(half), expected) << i;
    }
    const hemi::io::LightmapAsset a = hemi::io::read_lightmap_asset(p);
    const hemi::io::BlockMaps& m = a.output("plain").maps;
    EXPECT_EQ(m.at(0, 1234, 2345), glm::vec3(1.0f, 2.5f, -0.75f));
    EXPECT_EQ(m.at(0, 1235, 2345), glm::vec3(0.0f));
    EXPECT_EQ(m.at(0, 0, 0), glm::vec3(0.0f));
    EXPECT_EQ(m.grid.blocks().size(), 1u);
}

namespace
{
// `good` with its lightmap.info and L.<output> sections replaced (the rest copied).
fs::path rewritten(const fs::path& good, const std::string& name,
                   const std::function<void(const std::string&, std::vector<std::byte>&)>& edit)
{
    const hemi::io::AssetReader r(good);
    hemi::io::AssetWriter w;
    for (const std::string& section : r.names())
    {
        const std::span<const std::byte> b = r.section(section);
        std::vector<std::byte> bytes(b.begin(), b.end());
        edit(section, bytes);
        w.add(section, bytes);
    }
    const fs::path p = dir() / name;
    w.write(p);
    return p;
}
} // namespace

// An asset of layout 1 (the dense K x H x W x 3 halves hemi wrote before the blocks) still reads, to the same
// values; made here from a layout-2 asset by rewriting its sections as layout 1 documented them.
TEST(LightmapAsset, ReadsTheDenseLayoutOne)
{
    const hemi::io::LightmapAsset a = small_asset();
    const fs::path good = dir() / "layout2.hemi";
    hemi::io::write_lightmap_asset(good, a);
    const fs::path old = rewritten(good, "layout1.hemi",
                                   [&](const std::string& section, std::vector<std::byte>& bytes)
                                   {
                                       if (section == "lightmap.info")
                                       {
                                           const uint32_t one = 1;
                                           std::memcpy(bytes.data(), &one, 4);
                                       }
                                       if (section.rfind("L.", 0) != 0)
                                           return;
                                       const hemi::io::LightmapOutput& o = a.output(section.substr(2));
                                       const std::vector<float> dense = o.maps.dense();
                                       bytes.resize(4 + dense.size() * 2);
                                       std::memcpy(bytes.data(), &o.k, 4);
                                       for (size_t i = 0; i < dense.size(); ++i)
                                       {
                                           const uint16_t h = uint16_t(glm::packHalf1x16(dense[i]));
                                           std::memcpy(bytes.data() + 4 + 2 * i, &h, 2);
                                       }
                                   });
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(old);
    ASSERT_EQ(b.outputs.size(), a.outputs.size());
    for (const hemi::io::LightmapOutput& o : a.outputs)
    {
        const std::vector<float> written = o.maps.dense(), read = b.output(o.name).maps.dense();
        ASSERT_EQ(read.size(), written.size());
        for (size_t i = 0; i < written.size(); ++i)
            EXPECT_EQ(read[i], glm::unpackHalf1x16(glm::packHalf1x16(written[i]))) << o.name << " " << i;
    }
}

// Block lists that are not strictly ascending, or name blocks past the grid, or disagree with the section's
// size, are refused naming the file and the section.
TEST(LightmapAsset, RefusesBadBlockLists)
{
    const fs::path good = dir() / "blocks.hemi";
    hemi::io::write_lightmap_asset(good, small_asset()); // 5 x 3: one block, index 0
    auto with_blocks = [&](const std::string& name, std::vector<uint32_t> blocks)
    {
        return rewritten(good, name,
                         [&](const std::string& section, std::vector<std::byte>& bytes)
                         {
                             const uint32_t width = 17; // 3 blocks, so that block 0 stays valid
                             if (section == "lightmap.info")
                                 std::memcpy(bytes.data() + 4, &width, 4);
                             if (section != "L.plain")
                                 return;
                             const uint32_t n = uint32_t(blocks.size());
                             std::vector<std::byte> out(12 + n * 4 + size_t(n) * 64 * 3 * 2);
                             std::memcpy(out.data(), bytes.data(), 4); // K = 1
                             std::memcpy(out.data() + 4, &n, 4);       // and e = 0
                             if (n > 0) // memcpy from an empty vector's null data() is undefined
                                 std::memcpy(out.data() + 12, blocks.data(), n * 4);
                             bytes = out;
                         });
    };
    // No blocks at all: an output that is 0 everywhere, read as such (and written back the same way).
    const fs::path empty = with_blocks("no_blocks.hemi", {});
    const hemi::io::LightmapAsset none = hemi::io::read_lightmap_asset(empty);
    EXPECT_TRUE(none.output("plain").maps.grid.blocks().empty());
    EXPECT_EQ(none.output("plain").maps.at(0, 2, 1), glm::vec3(0.0f));
    hemi::io::write_lightmap_asset(dir() / "no_blocks_again.hemi", none);
    EXPECT_TRUE(
        hemi::io::read_lightmap_asset(dir() / "no_blocks_again.hemi").output("plain").maps.values.empty());
    for (const auto& [name, blocks, what] :
         {std::tuple{"twice.hemi", std::vector<uint32_t>{0, 0}, "ascending"},
          std::tuple{"past.hemi", std::vector<uint32_t>{3}, "out of the 3-block grid"},
          std::tuple{"many.hemi", std::vector<uint32_t>{0, 1, 2, 3}, "atlas has 3"}})
    {
        const fs::path p = with_blocks(name, blocks);
        const std::string e = error_of(p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << e;
        EXPECT_NE(e.find("L.plain"), std::string::npos) << e;
        EXPECT_NE(e.find(what), std::string::npos) << e;
    }
}

// Light of any magnitude (io/half_scale.h): the exponent of the scale for the values' largest magnitude is 0
// from 2^-6 to 2^15 (bytes as before) and otherwise brings the largest into (2^13, 2^14]; an output of a
// 100,000-lux sun (1.2e5) or a moonlit 1e-5 round-trips to the halves' relative precision (2^-11), where
// scale 1 would overflow to infinity (refused) or flush to 0, and its section stores the exponent.
TEST(LightmapAsset, LightOfAnyMagnitudeRoundTripsWithItsScale)
{
    EXPECT_EQ(hemi::io::half_scale_exponent(0.0f), 0);
    EXPECT_EQ(hemi::io::half_scale_exponent(1.0f), 0);
    EXPECT_EQ(hemi::io::half_scale_exponent(0x1p15f), 0);
    EXPECT_EQ(hemi::io::half_scale_exponent(0x1p-6f), 0);
    EXPECT_EQ(hemi::io::half_scale_exponent(0x1.0002p15f), 2); // (2^15, 2^16] / 2^2 is in (2^13, 2^14]
    EXPECT_EQ(hemi::io::half_scale_exponent(1.2e5f), 3);       // 1.2e5 / 8 = 15000
    EXPECT_EQ(hemi::io::half_scale_exponent(0x1p16f), 2);      // exactly 2^14 after
    EXPECT_EQ(hemi::io::half_scale_exponent(1e-5f), -30);      // 1e-5 * 2^30 = 10737
    EXPECT_EQ(hemi::io::half_scale_exponent(3e38f), hemi::io::kMaxHalfScaleExponent);
    for (const float largest : {1.2e5f, 3.5e9f, 1e-5f, 2e-9f})
    {
        hemi::io::LightmapAsset a = small_asset();
        for (hemi::io::LightmapOutput& o : a.outputs)
            for (size_t i = 0; i < o.maps.values.size(); ++i) // values from -largest to largest and near 0
                o.maps.values[i] = largest * std::sin(float(i) * 0.7f) * (i % 5 == 0 ? 1e-3f : 1.0f);
        const fs::path p = dir() / "bright.hemi";
        hemi::io::write_lightmap_asset(p, a);
        const int e = hemi::io::half_scale_exponent(hemi::io::largest_magnitude(a.outputs[0].maps.values));
        const hemi::io::AssetReader r(p);
        int32_t stored = 0;
        std::memcpy(&stored, r.section("L." + a.outputs[0].name).data() + 8, 4);
        EXPECT_EQ(stored, e) << largest;
        EXPECT_NE(e, 0) << largest;
        const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(p);
        for (size_t k = 0; k < a.outputs.size(); ++k)
            for (size_t i = 0; i < a.outputs[k].maps.values.size(); ++i)
            {
                const float v = a.outputs[k].maps.values[i], w = b.output(a.outputs[k].name).maps.values[i];
                ASSERT_LE(std::abs(w - v), std::abs(v) * 0x1p-11f) << largest << " " << k << " " << i;
            }
    }
}

// An asset of layout 2 (blocks without the scale's exponent, what hemi wrote before) still reads, to the
// same values; made from a layout-3 asset by taking the exponent out of its sections.
TEST(LightmapAsset, ReadsLayoutTwoWithoutAScale)
{
    const hemi::io::LightmapAsset a = small_asset();
    const fs::path good = dir() / "layout3.hemi";
    hemi::io::write_lightmap_asset(good, a);
    const fs::path old = rewritten(good, "layout2.hemi",
                                   [&](const std::string& section, std::vector<std::byte>& bytes)
                                   {
                                       if (section == "lightmap.info")
                                       {
                                           const uint32_t two = 2;
                                           std::memcpy(bytes.data(), &two, 4);
                                       }
                                       if (section.rfind("L.", 0) == 0)
                                           bytes.erase(bytes.begin() + 8, bytes.begin() + 12);
                                   });
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(old);
    ASSERT_EQ(b.outputs.size(), a.outputs.size());
    for (const hemi::io::LightmapOutput& o : a.outputs)
        EXPECT_EQ(b.output(o.name).maps.values,
                  hemi::io::read_lightmap_asset(good).output(o.name).maps.values);
    // A layout-3 section whose exponent is out of range is refused naming it.
    const fs::path bad = rewritten(good, "bad_scale.hemi",
                                   [&](const std::string& section, std::vector<std::byte>& bytes)
                                   {
                                       const int32_t e = 200;
                                       if (section == "L.plain")
                                           std::memcpy(bytes.data() + 8, &e, 4);
                                   });
    const std::string e = error_of(bad);
    EXPECT_NE(e.find("L.plain: scale 2^200"), std::string::npos) << e;
}

// Issue 43: the lights with their bake modes and shadowmask channels, and the RGBA8 shadowmask, read back
// (the mask to the nearest 1/255); a mixed light without a mask, a channel out of range and cut sections are
// refused naming the file and the section.
TEST(LightmapAsset, LightsAndTheShadowmaskRoundTrip)
{
    hemi::io::LightmapAsset a = small_asset();
    hemi::io::LightmapLight sun;
    sun.light.type = hemi::io::PunctualLight::Type::Directional;
    sun.light.name = "sun";
    sun.light.color = glm::vec3(3.0f, 2.0f, 1.0f);
    sun.light.intensity = 1.5f;
    sun.light.direction = glm::normalize(glm::vec3(-1.0f, -2.0f, 0.5f));
    sun.light.mode = hemi::io::LightMode::Mixed;
    sun.angular_diameter_degrees = 0.53f;
    sun.channel = 2;
    hemi::io::LightmapLight lamp;
    lamp.light.type = hemi::io::PunctualLight::Type::Spot;
    lamp.light.name = "lamp \xc3\xa9"; // UTF-8
    lamp.light.position = glm::vec3(1.0f, 2.0f, 3.0f);
    lamp.light.range = 4.0f;
    lamp.light.intensity = 20.0f;
    lamp.light.color = glm::vec3(0.25f, 0.5f, 1.0f);
    lamp.light.direction = glm::normalize(glm::vec3(0.0f, -1.0f, -1.0f));
    lamp.light.inner_cone = 0.1f;
    lamp.light.outer_cone = 0.4f;
    lamp.light.mode = hemi::io::LightMode::Realtime;
    a.lights = {sun, lamp};
    std::vector<float> dense(4 * 15 * 3);
    for (size_t c = 0; c < 4; ++c)
        for (size_t t = 0; t < 15; ++t)
            for (size_t rgb = 0; rgb < 3; ++rgb)
                dense[(c * 15 + t) * 3 + rgb] = float((t * 7 + c * 3) % 16) / 15.0f;
    a.shadowmask = hemi::io::BlockMaps::from_dense(5, 3, 4, dense);
    // The probes' occlusion of the mixed lights, to 1/255, interpolated like the irradiance.
    a.probes = probe_grid();
    a.probes.occlusion.resize(a.probes.irradiance.size());
    for (size_t i = 0; i < a.probes.occlusion.size(); ++i)
        for (size_t c = 0; c < 4; ++c)
            a.probes.occlusion[i][c] = float((i * 5 + c * 11) % 256) / 255.0f;
    const fs::path p = dir() / "mixed.hemi";
    hemi::io::write_lightmap_asset(p, a);
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(p);
    ASSERT_EQ(b.lights.size(), 2u);
    // Layout 4 with a mask (a hemi that knows no mixed lights refuses it), 3 without.
    {
        const hemi::io::AssetReader r(p);
        uint32_t layout = 0;
        std::memcpy(&layout, r.section("lightmap.info").data(), 4);
        EXPECT_EQ(layout, 4u);
    }
    for (size_t i = 0; i < 2; ++i)
    {
        const hemi::io::LightmapLight &x = a.lights[i], &y = b.lights[i];
        EXPECT_EQ(y.light.type, x.light.type);
        EXPECT_EQ(y.light.name, x.light.name);
        EXPECT_EQ(y.light.mode, x.light.mode);
        EXPECT_EQ(y.channel, x.channel);
        EXPECT_EQ(y.light.color, x.light.color);
        EXPECT_EQ(y.light.position, x.light.position);
        EXPECT_EQ(y.light.direction, x.light.direction);
        EXPECT_EQ(y.light.range, x.light.range);
        EXPECT_EQ(y.light.intensity, x.light.intensity);
        EXPECT_EQ(y.light.inner_cone, x.light.inner_cone);
        EXPECT_EQ(y.light.outer_cone, x.light.outer_cone);
        EXPECT_EQ(y.angular_diameter_degrees, x.angular_diameter_degrees);
    }
    ASSERT_EQ(b.probes.occlusion.size(), a.probes.occlusion.size());
    for (size_t i = 0; i < a.probes.occlusion.size(); ++i)
        for (size_t c = 0; c < 4; ++c)
            ASSERT_NEAR(b.probes.occlusion[i][c], a.probes.occlusion[i][c], 1e-6f) << i;
    {
        // Halfway between probes (0, 0, 0) and (1, 0, 0): the mean of theirs, as at() blends the irradiance.
        const hemi::io::LightProbes& q = b.probes;
        const glm::vec3 mid = (q.position(0, 0, 0) + q.position(1, 0, 0)) * 0.5f;
        const std::array<float, 4> o = q.occlusion_at(mid);
        for (size_t c = 0; c < 4; ++c)
            EXPECT_NEAR(o[c], 0.5f * (q.occlusion[0][c] + q.occlusion[1][c]), 1e-5f) << c;
        EXPECT_NEAR(q.at(mid)[0].x, 0.5f * (q.irradiance[0][0].x + q.irradiance[1][0].x), 1e-5f);
    }
    ASSERT_EQ(b.shadowmask.k, 4u);
    const std::vector<float> back = b.shadowmask.dense();
    ASSERT_EQ(back.size(), dense.size());
    for (size_t i = 0; i < dense.size(); ++i)
        ASSERT_NEAR(back[i], dense[i], 0.5f / 255.0f + 1e-6f) << i;

    hemi::io::LightmapAsset bad = a;
    bad.shadowmask = {};
    EXPECT_THROW(hemi::io::write_lightmap_asset(dir() / "bad.hemi", bad), std::invalid_argument);
    bad = a;
    bad.lights[0].channel = 4;
    EXPECT_THROW(hemi::io::write_lightmap_asset(dir() / "bad.hemi", bad), std::invalid_argument);
    bad = a;
    bad.lights[1].light.direction = glm::vec3(0.0f);
    EXPECT_THROW(hemi::io::write_lightmap_asset(dir() / "bad.hemi", bad), std::invalid_argument);
    bad = a;
    bad.lights[1].light.intensity = -1.0f;
    EXPECT_THROW(hemi::io::write_lightmap_asset(dir() / "bad.hemi", bad), std::invalid_argument);
    for (const char* section : {"lightmap.lights", "lightmap.shadowmask"})
    {
        const fs::path cut = rewritten(p, std::string("cut_") + section + ".hemi",
                                       [&](const std::string& name, std::vector<std::byte>& bytes)
                                       {
                                           if (name == section)
                                               bytes.resize(bytes.size() - 3);
                                       });
        const std::string e = error_of(cut);
        EXPECT_NE(e.find(cut.string()), std::string::npos) << e;
        EXPECT_NE(e.find(section), std::string::npos) << e;
    }
    // A mask without its lights' section: the asset's mixed lights are gone, the mask is refused.
    const fs::path no_lights =
        rewritten(p, "no_lights.hemi",
                  [](const std::string& name, std::vector<std::byte>& bytes)
                  {
                      if (name == "lightmap.lights")
                          bytes = {std::byte(0), std::byte(0), std::byte(0), std::byte(0)};
                  });
    EXPECT_NE(error_of(no_lights).find("a shadowmask without mixed lights"), std::string::npos)
        << error_of(no_lights);
}

// ---- What each probe sees (io/light_probes.h: LightProbes::depth) ----

// The octahedral map: +z at the square's centre, -z at its corners, the equator on the diamond between
// the edges' midpoints, and decode(encode(d)) = d.
TEST(LightProbes, TheOctahedralMapCoversTheSphere)
{
    EXPECT_EQ(hemi::io::octahedral_encode(glm::vec3(0, 0, 1)), glm::vec2(0.5f, 0.5f));
    EXPECT_EQ(hemi::io::octahedral_encode(glm::vec3(1, 0, 0)), glm::vec2(1.0f, 0.5f));
    EXPECT_EQ(hemi::io::octahedral_encode(glm::vec3(0, -2, 0)), glm::vec2(0.5f, 0.0f));
    EXPECT_EQ(hemi::io::octahedral_encode(glm::vec3(0, 0, -1)), glm::vec2(1.0f, 1.0f));
    for (int i = 0; i < 200; ++i)
    {
        const double z = 1.0 - (i + 0.5) / 100.0, phi = i * 2.39996;
        const glm::vec3 d(float(std::sqrt(1 - z * z) * std::cos(phi)),
                          float(std::sqrt(1 - z * z) * std::sin(phi)), float(z));
        const glm::vec2 uv = hemi::io::octahedral_encode(d);
        ASSERT_TRUE(uv.x >= 0 && uv.x <= 1 && uv.y >= 0 && uv.y <= 1);
        const glm::vec3 back = hemi::io::octahedral_decode(uv);
        EXPECT_NEAR(glm::distance(back, d), 0.0f, 1e-5f) << i;
    }
}

namespace
{
// Two probes 2 apart along x (a 2 x 1 x 1 grid), R = 8 depth maps: probe 0 sees a constant 1 with
// deviation 0.1, probe 1 the smooth f(d) = 2 + d.x + 0.5 d.y (deviation 0) at its texels' centres.
hemi::io::LightProbes seeing_probes()
{
    hemi::io::LightProbes p;
    p.count = glm::uvec3(2, 1, 1);
    p.lo = glm::vec3(0.0f);
    p.hi = glm::vec3(2.0f, 0.0f, 0.0f);
    for (int at = 0; at < 2; ++at)
    {
        std::array<glm::vec3, 9> sh{};
        sh[0] = glm::vec3(float(at + 1));
        p.irradiance.push_back(sh);
        p.valid.push_back(1);
    }
    p.depth_resolution = 8;
    p.max_distance = 10.0f;
    for (int at = 0; at < 2; ++at)
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x)
            {
                const glm::vec3 d = hemi::io::octahedral_decode(glm::vec2(x + 0.5f, y + 0.5f) / 8.0f);
                p.depth.push_back(at == 0 ? glm::vec2(1.0f, 0.1f) : glm::vec2(2.0f + d.x + 0.5f * d.y, 0.0f));
            }
    return p;
}
} // namespace

// Visibility is Chebyshev's bound, squared (worked out here): 1 up to the mean distance, (0.01 / (0.01 +
// 0.05^2))^2 = 0.64 at 1.05 from a probe whose mean is 1 with deviation 0.1, (0.01 / 0.26)^2 = 0.0014793 at
// 1.5, and the floor 1e-4 at 2.5 (the bound's 1.96e-5); the blend weights each probe by trilinear weight
// times visibility. The depth map's
// lookup returns a texel at its centre and is continuous over the whole sphere, across the octahedral map's
// folded edges too (a wrong mirror rule jumps by up to 1 there).
TEST(LightProbes, VisibilityIsChebyshevsBoundOverTheDepthMaps)
{
    const hemi::io::LightProbes p = seeing_probes();
    EXPECT_FLOAT_EQ(p.visibility(0, glm::vec3(0.0f, 0.5f, 0.0f)), 1.0f);
    EXPECT_FLOAT_EQ(p.visibility(0, glm::vec3(0.0f, 0.0f, -1.0f)), 1.0f);
    EXPECT_NEAR(p.visibility(0, glm::vec3(0.0f, -1.05f, 0.0f)), 0.64f, 1e-4f);
    EXPECT_NEAR(p.visibility(0, glm::vec3(1.5f, 0.0f, 0.0f)), 0.0014793f, 1e-6f);
    EXPECT_EQ(p.visibility(0, glm::vec3(0.0f, 0.0f, 2.5f)), hemi::io::LightProbes::kMinVisibility);
    // At x = 1.5: trilinear 0.25 and 0.75, probe 0 seeing only 0.0015 of it.
    const float w0 = 0.25f * 0.0014793f, w1 = 0.75f * p.visibility(1, glm::vec3(1.5f, 0.0f, 0.0f));
    EXPECT_FLOAT_EQ(p.visibility(1, glm::vec3(1.5f, 0.0f, 0.0f)), 1.0f); // 0.5 away, f >= 0.88
    EXPECT_NEAR(p.at(glm::vec3(1.5f, 0.0f, 0.0f))[0].x, (w0 * 1.0f + w1 * 2.0f) / (w0 + w1), 1e-6f);
    // A texel's centre returns the texel; along a great circle through both poles and the folds the lookup
    // never jumps.
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
        {
            const glm::vec3 d = hemi::io::octahedral_decode(glm::vec2(x + 0.5f, y + 0.5f) / 8.0f);
            EXPECT_NEAR(p.depth_at(1, d).x, p.depth[64 + size_t(y) * 8 + size_t(x)].x, 1e-5f)
                << x << "," << y;
        }
    for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(0.6f, 0.8f, 0), glm::vec3(0.3f, -0.2f, 0.93f)})
    {
        const glm::vec3 u = glm::normalize(glm::cross(axis, glm::vec3(0.1f, 0.2f, 1.0f))),
                        v = glm::normalize(glm::cross(axis, u));
        float previous = p.depth_at(1, u).x, jump = 0.0f;
        for (int i = 1; i <= 20000; ++i)
        {
            const float a = float(2.0 * M_PI * i / 20000);
            const float value = p.depth_at(1, std::cos(a) * u + std::sin(a) * v).x;
            jump = std::max(jump, std::abs(value - previous));
            previous = value;
        }
        EXPECT_LT(jump, 0.003f) << "around " << axis.x << "," << axis.y << "," << axis.z;
    }
}

// The depth maps round-trip through the asset to half precision of the largest distance (each value is
// stored as a half of value / max_distance, the layout the header documents); an asset without them reads
// with none (trilinear alone). The writer refuses maps of the wrong size, a NaN and a resolution out of
// range; the reader refuses a truncated section, a resolution out of range, a largest distance that is not
// finite and depth maps without probes, naming the file.
TEST(LightProbes, DepthMapsRoundTripAndBrokenOnesAreRefused)
{
    hemi::io::LightmapAsset a = small_asset();
    a.probes = seeing_probes();
    const fs::path good = dir() / "depth.hemi";
    hemi::io::write_lightmap_asset(good, a);
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(good);
    ASSERT_EQ(b.probes.depth_resolution, 8u);
    EXPECT_EQ(b.probes.max_distance, 10.0f);
    ASSERT_EQ(b.probes.depth.size(), 128u);
    for (size_t i = 0; i < 128; ++i)
    {
        EXPECT_NEAR(b.probes.depth[i].x, a.probes.depth[i].x, 10.0f / 2048.0f) << i;
        EXPECT_NEAR(b.probes.depth[i].y, a.probes.depth[i].y, 10.0f / 2048.0f) << i;
    }
    {
        const hemi::io::AssetReader r(good);
        const std::span<const std::byte> s = r.section("lightmap.probe_depth");
        ASSERT_EQ(s.size(), 8u + 2 * 64 * 4);
        uint32_t resolution = 0;
        uint16_t first[2];
        std::memcpy(&resolution, s.data(), 4);
        std::memcpy(first, s.data() + 8, 4);
        EXPECT_EQ(resolution, 8u);
        EXPECT_EQ(glm::unpackHalf1x16(first[0]), glm::unpackHalf1x16(glm::packHalf1x16(0.1f)));
        EXPECT_EQ(glm::unpackHalf1x16(first[1]), glm::unpackHalf1x16(glm::packHalf1x16(0.01f)));
    }
    hemi::io::LightmapAsset none = a;
    none.probes.depth.clear();
    none.probes.depth_resolution = 0;
    hemi::io::write_lightmap_asset(dir() / "no_depth.hemi", none);
    EXPECT_TRUE(hemi::io::read_lightmap_asset(dir() / "no_depth.hemi").probes.depth.empty());

    for (const auto& [edit, what] :
         {std::pair<std::function<void(hemi::io::LightProbes&)>, std::string>{
              [](hemi::io::LightProbes& p) { p.depth.pop_back(); }, "depth maps hold 127 texels"},
          {[](hemi::io::LightProbes& p) { p.depth[7].y = NAN; }, "not finite"},
          {[](hemi::io::LightProbes& p) { p.depth[7].x = 11.0f; }, "beyond its largest"},
          {[](hemi::io::LightProbes& p) { p.depth_resolution = 65; }, "not 1 to 64"}})
    {
        hemi::io::LightmapAsset bad = a;
        edit(bad.probes);
        try
        {
            hemi::io::write_lightmap_asset(dir() / "never_depth.hemi", bad);
            ADD_FAILURE() << "accepted: " << what;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    }
    auto read_refused = [&](const std::string& name, const std::string& what,
                            const std::function<void(const std::string&, std::vector<std::byte>&)>& edit)
    {
        const fs::path p = rewritten(good, name, edit);
        const std::string e = error_of(p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << e;
        EXPECT_NE(e.find(what), std::string::npos) << e;
    };
    read_refused("depth_short.hemi", "lightmap.probe_depth has 519 bytes",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     if (s == "lightmap.probe_depth")
                         bytes.pop_back();
                 });
    read_refused("depth_huge.hemi", "depth maps of 65 texels",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     const uint32_t r = 65;
                     if (s == "lightmap.probe_depth")
                         std::memcpy(bytes.data(), &r, 4);
                 });
    read_refused("depth_nan.hemi", "largest distance",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     const float m = NAN;
                     if (s == "lightmap.probe_depth")
                         std::memcpy(bytes.data() + 4, &m, 4);
                 });
    read_refused("depth_negative.hemi", "negative",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     const uint16_t h = glm::packHalf1x16(-0.5f);
                     if (s == "lightmap.probe_depth")
                         std::memcpy(bytes.data() + 8, &h, 2);
                 });
    // Without lightmap.probes.
    const hemi::io::AssetReader r(good);
    hemi::io::AssetWriter w;
    for (const std::string& section : r.names())
        if (section != "lightmap.probes")
        {
            const std::span<const std::byte> s = r.section(section);
            w.add(section, std::vector<std::byte>(s.begin(), s.end()));
        }
    w.write(dir() / "depth_alone.hemi");
    EXPECT_NE(error_of(dir() / "depth_alone.hemi").find("lightmap.probe_depth without lightmap.probes"),
              std::string::npos);
}

// Reflection probes travel in the lightmap asset (lightmap.reflections and reflection<i>.*, laid out as an
// environment asset's sections): centre, box and every map round-trip exactly; a count that disagrees with
// the section's size, a missing map section and a box out of order are refused, naming the file.
TEST(LightmapAsset, ReflectionProbesRoundTrip)
{
    hemi::io::ImageRgba sky{32, 16, std::vector<float>(32 * 16 * 4, 1.0f)};
    for (size_t i = 0; i < sky.pixels.size(); ++i)
        sky.pixels[i] = 0.5f + 0.4f * std::sin(float(i) * 0.37f);
    hemi::bake::EnvmapBakeOptions eo;
    eo.size = 8;
    eo.exponents = {10};
    hemi::io::LightmapAsset a = small_asset();
    for (int i = 0; i < 2; ++i)
        a.reflections.push_back({glm::vec3(0.1f * i, 0.5f, 0.2f), glm::vec3(-1.0f),
                                 glm::vec3(1.0f, 2.0f, 1.5f), hemi::bake::bake_envmap(sky, eo)});
    a.reflections[1].maps.mirror[0].rgb[5] = 7.0f; // the two differ
    const fs::path good = dir() / "reflections.hemi";
    hemi::io::write_lightmap_asset(good, a);
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(good);
    ASSERT_EQ(b.reflections.size(), 2u);
    for (size_t i = 0; i < 2; ++i)
    {
        EXPECT_EQ(b.reflections[i].centre, a.reflections[i].centre);
        EXPECT_EQ(b.reflections[i].box_min, a.reflections[i].box_min);
        EXPECT_EQ(b.reflections[i].box_max, a.reflections[i].box_max);
        ASSERT_EQ(b.reflections[i].maps.mirror.size(), a.reflections[i].maps.mirror.size());
        for (size_t l = 0; l < a.reflections[i].maps.mirror.size(); ++l)
            EXPECT_EQ(b.reflections[i].maps.mirror[l].rgb, a.reflections[i].maps.mirror[l].rgb)
                << i << " " << l;
        EXPECT_EQ(b.reflections[i].maps.glossy[0].rgb, a.reflections[i].maps.glossy[0].rgb);
        EXPECT_EQ(b.reflections[i].maps.diffuse.rgb, a.reflections[i].maps.diffuse.rgb);
        EXPECT_EQ(b.reflections[i].maps.exponents, a.reflections[i].maps.exponents);
    }
    hemi::io::LightmapAsset bad = a;
    std::swap(bad.reflections[0].box_min, bad.reflections[0].box_max);
    EXPECT_THROW(hemi::io::write_lightmap_asset(dir() / "never_reflections.hemi", bad),
                 std::invalid_argument);

    const fs::path miscounted = rewritten(good, "reflections_count.hemi",
                                          [](const std::string& s, std::vector<std::byte>& bytes)
                                          {
                                              const uint32_t three = 3;
                                              if (s == "lightmap.reflections")
                                                  std::memcpy(bytes.data(), &three, 4);
                                          });
    std::string e = error_of(miscounted);
    EXPECT_NE(e.find(miscounted.string()), std::string::npos) << e;
    EXPECT_NE(e.find("lightmap.reflections has 76 bytes for 3 probes"), std::string::npos) << e;
    const hemi::io::AssetReader r(good);
    hemi::io::AssetWriter w;
    for (const std::string& section : r.names())
        if (section != "reflection1.mirror")
        {
            const std::span<const std::byte> s = r.section(section);
            w.add(section, std::vector<std::byte>(s.begin(), s.end()));
        }
    w.write(dir() / "reflections_missing.hemi");
    e = error_of(dir() / "reflections_missing.hemi");
    EXPECT_NE(e.find("reflection1.mirror"), std::string::npos) << e;
}

// Scattered probes (issue 44) round-trip through the asset with their points and reaches (section
// lightmap.probe_points; lightmap.probes' kind 1), and are looked up by their bumps: at a probe's own point
// with no other reaching, its value; halfway between two probes of equal reach, their mean. The writer
// refuses points that disagree with the probes or a reach that is not positive; the reader refuses a
// truncated or missing points section, and points with a grid, naming the file.
TEST(LightProbes, ScatteredProbesRoundTripAndBrokenOnesAreRefused)
{
    hemi::io::LightmapAsset a = small_asset();
    a.probes = seeing_probes();
    a.probes.points = {glm::vec4(0.0f, 0.0f, 0.0f, 1.5f), glm::vec4(2.0f, 0.0f, 0.0f, 1.5f)};
    a.probes.depth.clear(); // visibility 1: the bumps alone
    a.probes.depth_resolution = 0;
    ASSERT_EQ(hemi::io::light_probes_problem(a.probes), "");
    const fs::path good = dir() / "scattered.hemi";
    hemi::io::write_lightmap_asset(good, a);
    const hemi::io::LightmapAsset b = hemi::io::read_lightmap_asset(good);
    ASSERT_TRUE(b.probes.scattered());
    EXPECT_EQ(b.probes.points, a.probes.points);
    EXPECT_EQ(b.probes.irradiance, a.probes.irradiance);
    EXPECT_EQ(b.probes.at(glm::vec3(0.0f))[0], glm::vec3(1.0f));
    EXPECT_EQ(b.probes.at(glm::vec3(2.0f, 0.0f, 0.0f))[0], glm::vec3(2.0f));
    EXPECT_FLOAT_EQ(b.probes.at(glm::vec3(1.0f, 0.3f, 0.0f))[0].x, 1.5f);
    // At 0.5 from the first and 1.5 from the second (out of its reach): the first alone.
    EXPECT_EQ(b.probes.at(glm::vec3(0.5f, 0.0f, 0.0f))[0], glm::vec3(1.0f));
    // At 0.9 and 1.1: (1 - 0.81/2.25)^8 = 0.64^8 = 0.028147 against (1 - 1.21/2.25)^8 = 0.0020836, worked
    // out here: 1.0692 (a square bump, (1 - x^2)^2, would give 1.343).
    const float w0 = 0.0281475f, w1 = 0.00208356f;
    EXPECT_NEAR(b.probes.at(glm::vec3(0.9f, 0.0f, 0.0f))[0].x, (w0 + 2.0f * w1) / (w0 + w1), 1e-5f);

    for (const auto& [edit, what] :
         {std::pair<std::function<void(hemi::io::LightProbes&)>, std::string>{
              [](hemi::io::LightProbes& p) { p.points.pop_back(); }, "1 scattered probes in a grid of 2x1x1"},
          {[](hemi::io::LightProbes& p) { p.points[1].w = 0.0f; }, "reach not a positive"},
          {[](hemi::io::LightProbes& p) { p.points[0].y = INFINITY; }, "position is not finite"},
          {[](hemi::io::LightProbes& p) { p.count = glm::uvec3(1, 2, 1); }, "expected 2x1x1"}})
    {
        hemi::io::LightmapAsset bad = a;
        edit(bad.probes);
        try
        {
            hemi::io::write_lightmap_asset(dir() / "never_scattered.hemi", bad);
            ADD_FAILURE() << "accepted: " << what;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    }
    auto read_refused = [&](const fs::path& from, const std::string& name, const std::string& what,
                            const std::function<void(const std::string&, std::vector<std::byte>&)>& edit)
    {
        const fs::path p = rewritten(from, name, edit);
        const std::string e = error_of(p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << e;
        EXPECT_NE(e.find(what), std::string::npos) << e;
    };
    read_refused(good, "points_short.hemi", "lightmap.probe_points has 31 bytes, 2 probes need 32",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     if (s == "lightmap.probe_points")
                         bytes.pop_back();
                 });
    read_refused(good, "points_reach.hemi", "reach not a positive",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     const float reach = -1.0f;
                     if (s == "lightmap.probe_points")
                         std::memcpy(bytes.data() + 12, &reach, 4);
                 });
    read_refused(good, "points_kind.hemi", "lightmap.probe_points with a grid of probes",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     const uint32_t grid = 0;
                     if (s == "lightmap.probes")
                         std::memcpy(bytes.data() + 12, &grid, 4);
                 });
    read_refused(good, "points_unknown_kind.hemi", "not supported",
                 [](const std::string& s, std::vector<std::byte>& bytes)
                 {
                     const uint32_t kind = 2;
                     if (s == "lightmap.probes")
                         std::memcpy(bytes.data() + 12, &kind, 4);
                 });
    // Without the points section.
    const hemi::io::AssetReader r(good);
    hemi::io::AssetWriter w;
    for (const std::string& section : r.names())
        if (section != "lightmap.probe_points")
        {
            const std::span<const std::byte> s = r.section(section);
            w.add(section, std::vector<std::byte>(s.begin(), s.end()));
        }
    w.write(dir() / "points_missing.hemi");
    const std::string e = error_of(dir() / "points_missing.hemi");
    EXPECT_NE(e.find("scattered probes without lightmap.probe_points"), std::string::npos) << e;
}
