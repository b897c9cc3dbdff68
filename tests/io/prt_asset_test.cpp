// The baked PRT asset: a round trip keeps every value (surfaces and their images included), an asset copied
// away from its source scene still has its images, and every broken file (truncated, corrupted, a missing or
// inconsistent section, a malformed material section, an unknown technique, an out-of-range index or cluster,
// NaN, an older layout) is a FormatError that names the file.
#include "../temp_dir.h"
#include "models.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/io/asset.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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
    hemi::io::PrtAsset a = hemi::bake::make_prt_asset(
        hemi::samples::make_prt_model(hemi::samples::PrtModel::Simple, 0.5f), o, summary);
    // Two materials over two primitives, a PNG and a JPEG, and a second UV set.
    using namespace hemi::io;
    ImageRgba8 small{3, 2, std::vector<uint8_t>(24)};
    for (size_t i = 0; i < small.pixels.size(); ++i)
        small.pixels[i] = uint8_t(i * 10);
    a.images = {{"textures/base.png", "image/png", encode_png(small)},
                {"scene.glb image 1", "image/jpeg", encode_jpeg(small, 90)}};
    Material brick;
    brick.name = "brick";
    brick.base_color_factor = {0.9f, 0.8f, 0.7f, 1.0f};
    brick.base_color.image = 0;
    brick.base_color.sampler = {Filter::Nearest, Filter::Linear, false, Wrap::MirroredRepeat,
                                Wrap::ClampToEdge};
    brick.normal.image = 1;
    brick.normal.texcoord = 1;
    brick.normal.offset = {0.5f, -0.25f};
    brick.normal.scale = {2.0f, 0.5f};
    brick.normal.rotation = 1.25f;
    brick.normal_scale = 0.75f;
    brick.occlusion.image = 0; // glTF's occlusion texture (its red channel), with its own UV set and strength
    brick.occlusion.texcoord = 1;
    brick.occlusion_strength = 0.6f;
    Material glow;
    glow.name = "glow \"quoted\" \u00e9";
    glow.emissive_factor = {1.0f, 0.5f, 0.25f};
    glow.emissive.image = 0;
    glow.double_sided = true;
    a.materials = {brick, glow};
    const uint32_t half = uint32_t(a.mesh.indices.size() / 6 * 3);
    a.primitives = {{0, half, 1}, {half, uint32_t(a.mesh.indices.size()) - half, 0}};
    a.mesh.uvs1.resize(a.mesh.vertex_count());
    for (size_t v = 0; v < a.mesh.uvs1.size(); ++v)
        a.mesh.uvs1[v] = glm::vec2(float(v) / 7.0f, 1.0f - float(v) / 3.0f);
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
    EXPECT_EQ(b.materials, a.materials);
    EXPECT_EQ(b.images, a.images);
    EXPECT_EQ(b.primitives, a.primitives);
    ASSERT_EQ(b.mesh.uvs1.size(), a.mesh.uvs1.size());
    EXPECT_EQ(0, std::memcmp(b.mesh.uvs1.data(), a.mesh.uvs1.data(), a.mesh.uvs1.size() * 8));
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

    // Without a second UV set and with the baker's default surfaces (one material, no images).
    hemi::io::PrtAsset plain = a;
    plain.mesh.uvs1.clear();
    plain.materials = {hemi::io::Material{"default"}};
    plain.images.clear();
    plain.primitives = {{0, uint32_t(a.mesh.indices.size()), 0}};
    hemi::io::write_prt_asset(dir() / "plain.hemi", plain);
    const hemi::io::PrtAsset c = hemi::io::read_prt_asset(dir() / "plain.hemi");
    EXPECT_TRUE(c.mesh.uvs1.empty());
    EXPECT_EQ(c.materials, plain.materials);
    EXPECT_TRUE(c.images.empty());
    EXPECT_EQ(c.primitives, plain.primitives);
    EXPECT_FALSE(hemi::io::AssetReader(dir() / "plain.hemi").has("mesh.uvs1"));
}

// The asset is self-contained: baked from a glTF with external textures, copied to another folder, and the
// scene and its textures deleted, it still has its materials and its images decode to the textures' pixels.
TEST(PrtAsset, CopiedAssetKeepsItsImages)
{
    const fs::path scene_dir = dir() / "scene";
    const fs::path gltf =
        hemi::samples::write_prt_model(scene_dir, "moved", hemi::samples::PrtModel::Simple, 0.3f);
    hemi::bake::PrtAssetOptions o;
    o.bake.kind = hemi::bake::TransferKind::Unshadowed;
    o.techniques = {"prt"};
    const fs::path baked = scene_dir / "moved.hemi";
    const hemi::bake::PrtBakeSummary summary = hemi::bake::bake_prt_file(gltf, baked, o);
    EXPECT_EQ(summary.materials, 1u);
    EXPECT_EQ(summary.primitives, 1u);
    EXPECT_EQ(summary.images, 2u);
    const fs::path elsewhere = dir() / "elsewhere" / "deeper";
    fs::create_directories(elsewhere);
    fs::copy_file(baked, elsewhere / "copy.hemi", fs::copy_options::overwrite_existing);
    fs::remove_all(scene_dir);

    const hemi::io::PrtAsset a = hemi::io::read_prt_asset(elsewhere / "copy.hemi");
    ASSERT_EQ(a.materials.size(), 1u);
    ASSERT_EQ(a.images.size(), 2u);
    ASSERT_EQ(a.primitives.size(), 1u);
    EXPECT_EQ(a.primitives[0], (hemi::io::Primitive{0, uint32_t(a.mesh.indices.size()), 0}));
    const hemi::io::Material& m = a.materials[0];
    ASSERT_TRUE(m.base_color.present());
    ASSERT_TRUE(m.normal.present());
    EXPECT_EQ(a.images[size_t(m.base_color.image)].name, "moved_base_color.png");
    EXPECT_EQ(hemi::io::decode_image(a.images[size_t(m.base_color.image)]).pixels,
              hemi::samples::brick_base_color(512, 256).pixels);
    EXPECT_EQ(hemi::io::decode_image(a.images[size_t(m.normal.image)]).pixels,
              hemi::samples::brick_normal_map(512, 256).pixels);
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
    expect_error(rewrite(good, "short_uvs1.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "mesh.uvs1")
                                 b.resize(b.size() - 8);
                             return true;
                         }),
                 "TEXCOORD_1");
    expect_error(rewrite(good, "short_t.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "T.gs")
                                 b.resize(b.size() - 4);
                             return true;
                         }),
                 "technique 'gs'");
    expect_error(rewrite(good, "nan.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "T.hl2")
                             {
                                 const float nan = NAN;
                                 std::memcpy(b.data() + 40, &nan, 4);
                             }
                             return true;
                         }),
                 "non-finite");
    expect_error(rewrite(good, "index.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "mesh.indices")
                             {
                                 const uint32_t big = 1u << 30;
                                 std::memcpy(b.data() + 8, &big, 4);
                             }
                             return true;
                         }),
                 "out of range");
    expect_error(rewrite(good, "cluster.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
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
    // NaN in each stored array of a CPCA section (the rms error, the means, the PCA vectors, the weights),
    // under a valid container checksum: refused, naming the file, the technique and the problem.
    {
        const size_t d = 9, header = 12, means = 2 * d * 4;
        const std::pair<const char*, size_t> places[] = {
            {"rms", 8}, {"means", header + 4}, {"vectors", header + means + 8}, {"weights", size_t(-4)}};
        for (const auto& [what, offset] : places)
            expect_error(rewrite(good, std::string("cpca_nan_") + what + ".hemi",
                                 [offset](const std::string& s, std::vector<std::byte>& b)
                                 {
                                     if (s == "C.prt")
                                     {
                                         // The weights are the section's last N x V floats.
                                         const size_t at = offset == size_t(-4) ? b.size() - 4 : offset;
                                         const float nan = NAN;
                                         std::memcpy(b.data() + at, &nan, 4);
                                     }
                                     return true;
                                 }),
                         "technique 'prt': non-finite CPCA value");
    }
    expect_error(rewrite(good, "unknown.hemi", keep, {{"T.phong", std::vector<std::byte>(16)}}),
                 "unknown technique 'phong'");
    expect_error(rewrite(good, "version.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "prt.info")
                                 b[0] = std::byte{9};
                             return true;
                         }),
                 "layout version 9");
    expect_error(rewrite(good, "layout1.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "prt.info")
                                 b[0] = std::byte{1};
                             return true;
                         }),
                 "written by an older hemi (PRT layout 1");
    // An absurd lighting order would make every size computed from it overflow: refused before any is.
    expect_error(rewrite(good, "order.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "prt.info")
                             {
                                 const uint32_t order = 1u << 31;
                                 std::memcpy(b.data() + 8, &order, 4);
                             }
                             return true;
                         }),
                 "lighting order 2147483648");
}

// The surfaces' sections with a valid container checksum but wrong contents: cut, not JSON, a field missing
// or of the wrong type, an image or material out of range, a UV set other than 0 and 1, primitives that do
// not cover the mesh, an image whose bytes are missing, of another size or another type. Each names the file
// and the problem.
TEST(PrtAsset, BrokenSurfaceSectionsAreRefusedWithTheReason)
{
    using nlohmann::json;
    const fs::path good = dir() / "surfaces.hemi";
    hemi::io::write_prt_asset(good, small_asset());
    auto text_of = [](const std::vector<std::byte>& b)
    { return std::string(reinterpret_cast<const char*>(b.data()), b.size()); };
    auto set_text = [](std::vector<std::byte>& b, const std::string& t)
    {
        b.resize(t.size());
        std::memcpy(b.data(), t.data(), t.size());
    };
    // Rewrites scene.materials through `edit` on its JSON.
    auto materials = [&](const std::string& name, const std::function<void(json&)>& edit)
    {
        return rewrite(good, name,
                       [&](const std::string& s, std::vector<std::byte>& b)
                       {
                           if (s == "scene.materials")
                           {
                               json j = json::parse(text_of(b));
                               edit(j);
                               set_text(b, j.dump());
                           }
                           return true;
                       });
    };
    expect_error(rewrite(good, "cut_materials.hemi",
                         [&](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "scene.materials")
                                 b.resize(b.size() / 2);
                             return true;
                         }),
                 "scene.materials is not valid JSON");
    expect_error(rewrite(good, "no_materials.hemi",
                         [](const std::string& s, auto&) { return s != "scene.materials"; }),
                 "section 'scene.materials' is missing");
    expect_error(materials("no_factor.hemi", [](json& j) { j["materials"][0].erase("base_color_factor"); }),
                 "scene.materials: material 0: no 'base_color_factor'");
    expect_error(materials("string_factor.hemi", [](json& j) { j["materials"][1]["normal_scale"] = "big"; }),
                 "material 1: 'normal_scale' is not a number");
    expect_error(
        materials("null_factor.hemi", [](json& j) { j["materials"][0]["base_color_factor"][2] = nullptr; }),
        "'base_color_factor' holds a value that is not a finite number");
    expect_error(
        materials("negative_image.hemi", [](json& j) { j["materials"][0]["base_color"]["image"] = -3; }),
        "'image' = -3 is not in [0,");
    expect_error(materials("far_image.hemi", [](json& j) { j["materials"][1]["emissive"]["image"] = 5; }),
                 "refers to image 5, but there are 2");
    expect_error(materials("texcoord2.hemi", [](json& j) { j["materials"][0]["normal"]["texcoord"] = 2; }),
                 "'texcoord' = 2 is not in [0, 1]");
    expect_error(materials("wrap.hemi",
                           [](json& j) { j["materials"][0]["base_color"]["sampler"]["wrap_s"] = "tile"; }),
                 "'wrap_s' = 'tile' is not a known value");
    expect_error(materials("mime.hemi", [](json& j) { j["images"][0]["mime_type"] = "image/webp"; }),
                 "mime type 'image/webp' is neither image/png nor image/jpeg");
    expect_error(materials("swapped_mime.hemi", [](json& j) { j["images"][0]["mime_type"] = "image/jpeg"; }),
                 "the bytes are not image/jpeg");
    expect_error(materials("image_size.hemi", [](json& j) { j["images"][1]["bytes"] = 3; }), "image.1 holds");
    expect_error(materials("one_image.hemi", [](json& j) { j["images"].erase(1); }),
                 "section 'image.1' is not one of the 1 images");
    expect_error(materials("no_images_key.hemi", [](json& j) { j.erase("images"); }), "no 'images'");
    expect_error(rewrite(good, "no_image.hemi", [](const std::string& s, auto&) { return s != "image.0"; }),
                 "section 'image.0' is missing");
    expect_error(
        rewrite(good, "uvs1_gone.hemi", [](const std::string& s, auto&) { return s != "mesh.uvs1"; }),
        "reads TEXCOORD_1, which the mesh does not have");
    auto primitives = [&](const std::string& name, const std::function<void(std::vector<uint32_t>&)>& edit)
    {
        return rewrite(good, name,
                       [&](const std::string& s, std::vector<std::byte>& b)
                       {
                           if (s == "scene.primitives")
                           {
                               std::vector<uint32_t> p(b.size() / 4);
                               std::memcpy(p.data(), b.data(), b.size());
                               edit(p);
                               b.resize(p.size() * 4);
                               std::memcpy(b.data(), p.data(), b.size());
                           }
                           return true;
                       });
    };
    expect_error(primitives("prim_pairs.hemi", [](std::vector<uint32_t>& p) { p.pop_back(); }),
                 "not (first, count, material) triples");
    expect_error(primitives("prim_material.hemi", [](std::vector<uint32_t>& p) { p[2] = 9; }),
                 "primitive 0: material 9 out of range (2 materials)");
    expect_error(primitives("prim_gap.hemi", [](std::vector<uint32_t>& p) { p[3] += 3, p[4] -= 3; }),
                 "primitive 1: starts at index");
    expect_error(primitives("prim_short.hemi", [](std::vector<uint32_t>& p) { p[4] -= 3; }),
                 "the primitives cover");
    expect_error(primitives("prim_long.hemi", [](std::vector<uint32_t>& p) { p[4] += 3; }),
                 "past the mesh's");
    expect_error(primitives("prim_none.hemi", [](std::vector<uint32_t>& p) { p.clear(); }), "no primitives");
    // 2^32 - 1 is a multiple of 3: the end of the range is summed in 64 bits, not wrapped around.
    expect_error(primitives("prim_huge.hemi", [](std::vector<uint32_t>& p) { p[1] = 0xFFFFFFFFu; }),
                 "ends at index 4294967295, past the mesh's");
    expect_error(
        primitives("prim_odd.hemi", [](std::vector<uint32_t>& p) { p[1] -= 1, p[3] -= 1, p[4] += 1; }),
        "not a positive multiple of 3");
    // An image that is an image by its signature but corrupt inside is the renderer's to refuse (it decodes);
    // the asset reader checks signatures only. Bytes that are no PNG at all are refused here.
    expect_error(rewrite(good, "not_png.hemi",
                         [](const std::string& s, std::vector<std::byte>& b)
                         {
                             if (s == "image.0")
                                 b[1] = std::byte{'X'};
                             return true;
                         }),
                 "the bytes are not image/png");
}

TEST(PrtAsset, WriterRefusesInconsistentAssets)
{
    hemi::io::PrtAsset a = small_asset();
    a.techniques[0].matrices[3] = INFINITY;
    EXPECT_THROW(hemi::io::write_prt_asset(dir() / "never.hemi", a), std::invalid_argument);
    a = small_asset();
    a.primitives[1].index_count -= 3;
    EXPECT_THROW(hemi::io::write_prt_asset(dir() / "never.hemi", a), std::invalid_argument);
    a = small_asset();
    a.materials[0].base_color.image = 2;
    EXPECT_THROW(hemi::io::write_prt_asset(dir() / "never.hemi", a), std::invalid_argument);
    a = small_asset();
    a.primitives.clear();
    EXPECT_THROW(hemi::io::write_prt_asset(dir() / "never.hemi", a), std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir() / "never.hemi"));
}
