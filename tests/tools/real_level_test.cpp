// A real game level instead of a procedural scene: OpenArena's oa_dm3 ("The Abandoned Base", a Quake III
// deathmatch map from Debian's openarena-081-maps), converted with its own lightmap UVs (q3_level.h) and
// baked by hemi-bake lightmap as a process. The level's lightmaps, as q3map2 packed them, share texels
// between surfaces whose lighting came out identical (copies of a wall, mirrored corridors) and between
// coplanar surfaces laid over each other, so the bake meets overlapping lightmap UVs as shipped levels have
// them.
#include "../temp_dir.h"
#include "q3_level.h"
#include "run_tool.h"

#include <hemi/bake/embree_scene.h>
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/lightmap_unwrap.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <utility>

namespace fs = std::filesystem;

namespace
{

fs::path dir()
{
    return hemi::test::temp_dir("real_level_test");
}

using hemi::test::q;
using hemi::test::Result;
using hemi::test::slurp;

// hemi-bake lightmap as a process.
Result lightmap(const std::string& args)
{
    return hemi::test::run(dir(), HEMI_BAKE_EXE, "lightmap " + args);
}

const char* const kMap = "maps/oa_dm3.bsp";

const hemi::test::Q3Level& level()
{
    static const hemi::test::Q3Level l = hemi::test::read_q3_level(hemi::test::kOpenArenaMaps, kMap);
    return l;
}

// The level as the glTF file hemi-bake reads, written once per process.
const fs::path& level_gltf()
{
    static const fs::path p = []
    {
        const fs::path path = dir() / "oa_dm3.gltf";
        hemi::io::write_gltf(path, level().scene);
        return path;
    }();
    return p;
}

// The words hemi-bake uses for overlapping lightmap UVs, in the warning and in --strict-uv's refusal.
const char* const kOverlap = "lie inside two or more triangles";

} // namespace

// The conversion keeps the level whole: its polygons and patches (tessellated), thousands of triangles,
// each in one 128 x 128 lightmap page's cell of the atlas, front faces counter-clockwise as glTF wants them;
// the sky (faces without a lightmap) is left out. What hemi-bake reads back is the same mesh.
TEST(RealLevel, ConvertsAQuake3MapWithItsOwnLightmapUvs)
{
    const hemi::test::Q3Level& l = level();
    const hemi::io::Mesh& m = l.scene.mesh;
    const size_t triangles = m.indices.size() / 3;
    // oa_dm3: 22459 vertices, 22188 triangles, 1789 polygons and 174 patch faces (470 patches), 14 pages.
    EXPECT_GT(m.vertex_count(), 10000u);
    EXPECT_GT(triangles, 10000u);
    EXPECT_GT(l.polygon_faces, 1000u);
    EXPECT_GT(l.patches, 100u);
    EXPECT_GT(l.faces_without_lightmap, 0u) << "the sky was not left out";
    EXPECT_GT(l.lightmap_pages, 4u);
    ASSERT_EQ(l.faces.size(), triangles);
    ASSERT_EQ(m.uvs1.size(), m.vertex_count());
    ASSERT_EQ(m.uvs.size(), m.vertex_count());

    // TEXCOORD_1 lies in [0, 1], and each triangle inside one page's cell of the grid (a triangle reaching
    // into the next cell would take another surface's texels).
    const glm::vec2 grid(float(l.atlas_columns), float(l.atlas_rows));
    size_t outside = 0, straddling = 0;
    for (const glm::vec2& uv : m.uvs1)
        outside += !(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f);
    for (size_t t = 0; t < triangles; ++t)
    {
        glm::vec2 lo(INFINITY), hi(-INFINITY);
        for (int k = 0; k < 3; ++k)
        {
            lo = glm::min(lo, m.uvs1[m.indices[3 * t + k]] * grid);
            hi = glm::max(hi, m.uvs1[m.indices[3 * t + k]] * grid);
        }
        straddling += glm::floor(lo) != glm::floor(glm::max(lo, hi - 1e-4f));
    }
    EXPECT_EQ(outside, 0u);
    EXPECT_EQ(straddling, 0u);

    // The winding turned from Quake's clockwise: triangles face the way their vertex normals point (all
    // but a few folded patch triangles; measured 22085 of 22090 with area).
    size_t agree = 0, with_area = 0;
    for (size_t t = 0; t < triangles; ++t)
    {
        const glm::vec3 &a = m.positions[m.indices[3 * t]], &b = m.positions[m.indices[3 * t + 1]],
                        &c = m.positions[m.indices[3 * t + 2]];
        const glm::vec3 n = glm::cross(b - a, c - a);
        if (glm::length(n) < 1e-9f)
            continue;
        ++with_area;
        agree += glm::dot(n, m.normals[m.indices[3 * t]] + m.normals[m.indices[3 * t + 1]] +
                                 m.normals[m.indices[3 * t + 2]]) > 0.0f;
    }
    EXPECT_GT(double(agree), 0.999 * double(with_area)) << agree << " of " << with_area;

    const hemi::io::GltfScene back = hemi::io::read_gltf(level_gltf());
    ASSERT_EQ(back.mesh.vertex_count(), m.vertex_count());
    EXPECT_EQ(back.mesh.indices, m.indices);
    EXPECT_EQ(back.mesh.uvs1, m.uvs1);
    EXPECT_TRUE(back.tangents_generated);
    ASSERT_EQ(back.materials.size(), 1u);
    EXPECT_EQ(back.materials[0].base_color_factor, glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
}

// hemi-bake lightmap bakes the level on its own lightmap UVs: the overlapping texels are resolved and named
// in a warning, the sky's light comes in where the sky was, and --strict-uv refuses the overlaps, naming the
// scene, with no asset written. About 3 s in a release build on 2 cores (1024 x 1024, 627 k texels covered).
TEST(RealLevel, BakesItsOwnOverlappingLightmapUvsWithAWarning)
{
    const fs::path asset = dir() / "oa_dm3.hemi", json = dir() / "oa_dm3.json";
    const Result r = lightmap(q(level_gltf()) + " -o " + q(asset) +
                              " --size 1024 --rays 2 --bases plain --json " + q(json));
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json report = nlohmann::json::parse(slurp(json));
    EXPECT_EQ(report["width"], 1024);
    EXPECT_EQ(report["triangles"], level().scene.mesh.indices.size() / 3);
    EXPECT_GT(report["covered_texels"].get<size_t>(), 100000u); // measured 626922
    // q3map2 gives surfaces it found lit alike one lightmap rectangle (copies of a wall, of a pipe): 7056
    // texels of the 1024 x 1024 atlas that two triangles claim (measured).
    EXPECT_GT(report.value("overlapping_texels", size_t(0)), 1000u);
    // Texels whose claimants all lie inside geometry, given to a visible face of another rectangle that
    // covers part of them (q3map2 packs its rectangles unpadded): measured 34.
    EXPECT_GT(report.value("grazed_texels", size_t(0)), 0u);
    ASSERT_TRUE(report["warnings"].is_array());
    bool named = false;
    for (const nlohmann::json& w : report["warnings"])
        named |= w.get<std::string>().find(kOverlap) != std::string::npos;
    EXPECT_TRUE(named) << report["warnings"];
    // Where two faces meet on a smooth surface but q3map2 gave them rectangles of their own, a seam: the
    // stitch closes them (measured 454 edges, 0.51 -> 0.0086 at 2 rays).
    EXPECT_GT(report["seams"]["edges"].get<int>(), 100);
    EXPECT_LE(report["seams"]["outputs"]["plain"]["after"]["mean"].get<double>(),
              report["seams"]["outputs"]["plain"]["before"]["mean"].get<double>() / 10.0)
        << report["seams"];

    // Under uniform radiance, the texels whose rays leave through the openings where the sky faces were are
    // lit: measured 59201 texels for 626922 covered (the level is mostly indoors; 2 rays, no bounce), and
    // 5952 when the sky's polygons are kept.
    const hemi::io::LightmapAsset a = hemi::io::read_lightmap_asset(asset);
    const std::vector<float>& plain = a.output("plain").maps.values;
    size_t lit = 0;
    for (size_t i = 0; i < plain.size(); i += 3)
        lit += plain[i] > 0.0f;
    EXPECT_GT(lit, a.covered_texels / 50) << lit << " of " << a.covered_texels << " texels lit";
    fs::remove(asset); // 7 MB, in the system's temporary folder

    // The refusal comes after the atlas is rasterised, so a small atlas keeps it quick; the shared
    // rectangles overlap at any size (407 texels at 256 x 256).
    const fs::path refused = dir() / "oa_dm3_strict.hemi";
    const Result s =
        lightmap(q(level_gltf()) + " -o " + q(refused) + " --size 256 --rays 2 --bases plain --strict-uv");
    EXPECT_EQ(s.status, 1) << s.out << s.err;
    EXPECT_NE(s.err.find(kOverlap), std::string::npos) << s.err;
    EXPECT_NE(s.err.find(level_gltf().string()), std::string::npos) << s.err;
    EXPECT_FALSE(fs::exists(refused));
}

// The rasteriser in bands of block rows (a bake in tiles under a memory budget, issue 45) makes the atlas and
// the report of the whole atlas at once, on the real level's own lightmap UVs: its overlapping rectangles
// (resolved from each texel's neighbours, which may lie across a band's edge, and by rays), the texels given
// to a grazing face, the first overlap named. Bands of one block row, of three, and of a size that is no
// multiple of a row.
TEST(RealLevel, TheAtlasRasterisedInBandsIsTheWholeAtlas)
{
    // As hemi-bake reads it (its tangents made on reading).
    const hemi::io::Mesh mesh = hemi::io::read_gltf(level_gltf()).mesh;
    constexpr uint32_t kSize = 1024;
    hemi::bake::LightmapUvReport whole_report;
    const hemi::bake::LightmapAtlas whole = hemi::bake::rasterize_lightmap(mesh, kSize, kSize, whole_report);
    std::printf("%zu covered texels, %zu overlapping, %zu given to a grazing face\n",
                whole_report.covered_texels, whole_report.overlapping_texels, whole_report.grazed_instead);
    ASSERT_GT(whole_report.overlapping_texels, 1000u);
    ASSERT_GT(whole_report.grazed_instead, 0u);
    const size_t row = (kSize / 8) * 64;
    const std::filesystem::path pages = dir() / "atlas_pages";
    std::filesystem::create_directories(pages);
    for (const size_t band : {row, 3 * row, size_t(10007)})
    {
        hemi::bake::LightmapUvReport report;
        // The last kept in pages of temporary files, read back through a cache of 3 pages (PagedStore).
        const hemi::bake::LightmapAtlasStorage storage{band == 10007 ? pages : std::filesystem::path(), 3};
        const hemi::bake::LightmapAtlas banded =
            hemi::bake::rasterize_lightmap(mesh, kSize, kSize, report, {}, {}, 0, band, storage);
        EXPECT_EQ(banded.slot_texel.store().paged(), band == 10007);
        ASSERT_EQ(banded.texels.size(), whole.texels.size()) << band;
        EXPECT_EQ(banded.slot_texel.to_vector(), whole.slot_texel.to_vector()) << band;
        EXPECT_EQ(banded.grid.blocks(), whole.grid.blocks()) << band;
        size_t different = 0;
        for (size_t i = 0; i < whole.texels.size(); ++i)
        {
            const hemi::bake::LightmapTexel a = whole.texels[i], b = banded.texels[i];
            different += a.x != b.x || a.y != b.y || a.triangle != b.triangle ||
                         a.barycentric != b.barycentric || a.centre_inside != b.centre_inside;
        }
        EXPECT_EQ(different, 0u) << band;
        EXPECT_EQ(report.overlapping_texels, whole_report.overlapping_texels) << band;
        EXPECT_EQ(report.grazed_instead, whole_report.grazed_instead) << band;
        EXPECT_EQ(report.overlap_example[0], whole_report.overlap_example[0]) << band;
        EXPECT_EQ(report.overlap_example[1], whole_report.overlap_example[1]) << band;
        EXPECT_EQ(report.overlaps, whole_report.overlaps) << band;
        EXPECT_EQ(report.warnings, whole_report.warnings) << band;
        EXPECT_EQ(report.covered_texels, whole_report.covered_texels) << band;
    }
}

// --unwrap on the real level (issue 25): its coplanar faces that overlap (a face modelled twice, a patch over
// a wall) used to join one planar chart, and the bake then refused its own atlas ("176 lightmap texel(s) lie
// inside two or more triangles"). Unwrapped now, no texel lies in two triangles: --strict-uv bakes it.
TEST(RealLevel, UnwrapsItsOverlappingFacesIntoChartsThatShareNoTexel)
{
    const fs::path asset = dir() / "oa_dm3_unwrapped.hemi", json = dir() / "oa_dm3_unwrapped.json";
    const Result r =
        lightmap(q(level_gltf()) + " -o " + q(asset) +
                 " --unwrap --texel-size 0.4 --rays 2 --bases plain --strict-uv --json " + q(json));
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json report = nlohmann::json::parse(slurp(json));
    EXPECT_EQ(report.value("overlapping_texels", size_t(0)), 0u);
    EXPECT_GT(report["unwrap"]["charts"].get<int>(), 1000);
    fs::remove(asset);
}

// Errors name the file: a missing archive, an entry it does not hold, bytes that are no BSP, a BSP cut short.
TEST(RealLevel, BadArchivesAndLevelsAreRefusedNamingTheFile)
{
    auto message = [](auto&& f)
    {
        try
        {
            f();
        }
        catch (const std::runtime_error& e)
        {
            return std::string(e.what());
        }
        return std::string("no exception");
    };
    const fs::path missing = dir() / "no_such.pk3";
    EXPECT_NE(message([&] { hemi::test::read_zip_entry(missing, kMap); }).find(missing.string()),
              std::string::npos);
    const std::string absent =
        message([] { hemi::test::read_zip_entry(hemi::test::kOpenArenaMaps, "maps/none.bsp"); });
    EXPECT_NE(absent.find("maps/none.bsp"), std::string::npos) << absent;
    EXPECT_NE(absent.find("no such entry"), std::string::npos) << absent;
    const fs::path not_zip = dir() / "not_a.pk3";
    std::ofstream(not_zip) << "not a zip archive";
    EXPECT_NE(message([&] { hemi::test::read_zip_entry(not_zip, kMap); }).find(not_zip.string()),
              std::string::npos);

    std::vector<uint8_t> bsp = hemi::test::read_zip_entry(hemi::test::kOpenArenaMaps, kMap);
    const std::string wrong = message(
        [] {
            hemi::test::convert_q3_level({'I', 'B', 'S', 'P'}, "short.bsp");
        });
    EXPECT_NE(wrong.find("short.bsp"), std::string::npos) << wrong;
    bsp.resize(bsp.size() / 2);
    const std::string cut = message([&] { hemi::test::convert_q3_level(bsp, "cut.bsp"); });
    EXPECT_NE(cut.find("cut.bsp: lump"), std::string::npos) << cut;
}

namespace
{

// The mesh's axis-aligned bounding box, the region open points are drawn from.
std::pair<glm::vec3, glm::vec3> bounds(const hemi::io::Mesh& mesh)
{
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : mesh.positions)
    {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    return {lo, hi};
}

// A point of the level's open space: none of 256 rays over the sphere (a Fibonacci set) meets the back of a
// surface (so it is not inside a wall, a pillar or the void outside the level) and at most half escape (it
// is inside the level).
bool open_point(const hemi::bake::EmbreeScene& scene, const glm::vec3& c)
{
    constexpr int kProbe = 256;
    int escape = 0;
    for (int i = 0; i < kProbe; ++i)
    {
        const float z = 1.0f - 2.0f * (float(i) + 0.5f) / kProbe, r = std::sqrt(1.0f - z * z);
        const glm::vec3 d(r * std::cos(2.39996323f * float(i)), r * std::sin(2.39996323f * float(i)), z);
        const std::optional<hemi::bake::RayHit> h = scene.intersect(c, d);
        if (h && glm::dot(scene.geometric_normal(h->primitive), d) > 0.0f)
            return false;
        escape += !h;
    }
    return 2 * escape <= kProbe;
}

// The real levels of issue 41's tests: the community pack's sealed indoor level and the 0.8.1 arena.
struct LevelCase
{
    std::filesystem::path pk3;
    const char* map;
};
const std::array<LevelCase, 2> kLevels = {LevelCase{hemi::test::kOpenArenaCommunityMaps, "maps/oacmpdm1.bsp"},
                                          LevelCase{hemi::test::kOpenArenaMaps, kMap}};

// What a viewer standing in a level's open space sees of its lightmap (issue 41). Open points: points of the
// level's bounding box from which none of 256 rays over the sphere meets the back of a surface (so the
// point is not inside a wall, a pillar or the void outside the level) and at most half escape (it is inside
// the level). From each, 200 random rays; each hit is looked up in the atlas at its TEXCOORD_1: counted when
// the texel there is inside geometry (LightmapSh::valid 0: its value comes from its neighbours, or is its own
// where none reaches it), and when that texel is the hit triangle's own.
struct Sight
{
    size_t texels = 0, pushed = 0, invalid = 0; // the bake's
    size_t points = 0, hits = 0, on_invalid = 0, on_own_invalid = 0;
    size_t on_backs = 0; // of on_invalid: hits on a point that itself sees backs over much of its hemisphere
    size_t no_uv_area = 0; // hits on triangles with no lightmap UV area (no texel of their own), not counted
};

// The share of 256 rays over the hemisphere of a surface point (a Fibonacci set about its unit normal `g`)
// that meet the back of a surface first.
double back_share(const hemi::bake::EmbreeScene& scene, const glm::vec3& p, const glm::vec3& g)
{
    constexpr int kProbe = 256;
    const glm::vec3 u = glm::normalize(
                        glm::cross(g, std::abs(g.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0))),
                    v = glm::cross(g, u);
    int back = 0;
    for (int i = 0; i < kProbe; ++i)
    {
        const float z = 1.0f - (float(i) + 0.5f) / kProbe, r = std::sqrt(1.0f - z * z);
        const glm::vec3 d =
            r * std::cos(2.39996323f * float(i)) * u + r * std::sin(2.39996323f * float(i)) * v + z * g;
        const std::optional<hemi::bake::RayHit> h = scene.intersect(p, d);
        back += h && glm::dot(scene.geometric_normal(h->primitive), d) > 0.0f;
    }
    return double(back) / kProbe;
}

Sight sight(hemi::io::Mesh mesh, uint32_t size, bool unwrap)
{
    using namespace hemi::bake;
    if (unwrap)
    {
        UnwrapOptions u;
        u.width = u.height = size;
        unwrap_lightmap(mesh, u);
    }
    LightmapUvReport report;
    const LightmapAtlas atlas = rasterize_lightmap(mesh, size, size, report);
    LightmapBakeOptions o;
    o.rays = 64; // the classification counts the first pass's rays
    const LightmapSh sh = bake_lightmap_sh(mesh, atlas, LightmapLights{}, o);
    Sight s;
    s.texels = atlas.texels.size();
    s.pushed = sh.pushed;
    s.invalid = sh.invalid;

    const EmbreeScene scene(mesh);
    const auto [lo, hi] = bounds(mesh);
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    auto random_direction = [&]
    {
        const float z = 2.0f * uniform(rng) - 1.0f, r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        const float phi = 2.0f * float(M_PI) * uniform(rng);
        return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    for (int attempt = 0; attempt < 1000000 && s.points < 300; ++attempt)
    {
        const glm::vec3 c = lo + (hi - lo) * glm::vec3(uniform(rng), uniform(rng), uniform(rng));
        if (!open_point(scene, c))
            continue;
        ++s.points;
        for (int i = 0; i < 200; ++i)
        {
            const glm::vec3 d = random_direction();
            const std::optional<RayHit> h = scene.intersect(c, d);
            if (!h)
                continue;
            const uint32_t t = h->primitive;
            const glm::vec2 uv = (1.0f - h->u - h->v) * mesh.uvs1[mesh.indices[3 * t]] +
                                 h->u * mesh.uvs1[mesh.indices[3 * t + 1]] +
                                 h->v * mesh.uvs1[mesh.indices[3 * t + 2]];
            const glm::vec2 e1 = mesh.uvs1[mesh.indices[3 * t + 1]] - mesh.uvs1[mesh.indices[3 * t]],
                            e2 = mesh.uvs1[mesh.indices[3 * t + 2]] - mesh.uvs1[mesh.indices[3 * t]];
            if (std::abs(double(e1.x) * e2.y - double(e1.y) * e2.x) * size * size < 1e-6)
            {
                ++s.no_uv_area; // q3map2 gave the face a line or a point of its page (the bake warns)
                continue;
            }
            const int32_t texel = atlas.texel_of(int64_t(uv.x * float(size)), int64_t(uv.y * float(size)));
            ++s.hits;
            if (texel >= 0 && !sh.valid[size_t(texel)])
            {
                ++s.on_invalid;
                s.on_own_invalid += atlas.texels[size_t(texel)].triangle == t;
                const glm::vec3 g = glm::normalize(scene.geometric_normal(t));
                s.on_backs += back_share(scene, c + d * h->distance + 1e-3f * g, g) > 0.3;
            }
        }
    }
    return s;
}

} // namespace

// Issue 41: a shipped level's lightmap went dark where a viewer looks. q3map2 gives a face left inside a
// pillar (a ceiling running on over the pillar's top) the same lightmap rectangle as a visible face, and
// the overlap went to the hidden face, whose texels are inside geometry: the visible face read them dark.
// Overlaps now go first to a face a viewer can reach, a texel that straddles a wall samples the part of its
// footprint outside it, and a texel inside geometry that points outside geometry see is baked all the same
// (detail::TexelOrigins::seen: oa_dm3's outer walls face the backs of the arena's single-sided walls, and a
// viewer in the arena sees them over the walls' tops). From 300 open points of each level (each 200 rays),
// on its own lightmap UVs and unwrapped at 1024 x 1024, hits on texels inside geometry at points that see
// backs over at most 30% of their hemisphere (the point is in the open by any measure): at most 1 in 40,000.
// Those at points that see more: at most 1 in 4,000. Hits on faces to which q3map2 gave a line or a point
// of its page (no UV area, no texel of their own: the bake warns, and --unwrap gives them texels) are
// counted apart. Measured (texels / moved out of walls / inside geometry; hits on such texels: all, at
// points that see more backs; hits on faces with no UV area):
//   oacmpdm1 own UVs   736,101 / 39,614 / 65,066; 0 of 59,964 (0); 36. Before the footprint and the
//                      grazing faces 35 of 60,000, before the overlap rule 262
//   oacmpdm1 unwrapped 511,847 / 37,574 / 43,537; 0 of 60,000
//   oa_dm3 own UVs     626,922 / 23,914 / 33,011; 4 of 44,394 (4); 168. Before seen(): 17 (17), before
//                      the footprint 97
//   oa_dm3 unwrapped   441,210 / 13,234 / 25,768; 2 of 44,562 (2). Before seen(): 60 (59)
// The other texels inside geometry are faces no viewer reaches (oacmpdm1 has no sky).
TEST(RealLevel, WhatAViewerInTheLevelSeesIsBakedNotFilledFromNeighbours)
{
    for (const LevelCase& c : kLevels)
    {
        // Through glTF, as hemi-bake reads it (the reader makes the tangent frames).
        const fs::path gltf = dir() / (fs::path(c.map).stem().string() + "_sight.gltf");
        hemi::io::write_gltf(gltf, hemi::test::read_q3_level(c.pk3, c.map).scene);
        const hemi::io::Mesh mesh = hemi::io::read_gltf(gltf).mesh;
        for (const bool unwrap : {false, true})
        {
            const Sight s = sight(mesh, 1024, unwrap);
            SCOPED_TRACE(std::string(c.map) + (unwrap ? " unwrapped" : " own UVs"));
            std::printf("%s%s: %zu texels, %zu moved out of walls, %zu inside geometry; %zu open points, %zu "
                        "hits, %zu on texels inside geometry (%zu the hit triangle's own, %zu on points that "
                        "see backs over 30%% of their hemisphere); %zu hits on faces with no UV area\n",
                        c.map, unwrap ? " unwrapped" : "", s.texels, s.pushed, s.invalid, s.points, s.hits,
                        s.on_invalid, s.on_own_invalid, s.on_backs, s.no_uv_area);
            EXPECT_GT(s.points, 100u);
            EXPECT_GT(s.hits, 10000u);
            EXPECT_LE(double(s.on_invalid - s.on_backs), 2.5e-5 * double(s.hits));
            EXPECT_LE(double(s.on_backs), 2.5e-4 * double(s.hits));
        }
    }
}

namespace
{

// A camera of the comparison below, in hemi's world (z up): at an open point, looking at a surface it sees.
struct View
{
    glm::vec3 eye, target;
    uint32_t triangle = 0; // the surface seen, and its TEXCOORD_1 at the target
    glm::vec2 uv{0.0f};
};

// glTF's y-up scene space to hemi's z-up world (math::gltf_to_world()).
glm::vec3 to_world(const glm::vec3& p)
{
    return {p.x, -p.z, p.y};
}

// `lights` open points of the level (as in sight() above) for point lights, and `count` views: each from an
// open point within 8 units of a light, at a surface 1 to 10 units away facing it (cosine over 0.5), which
// that light reaches within 10 units, unshadowed there and 0.5 and 1 unit around it, with an irradiance
// within 20% of the target's at those points, of a triangle whose texels
// are at most 0.5 units across at `size`^2 (the arena's own density; the terrain outside oa_dm3's arena has
// texels of 10 units, which cannot hold a point light's falloff). Deterministic.
void pick_views(const hemi::io::Mesh& mesh, uint32_t size, int lights, int count, std::vector<glm::vec3>& at,
                std::vector<View>& views)
{
    const hemi::bake::EmbreeScene scene(mesh);
    const auto [lo, hi] = bounds(mesh);
    std::mt19937 rng(4141);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    auto open = [&](const glm::vec3& c) { return open_point(scene, c); };
    auto texel_size = [&](uint32_t t)
    {
        const uint32_t* i = &mesh.indices[size_t(t) * 3];
        const glm::vec2 a = mesh.uvs1[i[0]], b = mesh.uvs1[i[1]], c = mesh.uvs1[i[2]];
        const double uv = 0.5 * std::abs(double((b - a).x * (c - a).y - (b - a).y * (c - a).x)) * size * size;
        const double area = 0.5 * double(glm::length(scene.geometric_normal(t)));
        return uv > 0.0 ? std::sqrt(area / uv) : INFINITY;
    };
    for (int attempt = 0; attempt < 1000000 && int(at.size()) < lights; ++attempt)
    {
        const glm::vec3 c = lo + (hi - lo) * glm::vec3(uniform(rng), uniform(rng), uniform(rng));
        if (open(c))
            at.push_back(c);
    }
    for (int attempt = 0; attempt < 1000000 && int(views.size()) < count && !at.empty(); ++attempt)
    {
        const glm::vec3& light = at[size_t(attempt) % at.size()];
        const glm::vec3 eye = light + 16.0f * (glm::vec3(uniform(rng), uniform(rng), uniform(rng)) - 0.5f);
        if (!open(eye))
            continue;
        for (int k = 0; k < 50; ++k)
        {
            const float z = 2.0f * uniform(rng) - 1.0f, r = std::sqrt(1.0f - z * z);
            const float phi = 2.0f * float(M_PI) * uniform(rng);
            const glm::vec3 d(r * std::cos(phi), r * std::sin(phi), z);
            const std::optional<hemi::bake::RayHit> h = scene.intersect(eye, d);
            if (!h || h->distance < 1.0f || h->distance > 10.0f || texel_size(h->primitive) > 0.5)
                continue;
            const glm::vec3 g = glm::normalize(scene.geometric_normal(h->primitive));
            const glm::vec3 target = eye + d * h->distance;
            // Seen square on, and lit at more than a grazing angle (where E changes fastest across a texel).
            if (glm::dot(g, -d) < 0.5f || glm::length(light - target) > 10.0f ||
                glm::dot(g, glm::normalize(light - target)) < 0.2f)
                continue;
            // Lit at the target and at 8 points 0.5 and 1 unit around it in its plane: no shadow's edge
            // within the pixels compared, where the lightmap's texels cannot follow it.
            const glm::vec3 u = glm::normalize(glm::cross(g, std::abs(g.x) < 0.9f ? glm::vec3(1, 0, 0)
                                                                                  : glm::vec3(0, 1, 0))),
                            v = glm::cross(g, u);
            // And the light's irradiance there within 20% of the target's: no falloff steeper than the
            // lightmap's texels can follow (a light a unit from the surface).
            bool lit = true;
            const glm::vec3 at_target = light - target;
            const float e_target = glm::dot(g, glm::normalize(at_target)) / glm::dot(at_target, at_target);
            for (int p = 0; p < 17 && lit; ++p)
            {
                const float a = float(p % 8) * float(M_PI) / 4.0f,
                            radius = p == 16 ? 0.0f : (p < 8 ? 0.5f : 1.0f);
                const glm::vec3 from = target + radius * (std::cos(a) * u + std::sin(a) * v) + 1e-3f * g,
                                to = light - from;
                const float e = glm::dot(g, glm::normalize(to)) / glm::dot(to, to);
                lit = glm::dot(to, g) > 0.0f && std::abs(e / e_target - 1.0f) <= 0.2f &&
                      !scene.occluded(from, glm::normalize(to), 0.0f, glm::length(to));
            }
            if (!lit)
                continue;
            const uint32_t* i = &mesh.indices[size_t(h->primitive) * 3];
            views.push_back(
                {to_world(eye), to_world(target), h->primitive,
                 (1.0f - h->u - h->v) * mesh.uvs1[i[0]] + h->u * mesh.uvs1[i[1]] + h->v * mesh.uvs1[i[2]]});
            break;
        }
    }
}

// The mean of the red channel over the 8 x 8 pixels at the centre of a 64 x 48 EXR.
double centre(const fs::path& exr)
{
    const hemi::io::ImageRgba im = hemi::io::read_exr(exr);
    double sum = 0.0;
    for (uint32_t y = 20; y < 28; ++y)
        for (uint32_t x = 28; x < 36; ++x)
            sum += im.pixels[(size_t(y) * im.width + x) * 4];
    return sum / 64.0;
}

} // namespace

// Issue 41: the lightmap agrees with hemi's own path tracer (hemi-bake reference) from cameras in the
// level's open space. Each level, lit by four point lights of 30 cd at open points (oacmpdm1 is sealed: no
// sky light reaches its inside), is baked direct-only by hemi-bake lightmap on its own UVs and with
// --unwrap, and 20 cameras near the lights look at surfaces those lights reach (no shadow edge within 1
// unit, the light's irradiance within 20% of the target's there, not at a grazing angle: the lightmap holds
// E per texel of 0.1 to 0.5 units, the reference per point). The 8 x 8 pixels at the centre of hemi-render
// --white (E / pi from the lightmap) agree with the reference's (128 paths a pixel) within 5%: measured 77 of
// the 79 views compared within 2%, the others -4.4% and -2.3%. On the own UVs, a view whose texel q3map2 gave
// another face (lit alike under Quake's lights, not under these) is printed, not compared (one on oacmpdm1:
// 0.127 against 0.118; the bake warns of it and --unwrap gives every face its own). Fails when the push moves
// texels through front faces too, for texels black where they are seen, for a sliver's sample moved to its
// far end (oa_dm3 view 11: -17%), and for stitching across a sliver folded back over its neighbour
// (oacmpdm1 unwrapped view 8: -26%).
TEST(RealLevel, TheLightmapAgreesWithTheReferenceFromOpenPoints)
{
    for (const LevelCase& c : kLevels)
    {
        const std::string name = fs::path(c.map).stem().string();
        const fs::path plain = dir() / (name + "_views.gltf");
        hemi::io::write_gltf(plain, hemi::test::read_q3_level(c.pk3, c.map).scene);
        std::vector<glm::vec3> lights;
        std::vector<View> views;
        const hemi::io::Mesh mesh = hemi::io::read_gltf(plain).mesh;
        pick_views(mesh, 1024, 4, 20, lights, views);
        ASSERT_EQ(views.size(), 20u) << name;
        // On the level's own UVs, a view whose texel another triangle holds (q3map2 gave both faces one
        // rectangle, lit alike under Quake's lights, not under these) shows the other face's light, as the
        // bake's warning says; --unwrap gives every face its own.
        hemi::bake::LightmapUvReport report;
        const hemi::bake::LightmapAtlas atlas = hemi::bake::rasterize_lightmap(mesh, 1024, 1024, report);
        std::vector<bool> shared;
        for (const View& v : views)
        {
            const int32_t t = atlas.texel_of(int64_t(v.uv.x * 1024.0f), int64_t(v.uv.y * 1024.0f));
            shared.push_back(t < 0 || atlas.texels[size_t(t)].triangle != v.triangle);
        }
        // The lights as KHR_lights_punctual nodes.
        nlohmann::json j = nlohmann::json::parse(slurp(plain));
        j["extensionsUsed"].push_back("KHR_lights_punctual");
        for (size_t i = 0; i < lights.size(); ++i)
        {
            j["extensions"]["KHR_lights_punctual"]["lights"].push_back(
                {{"type", "point"}, {"intensity", 30.0}, {"color", {1.0, 0.9, 0.8}}});
            j["nodes"].push_back({{"translation", {lights[i].x, lights[i].y, lights[i].z}},
                                  {"extensions", {{"KHR_lights_punctual", {{"light", int(i)}}}}}});
            j["scenes"][0]["nodes"].push_back(int(j["nodes"].size()) - 1);
        }
        const fs::path scene = dir() / (name + "_lit.gltf");
        std::ofstream(scene) << j.dump();
        for (const glm::vec3& l : lights)
        {
            const glm::vec3 w = to_world(l);
            std::printf("%s: a light at %.6g,%.6g,%.6g (world)\n", name.c_str(), w.x, w.y, w.z);
        }
        auto camera = [](const View& v)
        {
            char text[256];
            std::snprintf(text, sizeof text, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", v.eye.x, v.eye.y, v.eye.z,
                          v.target.x, v.target.y, v.target.z);
            return std::string(text);
        };
        std::vector<double> reference;
        for (size_t v = 0; v < views.size(); ++v)
        {
            const fs::path exr = dir() / (name + "_ref" + std::to_string(v) + ".exr");
            const Result r =
                hemi::test::run(dir(), HEMI_BAKE_EXE,
                                "reference " + q(scene) + " -o " + q(exr) +
                                    " --env uniform --env-scale 0 --white --size 64x48 --rays 128"
                                    " --camera " +
                                    camera(views[v]));
            ASSERT_EQ(r.status, 0) << r.err;
            reference.push_back(centre(exr));
        }
        for (const bool unwrap : {false, true})
        {
            const fs::path asset = dir() / (name + (unwrap ? "_unwrapped" : "") + "_lit.hemi");
            const Result b = lightmap(q(scene) + " -o " + q(asset) +
                                      " --size 1024 --rays 32 --bounces 0 --bases plain --env uniform "
                                      "--env-scale 0" +
                                      (unwrap ? " --unwrap" : ""));
            ASSERT_EQ(b.status, 0) << b.err;
            for (size_t v = 0; v < views.size(); ++v)
            {
                const fs::path exr = dir() / (name + "_lm" + std::to_string(v) + ".exr");
                const Result r = hemi::test::run(dir(), HEMI_RENDER_EXE,
                                                 q(asset) + " --technique plain --white --size 64x48 -o " +
                                                     q(exr) + " --camera " + camera(views[v]),
                                                 "HEMI_VALIDATION=1");
                ASSERT_EQ(r.status, 0) << r.err;
                const double lit = centre(exr);
                std::printf("%s%s view %zu: reference %.4f, lightmap %.4f%s\n", name.c_str(),
                            unwrap ? " unwrapped" : "", v, reference[v], lit,
                            !unwrap && shared[v] ? " (a texel another triangle holds)" : "");
                if (!unwrap && shared[v])
                    continue;
                EXPECT_NEAR(lit, reference[v], 0.05 * reference[v])
                    << name << (unwrap ? " unwrapped" : "") << ", view " << v << " " << camera(views[v]);
            }
            fs::remove(asset);
        }
    }
}

// Issue 41's three cameras: oacmpdm1 under a uniform sky of 0.5 and a sun (--bounces 0), looking up from
// 1 m below at three ceilings (Quake (607, 544, 384), (619, -551, 384) and (736, 17, -64)), on its own
// UVs and with --unwrap. The 8 x 8 pixels at the centre of hemi-render --white agree with hemi-bake
// reference's within 10% (measured 0.121, 0.120, 0.160 against 0.118, 0.117, 0.161 on the own UVs). The
// ceilings' texels are judged inside geometry (most of their rays meet backs in this sealed level) though
// the cameras see them; their own values are right. The second lies two texels from another face's
// rectangle in q3map2's unpadded page, and before the dilation kept an invalid texel to its own chart's
// light it took that face's, 0 against 0.117.
TEST(RealLevel, TheIssuesThreeCeilingsAreLitAsTheReferenceSeesThem)
{
    // In metres, as the issue converted it: Quake's inches times 0.0254 (read_q3_level gives inches / 64).
    const fs::path scene = dir() / "oacmpdm1_ceilings.gltf";
    hemi::io::GltfScene level =
        hemi::test::read_q3_level(hemi::test::kOpenArenaCommunityMaps, "maps/oacmpdm1.bsp").scene;
    for (glm::vec3& p : level.mesh.positions)
        p *= 64.0f * 0.0254f;
    hemi::io::write_gltf(scene, level);
    const std::string lights = " --env uniform --env-scale 0.5 --sun 0.5,-0.35,0.79,3,3,3,0.53";
    std::vector<std::string> cameras;
    for (const glm::vec3 quake :
         {glm::vec3(607, 544, 384), glm::vec3(619, -551, 384), glm::vec3(736, 17, -64)})
    {
        const glm::vec3 p = quake * 0.0254f; // hemi's z-up world is Quake's axes in metres
        char text[256];
        std::snprintf(text, sizeof text, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", p.x, p.y, p.z - 1.0f, p.x, p.y,
                      p.z);
        cameras.push_back(text);
    }
    std::vector<double> reference;
    for (size_t v = 0; v < cameras.size(); ++v)
    {
        const fs::path exr = dir() / ("ceiling_ref" + std::to_string(v) + ".exr");
        const Result r =
            hemi::test::run(dir(), HEMI_BAKE_EXE,
                            "reference " + q(scene) + " -o " + q(exr) + lights +
                                " --bounces 0 --white --size 64x48 --rays 128 --camera " + cameras[v]);
        ASSERT_EQ(r.status, 0) << r.err;
        reference.push_back(centre(exr));
        EXPECT_GT(reference.back(), 0.1) << "the reference sees the lit ceiling at " << cameras[v];
    }
    for (const bool unwrap : {false, true})
    {
        const fs::path asset = dir() / (unwrap ? "ceilings_unwrapped.hemi" : "ceilings.hemi");
        const Result b = lightmap(q(scene) + " -o " + q(asset) + lights +
                                  " --size 1024 --bounces 0 --bases plain" + (unwrap ? " --unwrap" : ""));
        ASSERT_EQ(b.status, 0) << b.err;
        for (size_t v = 0; v < cameras.size(); ++v)
        {
            const fs::path exr = dir() / ("ceiling_lm" + std::to_string(v) + ".exr");
            const Result r = hemi::test::run(dir(), HEMI_RENDER_EXE,
                                             q(asset) + " --technique plain --white --size 64x48 -o " +
                                                 q(exr) + " --camera " + cameras[v],
                                             "HEMI_VALIDATION=1");
            ASSERT_EQ(r.status, 0) << r.err;
            const double lit = centre(exr);
            std::printf("oacmpdm1%s ceiling %zu: reference %.4f, lightmap %.4f\n", unwrap ? " unwrapped" : "",
                        v, reference[v], lit);
            EXPECT_NEAR(lit, reference[v], 0.1 * reference[v]) << (unwrap ? "unwrapped, " : "") << cameras[v];
        }
        fs::remove(asset);
    }
}
