// The baked PRT asset: a round trip keeps every value, and every broken file (truncated, corrupted, a missing
// or inconsistent section, an unknown technique, an out-of-range index or cluster, NaN) is a FormatError that
// names the file.
#include "../temp_dir.h"
#include "models.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/io/asset.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>

#include <gtest/gtest.h>


#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("prt_asset_test");
}

hemi::io::PrtAsset small_asset()
{
    hemi::bake::PrtAssetOptions o;
    o.bake.kind = hemi::bake::TransferKind::Shadowed;
    o.bake.rays = 16;
    o.bake.order = 3;
    o.techniques = {"gs", "hl2", "prt"};
    o.cpca_clusters = 2;
    o.cpca_vectors = 4;
    hemi::bake::PrtBakeSummary summary;
    hemi::io::PrtAsset a =
        hemi::bake::make_prt_asset(hemi::samples::make_prt_model(hemi::samples::PrtModel::Simple, 0.5f), o, summary);
    a.normal_texture = "textures/normal.png";
    return a;
}

// Copies `from` section by section into a new file, letting `edit` change, drop (return false) or add.
fs::path rewrite(const fs::path& from, const std::string& name,
                 const std::function<bool(const std::string&, std::vector<std::byte>&)>& edit,
                 const std::vector<std::pair<std::string, std::vector<std::byte>>>& extra = {})
{
    const hemi::io::AssetReader r(from);
    hemi::io::AssetWriter w;
    for (const std::string& s : r.names())
    {
        std::vector<std::byte> bytes(r.section(s).begin(), r.section(s).end());
        if (edit(s, bytes))
            w.add(s, bytes);
    }
    for (const auto& [s, bytes] : extra)
        w.add(s, bytes);
    const fs::path p = dir() / name;
    w.write(p);
    return p;
}

void expect_error(const fs::path& p, const std::string& part)
{
    try
    {
        hemi::io::read_prt_asset(p);
        ADD_FAILURE() << p << " was accepted; expected an error about '" << part << "'";
    }
    catch (const hemi::io::FormatError& e)
    {
        const std::string what = e.what();
        EXPECT_NE(what.find(p.string()), std::string::npos) << what;
        EXPECT_NE(what.find(part), std::string::npos) << what;
    }
}

} // namespace

TEST(PrtAsset, RoundTripKeepsEveryValue)
{
    const hemi::io::PrtAsset a = small_asset();
    const fs::path p = dir() / "round.hemi";
    hemi::io::write_prt_asset(p, a);
    const hemi::io::PrtAsset b = hemi::io::read_prt_asset(p);
    EXPECT_EQ(b.order, 3u);
    EXPECT_EQ(b.transfer_kind, uint32_t(hemi::bake::TransferKind::Shadowed));
    EXPECT_EQ(b.rays, 16u);
    EXPECT_EQ(b.normal_texture, "textures/normal.png");
    EXPECT_EQ(b.base_color_texture, "");
    ASSERT_EQ(b.mesh.vertex_count(), a.mesh.vertex_count());
    EXPECT_EQ(0, std::memcmp(b.mesh.tangents.data(), a.mesh.tangents.data(), a.mesh.tangents.size() * 16));
    EXPECT_EQ(b.mesh.indices, a.mesh.indices);
    EXPECT_EQ(0, std::memcmp(b.mesh.positions.data(), a.mesh.positions.data(), a.mesh.positions.size() * 12));
    EXPECT_EQ(0, std::memcmp(b.mesh.normals.data(), a.mesh.normals.data(), a.mesh.normals.size() * 12));
    EXPECT_EQ(0, std::memcmp(b.mesh.uvs.data(), a.mesh.uvs.data(), a.mesh.uvs.size() * 8));
    EXPECT_EQ(b.seed, a.seed);
    EXPECT_EQ(b.albedo, a.albedo);
    EXPECT_EQ(b.bounces, a.bounces);
    ASSERT_EQ(b.techniques.size(), 3u);
    for (const hemi::io::PrtTechnique& t : a.techniques)
    {
        const hemi::io::PrtTechnique& u = b.technique(t.name);
        EXPECT_EQ(u.k, t.k);
        EXPECT_EQ(u.matrices, t.matrices) << t.name;
        ASSERT_TRUE(u.cpca.has_value());
        EXPECT_EQ(u.cpca->cluster, t.cpca->cluster);
        EXPECT_EQ(u.cpca->weights, t.cpca->weights);
        EXPECT_EQ(u.cpca->basis, t.cpca->basis);
        EXPECT_EQ(u.cpca->means, t.cpca->means);
        EXPECT_EQ(u.cpca->rms_error, t.cpca->rms_error);
    }
    EXPECT_THROW(b.technique("sep4"), std::invalid_argument);
    EXPECT_EQ(hemi::io::resolve_texture(p, b.normal_texture), dir() / "textures/normal.png");
}

TEST(PrtAsset, TruncatedOrCorruptedFilesAreRefused)
{
    const fs::path good = dir() / "good.hemi";
    hemi::io::write_prt_asset(good, small_asset());
    std::ifstream in(good, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (size_t keep : {size_t(0), size_t(7), size_t(100), bytes.size() / 2, bytes.size() - 1})
    {
        const fs::path p = dir() / ("cut" + std::to_string(keep) + ".hemi");
        std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(keep));
        EXPECT_THROW(hemi::io::read_prt_asset(p), hemi::io::FormatError) << keep;
    }
    std::vector<char> flipped = bytes;
    flipped[bytes.size() / 3] ^= 0x10;
    const fs::path p = dir() / "flipped.hemi";
    std::ofstream(p, std::ios::binary).write(flipped.data(), std::streamsize(flipped.size()));
    expect_error(p, "checksum");
    expect_error(dir() / "missing.hemi", "no such file");
}

// Files whose container is intact (a valid checksum) but whose contents are not a valid PRT asset.
TEST(PrtAsset, InconsistentContentsAreRefusedWithTheReason)
{
    const fs::path good = dir() / "base.hemi";
    hemi::io::write_prt_asset(good, small_asset());
    auto keep = [](const std::string&, std::vector<std::byte>&) { return true; };

    expect_error(rewrite(good, "no_uvs.hemi", [](const std::string& s, auto&) { return s != "mesh.uvs"; }),
                 "mesh.uvs");
    expect_error(rewrite(good, "short_t.hemi",
                         [](const std::string& s, std::vector<std::byte>& b) {
                             if (s == "T.gs")
                                 b.resize(b.size() - 4);
                             return true;
                         }),
                 "technique 'gs'");
    expect_error(rewrite(good, "nan.hemi",
                         [](const std::string& s, std::vector<std::byte>& b) {
                             if (s == "T.hl2")
                             {
                                 const float nan = NAN;
                                 std::memcpy(b.data() + 40, &nan, 4);
                             }
                             return true;
                         }),
                 "non-finite");
    expect_error(rewrite(good, "index.hemi",
                         [](const std::string& s, std::vector<std::byte>& b) {
                             if (s == "mesh.indices")
                             {
                                 const uint32_t big = 1u << 30;
                                 std::memcpy(b.data() + 8, &big, 4);
                             }
                             return true;
                         }),
                 "out of range");
    expect_error(rewrite(good, "cluster.hemi",
                         [](const std::string& s, std::vector<std::byte>& b) {
                             if (s == "C.prt")
                             {
                                 // Cluster ids follow the 12-byte header, the means and the vectors.
                                 const size_t d = 9, header = 12, means = 2 * d * 4, vectors = 2 * 4 * d * 4;
                                 const uint32_t bad = 7;
                                 std::memcpy(b.data() + header + means + vectors, &bad, 4);
                             }
                             return true;
                         }),
                 "cluster 7 out of range");
    expect_error(rewrite(good, "unknown.hemi", keep, {{"T.phong", std::vector<std::byte>(16)}}),
                 "unknown technique 'phong'");
    expect_error(rewrite(good, "version.hemi",
                         [](const std::string& s, std::vector<std::byte>& b) {
                             if (s == "prt.info")
                                 b[0] = std::byte{9};
                             return true;
                         }),
                 "layout version 9");
    // An absurd lighting order would make every size computed from it overflow: refused before any is.
    expect_error(rewrite(good, "order.hemi",
                         [](const std::string& s, std::vector<std::byte>& b) {
                             if (s == "prt.info")
                             {
                                 const uint32_t order = 1u << 31;
                                 std::memcpy(b.data() + 8, &order, 4);
                             }
                             return true;
                         }),
                 "lighting order 2147483648");
}

TEST(PrtAsset, WriterRefusesInconsistentAssets)
{
    hemi::io::PrtAsset a = small_asset();
    a.techniques[0].matrices[3] = INFINITY;
    EXPECT_THROW(hemi::io::write_prt_asset(dir() / "never.hemi", a), std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir() / "never.hemi"));
}
