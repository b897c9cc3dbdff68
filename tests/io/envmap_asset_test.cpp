// The environment asset (io/envmap_asset.h): it round-trips exactly, and every refusal of read_envmap_asset
// (a missing, truncated or corrupted file, another kind of asset, a section of the wrong size, sizes,
// counts, extents, exponents and indices of refraction out of range, non-finite values) names the file and
// the problem. The broken files are written through io::AssetWriter with the documented sections, so the
// container is sound and the envmap reader's own checks are what refuses them; the first test shows that
// these sections are exactly what write_envmap_asset writes.
#include "../temp_dir.h"

#include <hemi/io/asset.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("envmap_asset_test");
}

hemi::math::ParabolicImage map(uint32_t size, double extent, float seed)
{
    hemi::math::ParabolicImage m;
    m.size = size;
    m.extent = extent;
    m.rgb.resize(size_t(2) * size * size * 3);
    for (size_t i = 0; i < m.rgb.size(); ++i)
        m.rgb[i] = seed + 0.01f * float(i);
    return m;
}

// Level 0 of 4 x 4 (levels 4, 2, 1), glossy maps at exponents 8 (4 x 4) and 30 (2 x 2), a 2 x 2 diffuse map,
// Fresnel tables at 1.5 and 2.4 of 3 samples; every value differs.
hemi::io::EnvmapAsset small_asset()
{
    hemi::io::EnvmapAsset a;
    a.source_width = 64;
    a.source_height = 32;
    a.mirror = {map(4, 2.0, 1.0f), map(2, 2.0, 2.0f), map(1, 2.0, 3.0f)};
    a.exponents = {8.0f, 30.0f};
    a.glossy = {map(4, 2.0, 4.0f), map(2, 1.0, 5.0f)};
    a.diffuse = map(2, 1.0, 6.0f);
    a.iors = {1.5f, 2.4f};
    a.fresnel_samples = 3;
    a.fresnel = {1.0f, 0.5f, 0.04f, 1.0f, 0.6f, 0.17f};
    return a;
}

template <typename T> void put(std::vector<std::byte>& out, const T& v)
{
    const auto* b = reinterpret_cast<const std::byte*>(&v);
    out.insert(out.end(), b, b + sizeof(T));
}
void put_floats(std::vector<std::byte>& out, const std::vector<float>& v)
{
    for (float f : v)
        put(out, f);
}

// The sections of `a` as io/envmap_asset.h documents them.
std::map<std::string, std::vector<std::byte>> sections(const hemi::io::EnvmapAsset& a)
{
    std::map<std::string, std::vector<std::byte>> s;
    std::vector<std::byte>& info = s["envmap.info"];
    for (uint32_t v : {1u, a.mirror[0].size, uint32_t(a.mirror.size()), uint32_t(a.glossy.size()),
                       uint32_t(a.iors.size()), a.fresnel_samples, a.source_width, a.source_height})
        put(info, v);
    put(info, float(a.mirror[0].extent));
    for (const hemi::math::ParabolicImage& m : a.mirror)
        put_floats(s["envmap.mirror"], m.rgb);
    std::vector<std::byte>& glossy = s["envmap.glossy"];
    for (size_t i = 0; i < a.glossy.size(); ++i)
    {
        put(glossy, a.exponents[i]);
        put(glossy, a.glossy[i].size);
        put(glossy, float(a.glossy[i].extent));
        put_floats(glossy, a.glossy[i].rgb);
    }
    std::vector<std::byte>& diffuse = s["envmap.diffuse"];
    put(diffuse, a.diffuse.size);
    put(diffuse, float(a.diffuse.extent));
    put_floats(diffuse, a.diffuse.rgb);
    std::vector<std::byte>& fresnel = s["envmap.fresnel"];
    for (size_t i = 0; i < a.iors.size(); ++i)
    {
        put(fresnel, a.iors[i]);
        put_floats(fresnel, std::vector<float>(a.fresnel.begin() + long(i * a.fresnel_samples),
                                               a.fresnel.begin() + long((i + 1) * a.fresnel_samples)));
    }
    return s;
}

// In the writer's order.
void write_sections(const fs::path& p, const std::map<std::string, std::vector<std::byte>>& s)
{
    hemi::io::AssetWriter w;
    for (const char* name :
         {"envmap.info", "envmap.mirror", "envmap.glossy", "envmap.diffuse", "envmap.fresnel"})
        if (s.count(name))
            w.add(name, s.at(name));
    w.write(p);
}

std::string error_of(const fs::path& p)
{
    try
    {
        hemi::io::read_envmap_asset(p);
    }
    catch (const hemi::io::FormatError& e)
    {
        return e.what();
    }
    return "(read)";
}

// Byte `at` of a section as a float or u32 (the sections are little-endian, like the machines hemi runs on).
template <typename T> void set(std::vector<std::byte>& section, size_t at, T v)
{
    std::memcpy(section.data() + at, &v, sizeof v);
}

std::vector<char> read_bytes(const fs::path& p)
{
    std::ifstream in(p, std::ios::binary);
    return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

} // namespace

TEST(EnvmapAsset, RoundTripsExactlyAndIsWhatTheSectionsSay)
{
    const hemi::io::EnvmapAsset a = small_asset();
    ASSERT_EQ(hemi::io::envmap_problem(a), "");
    const fs::path p = dir() / "round.hemi";
    hemi::io::write_envmap_asset(p, a);
    const hemi::io::EnvmapAsset b = hemi::io::read_envmap_asset(p);
    EXPECT_EQ(b.source_width, 64u);
    EXPECT_EQ(b.source_height, 32u);
    ASSERT_EQ(b.mirror.size(), 3u);
    for (size_t l = 0; l < 3; ++l)
    {
        EXPECT_EQ(b.mirror[l].size, a.mirror[l].size);
        EXPECT_EQ(b.mirror[l].extent, 2.0);
        EXPECT_EQ(b.mirror[l].rgb, a.mirror[l].rgb) << "level " << l;
    }
    EXPECT_EQ(b.exponents, a.exponents);
    ASSERT_EQ(b.glossy.size(), 2u);
    for (size_t i = 0; i < 2; ++i)
    {
        EXPECT_EQ(b.glossy[i].size, a.glossy[i].size);
        EXPECT_EQ(b.glossy[i].extent, a.glossy[i].extent);
        EXPECT_EQ(b.glossy[i].rgb, a.glossy[i].rgb);
    }
    EXPECT_EQ(b.diffuse.size, 2u);
    EXPECT_EQ(b.diffuse.rgb, a.diffuse.rgb);
    EXPECT_EQ(b.iors, a.iors);
    EXPECT_EQ(b.fresnel_samples, 3u);
    EXPECT_EQ(b.fresnel, a.fresnel);
    EXPECT_EQ(hemi::io::envmap_problem(b), "");

    // The sections the refusal tests below build on are the writer's, byte for byte.
    const hemi::io::AssetReader r(p);
    const auto expected = sections(a);
    std::vector<std::string> names;
    for (const auto& entry : expected)
        names.push_back(entry.first);
    EXPECT_EQ(r.names(), names);
    for (const auto& [name, bytes] : expected)
    {
        const std::span<const std::byte> got = r.section(name);
        EXPECT_TRUE(std::equal(got.begin(), got.end(), bytes.begin(), bytes.end())) << name;
    }
    const fs::path rebuilt = dir() / "rebuilt.hemi";
    write_sections(rebuilt, expected);
    EXPECT_EQ(read_bytes(rebuilt), read_bytes(p));
}

TEST(EnvmapAsset, MissingTruncatedCorruptedAndOtherFilesAreRefusedNamingThem)
{
    auto expect = [](const fs::path& p, const std::string& what)
    {
        const std::string e = error_of(p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << e;
        EXPECT_NE(e.find(what), std::string::npos) << "want '" << what << "': " << e;
    };
    expect(dir() / "does_not_exist.hemi", "no such file");

    const fs::path good = dir() / "good.hemi";
    hemi::io::write_envmap_asset(good, small_asset());
    const std::vector<char> bytes = read_bytes(good);
    for (size_t keep : {size_t(0), size_t(5), size_t(20), bytes.size() / 2, bytes.size() - 1})
    {
        const fs::path p = dir() / ("cut" + std::to_string(keep) + ".hemi");
        std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(keep));
        expect(p, keep < 8 ? "not a hemi asset" : keep < 24 ? "truncated" : "checksum mismatch");
    }
    std::vector<char> flipped = bytes;
    flipped[bytes.size() / 2] ^= 0x04; // inside envmap.mirror's values
    const fs::path corrupted = dir() / "corrupted.hemi";
    std::ofstream(corrupted, std::ios::binary).write(flipped.data(), std::streamsize(flipped.size()));
    expect(corrupted, "checksum mismatch");

    // A PRT asset where an environment asset is expected.
    hemi::io::PrtAsset prt;
    prt.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    prt.mesh.normals.assign(3, glm::vec3(0, 0, 1));
    prt.mesh.tangents.assign(3, glm::vec4(1, 0, 0, 1));
    prt.mesh.uvs = {{0, 0}, {1, 0}, {0, 1}};
    prt.mesh.indices = {0, 1, 2};
    prt.materials.emplace_back();
    prt.primitives = {{0, 3, 0}};
    prt.order = 3;
    hemi::io::PrtTechnique t;
    t.name = "gs";
    t.k = 9;
    t.matrices.assign(3 * 9 * 9, 0.25f);
    prt.techniques.push_back(t);
    const fs::path prt_path = dir() / "prt.hemi";
    hemi::io::write_prt_asset(prt_path, prt);
    expect(prt_path, "not an environment asset (no envmap.info)");
    // Nor is an environment asset a PRT asset.
    EXPECT_THROW(hemi::io::read_prt_asset(good), hemi::io::FormatError);
}

// Every check of the reader, each made to fail by one change to the sections of small_asset(). A reader
// without the check would return an asset envmap_problem() refuses, read past a section, allocate what a
// count claims (a mirror map of 8192^2 is 1.6 GB) or hand NaN to the renderer.
TEST(EnvmapAsset, EveryInconsistencyIsRefusedNamingTheFileAndTheProblem)
{
    using Sections = std::map<std::string, std::vector<std::byte>>;
    const Sections good = sections(small_asset());
    const size_t info_size = 4, info_levels = 8, info_glossy = 12, info_tables = 16, info_samples = 20,
                 info_extent = 32;
    const size_t glossy1 = 12 + 4 * 4 * 2 * 3 * 4; // the second glossy map's exponent
    const struct
    {
        const char* name;
        std::function<void(Sections&)> change;
        std::string what;
    } cases[] = {
        {"info_short", [](Sections& s) { s["envmap.info"].pop_back(); }, "envmap.info is too short"},
        {"info_long", [](Sections& s) { s["envmap.info"].push_back(std::byte(0)); },
         "envmap.info has 1 bytes too many"},
        {"layout", [](Sections& s) { set(s["envmap.info"], 0, uint32_t(2)); },
         "envmap layout version 2 is not supported"},
        {"size_3", [&](Sections& s) { set(s["envmap.info"], info_size, uint32_t(3)); },
         "envmap.info: size 3 is not a power of two in [1, 8192]"},
        {"size_0", [&](Sections& s) { set(s["envmap.info"], info_size, uint32_t(0)); },
         "envmap.info: size 0 is not a power of two"},
        {"size_16384", [&](Sections& s) { set(s["envmap.info"], info_size, uint32_t(16384)); },
         "envmap.info: size 16384 is not a power of two in [1, 8192]"},
        {"levels", [&](Sections& s) { set(s["envmap.info"], info_levels, uint32_t(2)); },
         "envmap.info: 2 mirror levels for size 4, expected 3"},
        {"extent_small", [&](Sections& s) { set(s["envmap.info"], info_extent, 0.5f); },
         "envmap.info: extent 0.500000 is not in [1, 4]"},
        {"extent_nan", [&](Sections& s) { set(s["envmap.info"], info_extent, NAN); }, "envmap.info: extent"},
        {"65_glossy", [&](Sections& s) { set(s["envmap.info"], info_glossy, uint32_t(65)); },
         "envmap.info: implausible counts"},
        {"65_tables", [&](Sections& s) { set(s["envmap.info"], info_tables, uint32_t(65)); },
         "envmap.info: implausible counts"},
        {"65537_samples", [&](Sections& s) { set(s["envmap.info"], info_samples, uint32_t(65537)); },
         "envmap.info: implausible counts"},
        {"1_sample", [&](Sections& s) { set(s["envmap.info"], info_samples, uint32_t(1)); },
         "envmap.info: implausible counts"},
        // 8192^2 claimed, 4^2 there: refused before any allocation of the claim.
        {"mirror_8192",
         [&](Sections& s)
         {
             set(s["envmap.info"], info_size, uint32_t(8192));
             set(s["envmap.info"], info_levels, uint32_t(14));
         },
         "envmap.mirror is too short"},
        {"mirror_missing", [](Sections& s) { s.erase("envmap.mirror"); },
         "section 'envmap.mirror' is missing"},
        {"mirror_short", [](Sections& s) { s["envmap.mirror"].resize(s["envmap.mirror"].size() - 4); },
         "envmap.mirror is too short"},
        {"mirror_long", [](Sections& s) { s["envmap.mirror"].resize(s["envmap.mirror"].size() + 4); },
         "envmap.mirror has 4 bytes too many"},
        {"mirror_nan", [](Sections& s) { set(s["envmap.mirror"], 40, NAN); },
         "envmap.mirror holds a value that is not finite"},
        {"mirror_inf", [](Sections& s) { set(s["envmap.mirror"], 0, INFINITY); },
         "envmap.mirror holds a value that is not finite"},
        {"glossy_exponent_0", [](Sections& s) { set(s["envmap.glossy"], 0, 0.0f); },
         "envmap.glossy: exponent 0.000000 is not > 0"},
        {"glossy_exponent_nan", [&](Sections& s) { set(s["envmap.glossy"], glossy1, NAN); },
         "envmap.glossy: exponent"},
        {"glossy_size", [](Sections& s) { set(s["envmap.glossy"], 4, uint32_t(6)); },
         "envmap.glossy: size 6 is not a power of two"},
        {"glossy_extent", [](Sections& s) { set(s["envmap.glossy"], 8, 4.5f); },
         "envmap.glossy: extent 4.500000 is not in [1, 4]"},
        {"glossy_short", [](Sections& s) { s["envmap.glossy"].resize(s["envmap.glossy"].size() - 1); },
         "envmap.glossy is too short"},
        {"glossy_long", [](Sections& s) { s["envmap.glossy"].resize(s["envmap.glossy"].size() + 8); },
         "envmap.glossy has 8 bytes too many"},
        {"glossy_nan", [&](Sections& s) { set(s["envmap.glossy"], glossy1 + 12, NAN); },
         "envmap.glossy holds a value that is not finite"},
        {"diffuse_size", [](Sections& s) { set(s["envmap.diffuse"], 0, uint32_t(0)); },
         "envmap.diffuse: size 0 is not a power of two"},
        {"diffuse_extent", [](Sections& s) { set(s["envmap.diffuse"], 4, -1.0f); },
         "envmap.diffuse: extent -1.000000 is not in [1, 4]"},
        {"diffuse_short", [](Sections& s) { s["envmap.diffuse"].resize(6); }, "envmap.diffuse is too short"},
        {"diffuse_long", [](Sections& s) { s["envmap.diffuse"].resize(s["envmap.diffuse"].size() + 12); },
         "envmap.diffuse has 12 bytes too many"},
        {"diffuse_nan", [](Sections& s) { set(s["envmap.diffuse"], 8 + 4 * 5, NAN); },
         "envmap.diffuse holds a value that is not finite"},
        {"ior_1", [](Sections& s) { set(s["envmap.fresnel"], 0, 1.0f); },
         "envmap.fresnel: index of refraction 1.000000 is not > 1"},
        {"ior_nan", [](Sections& s) { set(s["envmap.fresnel"], 16, NAN); },
         "envmap.fresnel: index of refraction"},
        {"fresnel_short", [](Sections& s) { s["envmap.fresnel"].resize(s["envmap.fresnel"].size() - 4); },
         "envmap.fresnel is too short"},
        {"fresnel_long", [](Sections& s) { s["envmap.fresnel"].resize(s["envmap.fresnel"].size() + 4); },
         "envmap.fresnel has 4 bytes too many"},
        {"fresnel_nan", [](Sections& s) { set(s["envmap.fresnel"], 8, NAN); },
         "envmap.fresnel holds a value that is not finite"},
        {"fresnel_missing", [](Sections& s) { s.erase("envmap.fresnel"); },
         "section 'envmap.fresnel' is missing"},
    };
    for (const auto& c : cases)
    {
        Sections s = good;
        c.change(s);
        const fs::path p = dir() / (std::string("broken_") + c.name + ".hemi");
        write_sections(p, s);
        const std::string e = error_of(p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.what), std::string::npos) << c.name << ": want '" << c.what << "', got: " << e;
    }
    // Unchanged, the same sections read.
    const fs::path p = dir() / "unbroken.hemi";
    write_sections(p, good);
    EXPECT_EQ(error_of(p), "(read)");
}

// What write_envmap_asset (and render::EnvironmentLighting) refuse: every inconsistency envmap_problem
// names, each made by one change to small_asset(); nothing is written.
TEST(EnvmapAsset, WriterRefusesEveryInconsistency)
{
    using Asset = hemi::io::EnvmapAsset;
    const struct
    {
        const char* name;
        std::function<void(Asset&)> change;
        std::string what;
    } cases[] = {
        {"no_mirror", [](Asset& a) { a.mirror.clear(); }, "no mirror map"},
        {"level_size", [](Asset& a) { a.mirror[1] = map(4, 2.0, 0.0f); },
         "mirror level 1 has the wrong size"},
        {"level_texels", [](Asset& a) { a.mirror[2].rgb.pop_back(); }, "mirror level 2 has the wrong size"},
        {"chain_end", [](Asset& a) { a.mirror.pop_back(); }, "does not end at 1x1"},
        {"exponents", [](Asset& a) { a.exponents.pop_back(); }, "one exponent per glossy map"},
        {"glossy_texels", [](Asset& a) { a.glossy[1].rgb.push_back(0.0f); }, "a glossy map's size"},
        {"glossy_size_0", [](Asset& a) { a.glossy[0].size = 0; }, "a glossy map's size"},
        {"diffuse", [](Asset& a) { a.diffuse.rgb.clear(); }, "the diffuse map's size"},
        {"fresnel_values", [](Asset& a) { a.fresnel.pop_back(); }, "the Fresnel tables' sizes disagree"},
        {"fresnel_samples",
         [](Asset& a)
         {
             a.fresnel_samples = 1;
             a.fresnel.resize(2);
         },
         "the Fresnel tables' sizes disagree"},
        {"65_glossy",
         [](Asset& a)
         {
             a.exponents.assign(65, 2.0f);
             a.glossy.assign(65, map(1, 1.0, 0.0f));
         },
         "at most 64 glossy maps"},
        {"65_iors",
         [](Asset& a)
         {
             a.iors.assign(65, 1.5f);
             a.fresnel.assign(65 * 3, 0.5f);
         },
         "at most 64 glossy maps, 64 Fresnel tables"},
        {"65537_samples",
         [](Asset& a)
         {
             a.fresnel_samples = 65537;
             a.fresnel.assign(2 * 65537, 0.5f);
         },
         "65536 samples"},
        {"not_power_of_two",
         [](Asset& a) {
             a.mirror = {map(6, 2.0, 0.0f), map(3, 2.0, 0.0f), map(1, 2.0, 0.0f)};
         },
         "not a power of two"},
        {"exponent_0", [](Asset& a) { a.exponents[1] = 0.0f; }, "a glossy map's exponent is not > 0"},
        {"exponent_nan", [](Asset& a) { a.exponents[0] = NAN; }, "a glossy map's exponent is not > 0"},
        {"ior_1", [](Asset& a) { a.iors[0] = 1.0f; }, "an index of refraction is not > 1"},
        {"ior_inf", [](Asset& a) { a.iors[1] = INFINITY; }, "an index of refraction is not > 1"},
    };
    const fs::path p = dir() / "never.hemi";
    for (const auto& c : cases)
    {
        hemi::io::EnvmapAsset a = small_asset();
        c.change(a);
        EXPECT_NE(hemi::io::envmap_problem(a).find(c.what), std::string::npos)
            << c.name << ": " << hemi::io::envmap_problem(a);
        try
        {
            hemi::io::write_envmap_asset(p, a);
            ADD_FAILURE() << c.name << " was written";
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(c.what), std::string::npos) << c.name << ": " << e.what();
            EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos)
                << c.name << ": " << e.what();
        }
        EXPECT_FALSE(fs::exists(p)) << c.name;
    }
}
