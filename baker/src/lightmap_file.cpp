// hemi-bake lightmap's job from a glTF file to a lightmap asset, EXRs and a JSON report (lightmap_bake.h).
#include <hemi/bake/checkpoint.h>
#include <hemi/bake/light_bound.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/lightmap_denoise.h>
#include <hemi/bake/lightmap_seams.h>
#include <hemi/bake/lightmap_unwrap.h>
#include <hemi/bake/probe_placement.h>
#include <hemi/bake/reflection_probe.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/half_scale.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/memory.h>
#include <hemi/math/camera.h>

#include <nlohmann/json.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <thread>

namespace hemi::bake
{
std::filesystem::path lightmap_exr_path(const std::filesystem::path& dir, const std::filesystem::path& asset,
                                        const std::string& output)
{
    return dir / (asset.stem().string() + "." + output + ".exr");
}

std::filesystem::path lightmap_tile_path(const std::filesystem::path& asset)
{
    return asset.string() + ".tiles";
}

namespace
{

// Peak memory of a bake, an upper estimate. The bake keeps only the 8 x 8 blocks of the atlas that triangles
// touch (io::BlockGrid), so it is counted per texel of those blocks ("slots") and per covered texel (at most
// one a slot), as the largest of three stages':
// - the rasteriser (lightmap_atlas.cpp): per slot its tables (the best triangle, its distance and
//   barycentrics, the claimants' count and first, the slot's texel index and its band copy:
//   kRasterBytesPerSlot), per covered
//   texel the record it makes (kTexelRecordBytes, LightmapTexels); in bands of block rows when that does not
//   fit the budget, per slot its texel index (kSlotTexelBytes) and the tables over one band and the block
//   rows either side (kRasterTableBytesPerSlot, lightmap_atlas.h);
// - the passes: per slot the texel index and the bounce map's halves (kLightmapBytesPerSlot), one band of the
//   bounce map's dilation (bounce_band_bytes), per covered texel its record and either every sum of the
//   passes and the pass being gathered with each texel's origin, flags and the irradiance the next pass
//   bounces (kLightmapBytesPerCoveredTexel, in memory) or, in tiles under a memory budget, the record, the
//   texel's validity and chart (kTiledBytesPerCoveredTexel) plus one tile's sums, pass, origins and bounced
//   irradiance (kTileBytesPerTexel per texel of a tile; the rest is in the tile file, texel_file.h);
// - the outputs: per slot of the outputs' blocks (the touched ones and their dilation) the float map of the
//   one output being made (the largest; the asset's writer spools each finished output's half floats to
//   disk, io::AssetWriter), per covered texel its record (its place and chart) and the sums when in memory.
// In tiles, where the records and slot indices kept in memory would leave room only for small tiles, they go
// to pages of files (PagedArray): each stage then holds the pages' caches instead.
// Measured (docs/lightmaps.md#memory-and-asset-size):
// the sample's 2 x 2 rooms at 2048^2 (2.77 M covered texels) peaked at 3.29 GB with every output held in
// floats at once, 2.08 GB with one at a time. --denoise adds each texel's noise estimate, for the bake and
// for the pass (32 bytes), and what the filter holds beside the bake's sums: a second copy of the values,
// five arrays of four floats and the 64-byte record of what its windows read (kDenoiseBytesPerCoveredTexel;
// each texel's chart it reads from the records); in tiles the filter works in
// bands of rows with the rows around them it depends on, each texel of a band read (sums and noise) and
// filtered in two copies (kDenoiseBandBytesPerTexel). With
// --exr-dir, one output at a time is expanded to the whole atlas (an EXR is a dense image): 4 bytes per atlas
// texel and coefficient of the largest output, and OpenEXR's half copy.
constexpr uint64_t kRasterBytesPerSlot = 33;
constexpr uint64_t kSlotTexelBytes = 4;
constexpr uint64_t kTexelRecordBytes = 16;
constexpr uint64_t kLightmapBytesPerSlot = 12;
constexpr uint64_t kLightmapBytesPerLargestCoefficient = 4; // the output being made, in floats
// In memory: the record 16, origin 12, flags 3, the bounced irradiance 12, the sums 108 + 48 and the pass's
// 108 + 48, the charts 4.
constexpr uint64_t kLightmapBytesPerCoveredTexel = 360;
constexpr uint64_t kTiledBytesPerCoveredTexel = 18; // the record 16, validity 1 (and 1 while found)
constexpr uint64_t kDilationBytesPerSlot = 2 + 4;   // the dilation's state (two passes') and chart per slot
constexpr uint64_t kPlaceBytesPerTexel =
    16; // what the outputs keep of the atlas: the records (places, charts)
// With the records in pages of files (LightmapAtlasStorage, when kept in memory they would leave tiles of
// fewer than kPagedBelowTileTexels): per slot the bounce map's halves alone, per texel its validity (and 1
// while found), and two caches of pages (page_cache_bytes below).
constexpr uint64_t kPagedLightmapBytesPerSlot = kLightmapBytesPerSlot - kSlotTexelBytes;
constexpr uint64_t kPagedTiledBytesPerCoveredTexel = kTiledBytesPerCoveredTexel - kTexelRecordBytes;
constexpr uint64_t kPagedBelowTileTexels = 65536;
constexpr size_t kPageCachePages = LightmapAtlasStorage::kDefaultCachePages;
// A tile's sums and pass (108 + 48 each), its origins and flags (13) and bounced irradiance (12).
constexpr uint64_t kTileBytesPerTexel = 2 * (108 + 48) + 13 + 12;
constexpr uint64_t kTileNoiseBytesPerTexel = 2 * 16;
constexpr uint64_t kDenoiseBytesPerCoveredTexel = 2 * 16 + 156 + 5 * 16 + 64;
constexpr uint64_t kDenoiseBandBytesPerTexel = 2 * 156 + 16 + 5 * 16 + 64;
constexpr uint64_t kExrBytesPerCoefficient = 6;
// With mixed lights, every covered texel's shadowmask (4 floats) and the mixed lights' direct light (3); in
// tiles a tile's, the rest in the tile file.
constexpr uint64_t kMixedBytesPerCoveredTexel = 28;
// Light probes (--probes) are held whole, beside the lightmap's sums while they bake and then written with
// the asset: their SH9 irradiance and validity, the asset's copy and its spooled bytes. Measured 218-220
// bytes a probe (64^3 and 128^3 probes at one ray each: +57.7 MB and +458 MB of peak); issue 41 found
// 256^3 probes peaking at 3.5 GB under a budget of 100 MB.
constexpr uint64_t kProbeBytes = 224;
// Each probe's depth map (--probe-depth R): R^2 texels of 2 floats held, 2 halves in the asset's bytes.
constexpr uint64_t kProbeDepthBytesPerTexel = 8 + 4;
// The ray tracer's BVH over the scene (EmbreeScene: its copy of the positions and triangles, the BVH and what
// its build holds): 160 bytes a triangle measured on oa_dm3's 22,188 triangles; with the bake's own record of
// each triangle for its rays' hits (40 bytes: lightmap_bake.cpp, HitTriangle), 200, rounded up.
constexpr uint64_t kEmbreeBytesPerTriangle = 256;
// What the ray tracer's device and the threads hold beside the heap the bake counts (Embree's and TBB's own
// arenas, the threads' stacks): measured 2.2 MB on 2 threads (the post scene at 512^2: the process's peak
// resident set over what it held before the bake and the heap's peak, heaptrack), counted with room.
constexpr uint64_t kTracerBytes = uint64_t(4) << 20, kTracerBytesPerThread = uint64_t(1) << 20;
// The smallest tile a budget may leave room for: below it, the ranks' slices and the tile file's reads
// would be too small to keep the cores busy.
constexpr uint32_t kMinTileTexels = 4096;

// The blocks around the touched ones that dilating the outputs by `dilate` texels may fill too.
uint64_t dilated_slots(const io::BlockGrid& grid, int dilate)
{
    const int64_t ring = (std::max(dilate, 0) + int64_t(io::BlockGrid::kSize) - 1) / io::BlockGrid::kSize;
    const int64_t bx = grid.blocks_x(), by = grid.blocks_y();
    std::vector<uint8_t> keep(size_t(bx * by), 0);
    for (uint32_t b : grid.blocks())
        for (int64_t j = std::max<int64_t>(0, b / bx - ring); j <= std::min<int64_t>(by - 1, b / bx + ring);
             ++j)
            for (int64_t i = std::max<int64_t>(0, b % bx - ring);
                 i <= std::min<int64_t>(bx - 1, b % bx + ring); ++i)
                keep[size_t(j * bx + i)] = 1;
    return uint64_t(std::count(keep.begin(), keep.end(), uint8_t(1))) * io::BlockGrid::kTexels;
}

// The atlas as a picture (LightmapFileOptions::uv_report).
void write_uv_report(const std::filesystem::path& path, const LightmapAtlas& atlas,
                     const LightmapUvReport& report)
{
    const uint32_t scale = std::max<uint32_t>(1, (std::max(atlas.width, atlas.height) + 2047) / 2048);
    io::ImageRgba8 image;
    image.width = (atlas.width + scale - 1) / scale;
    image.height = (atlas.height + scale - 1) / scale;
    image.pixels.assign(size_t(image.width) * image.height * 4, 0);
    for (size_t i = 3; i < image.pixels.size(); i += 4)
        image.pixels[i] = 255;
    auto paint = [&](uint32_t x, uint32_t y, uint8_t r, uint8_t g, uint8_t b)
    {
        uint8_t* p = &image.pixels[(size_t(y / scale) * image.width + x / scale) * 4];
        if (p[0] == 255 && p[1] == 40)
            return; // an overlap stays red
        p[0] = r;
        p[1] = g;
        p[2] = b;
    };
    for (size_t i = 0; i < atlas.texels.size(); ++i)
        paint(atlas.texels.place(i).x, atlas.texels.place(i).y, 110, 110, 110);
    for (const glm::uvec2& t : report.overlaps)
        paint(t.x, t.y, 255, 40, 40);
    io::write_png(path, image);
}

// Light beyond any physical value is refused before the work, naming the light; anything below it is stored
// (the asset's halves carry a scale, io/half_scale.h). The bound is reported.
LightBound check_light_bound(const LightmapLights& l, const std::vector<io::Material>& materials,
                             const io::Mesh& mesh, const std::filesystem::path& scene)
{
    LightBound bound;
    try
    {
        bound = lightmap_light_bound(l, materials, mesh);
    }
    catch (const std::invalid_argument& e)
    {
        throw io::FormatError(scene.string() + ": " + e.what());
    }
    const LightBoundSource* largest = bound.largest();
    if (largest && !(bound.total <= kMaxPlausibleIrradiance))
    {
        char text[400];
        std::snprintf(text, sizeof text,
                      ": the lights give an irradiance of up to %.4g (%s: %.4g), beyond any physical light "
                      "(%.0e W/m^2 or lux, 10^5 times direct sunlight); check the light's units",
                      bound.total, largest->name.c_str(), largest->irradiance, kMaxPlausibleIrradiance);
        throw io::FormatError(scene.string() + text);
    }
    return bound;
}

// How the light probes are placed, as hemi-bake's --probes says it: "NX,NY,NZ", "auto:N", "points" (N
// points) or "gltf"; empty for none.
std::string probes_named(const LightmapFileOptions& o)
{
    if (o.probes != glm::uvec3(0))
        return std::to_string(o.probes.x) + "," + std::to_string(o.probes.y) + "," +
               std::to_string(o.probes.z);
    if (o.probe_budget)
        return "auto:" + std::to_string(o.probe_budget);
    if (!o.probe_points.empty())
        return "points (" + std::to_string(o.probe_points.size()) + ")";
    return o.gltf_probes ? "gltf" : "";
}

} // namespace

LightmapBakeSummary bake_lightmap_file(const std::filesystem::path& scene_path,
                                       const std::filesystem::path& asset_path,
                                       const LightmapFileOptions& options,
                                       const std::function<void(const LightmapProgress&)>& progress)
{
    const auto t0 = std::chrono::steady_clock::now();
    const uint64_t resident_at_start = io::resident_memory(); // what the scene adds is counted from here
    // Where the time goes, stage by stage (the JSON's "stage_seconds").
    std::vector<std::pair<std::string, double>> stages;
    auto stage_start = t0;
    auto stage_done = [&](const char* stage)
    {
        const auto now = std::chrono::steady_clock::now();
        stages.emplace_back(stage, std::chrono::duration<double>(now - stage_start).count());
        stage_start = now;
        if (options.on_stage)
            options.on_stage(stage);
    };
    LightmapFileOptions o = options;
    if (o.outputs.empty())
        throw std::invalid_argument("no lightmap outputs asked for");
    for (const std::string& name : o.outputs)
    {
        if (name == "shadowmask")
            throw std::invalid_argument(
                "the shadowmask is not an output to ask for: a bake with mixed lights "
                "makes it (--sun-mode mixed, or a glTF light's extras.hemi_bake_mode)");
        lightmap_output_size(name); // throws for an unknown name, listing the known ones
    }
    if (o.texel_size < 0.0f || !std::isfinite(o.texel_size))
        throw std::invalid_argument("the texel size must be positive (world units)");
    if (o.denoise && (o.denoise_passes < 1 || o.denoise_passes > 10))
        throw std::invalid_argument("--denoise-passes must be 1 to 10, not " +
                                    std::to_string(o.denoise_passes));
    if (o.probes != glm::uvec3(0) && (o.probes.x == 0 || o.probes.y == 0 || o.probes.z == 0))
        throw std::invalid_argument("--probes needs at least one probe along each axis");
    const int probe_kinds =
        (o.probes != glm::uvec3(0)) + (o.probe_budget != 0) + !o.probe_points.empty() + o.gltf_probes;
    if (probe_kinds > 1)
        throw std::invalid_argument("light probes on a grid, placed automatically, at given points or at the "
                                    "glTF's nodes: one of them, not " +
                                    std::to_string(probe_kinds));
    if (o.probe_budget > (1u << 20))
        throw std::invalid_argument("a probe budget of " + std::to_string(o.probe_budget) +
                                    " is not in [1, 2^20]");
    if (o.probe_points.size() > size_t(1) << 24)
        throw std::invalid_argument(std::to_string(o.probe_points.size()) + " probe points: at most 2^24");
    for (const glm::vec3& p : o.probe_points)
        if (!std::isfinite(p.x + p.y + p.z))
            throw std::invalid_argument("a probe point is not finite");
    if (probe_kinds && (o.probe_rays < 1 || o.probe_rays > (1 << 20)))
        throw std::invalid_argument("rays per probe " + std::to_string(o.probe_rays) +
                                    " is not in [1, 2^20]");
    if (o.probe_depth > io::kMaxProbeDepthResolution)
        throw std::invalid_argument("--probe-depth " + std::to_string(o.probe_depth) + " is not in [0, " +
                                    std::to_string(io::kMaxProbeDepthResolution) + "]");
    if (o.reflection_probes.size() > io::kMaxReflectionProbes)
        throw std::invalid_argument(std::to_string(o.reflection_probes.size()) +
                                    " reflection probes: at most " +
                                    std::to_string(io::kMaxReflectionProbes));
    if (!o.reflection_probes.empty())
    {
        const int side = int(std::lround(std::sqrt(double(std::max(o.reflection.rays, 0)))));
        if (o.reflection.rays < 1 || o.reflection.rays > 4096 || side * side != o.reflection.rays)
            throw std::invalid_argument("--reflection-rays must be a square number from 1 to 4096, not " +
                                        std::to_string(o.reflection.rays));
        EnvmapBakeOptions envmap;
        envmap.size = o.reflection.size;
        envmap.exponents = o.reflection.exponents;
        check_envmap_options(envmap);
        for (const ReflectionProbePlacement& p : o.reflection_probes)
            if (!std::isfinite(p.centre.x + p.centre.y + p.centre.z + p.box_min.x + p.box_min.y +
                               p.box_min.z + p.box_max.x + p.box_max.y + p.box_max.z) ||
                (p.box_min != p.box_max &&
                 !(p.box_min.x < p.box_max.x && p.box_min.y < p.box_max.y && p.box_min.z < p.box_max.z)))
                throw std::invalid_argument("a reflection probe's centre and box must be finite, the box's "
                                            "minimum below its maximum along every axis");
    }
    if (o.bake.checkpoint.empty())
        o.bake.checkpoint = checkpoint_path(asset_path);
    // Under a distribution, the other ranks only compute: rank 0 checks and writes every output.
    const bool leader = !o.bake.distribution || o.bake.distribution->leader();
    // Fail fast: every output's folder before the scene is even read.
    if (leader)
    {
        io::check_writable(asset_path);
        io::check_writable(o.bake.checkpoint);
        io::check_temporary(lightmap_tile_path(asset_path)); // a bake in tiles
        io::check_temporary(asset_path.string() + ".spool"); // the asset's outputs as they are made
        if (!o.uv_report.empty())
            io::check_writable(o.uv_report);
        if (!o.exr_dir.empty())
            for (const std::string& name : o.outputs)
                io::check_writable(lightmap_exr_path(o.exr_dir, asset_path, name));
    }
    // One job per output: a second bake to the same asset (its checkpoint, tiles and spool are named after
    // it) is refused, naming the first.
    std::optional<io::OutputLock> lock;
    if (leader)
        lock.emplace(asset_path);
    // An EXR holds the whole atlas as one image: read_exr's and most tools' limit.
    if (!o.exr_dir.empty() && (o.width > 16384 || o.height > 16384))
        throw std::invalid_argument("--exr-dir writes each output as one image of the whole atlas, at most "
                                    "16384 a side; the atlas is " +
                                    std::to_string(o.width) + "x" + std::to_string(o.height) +
                                    " (the asset stores it in pages)");

    io::GltfScene scene = io::read_gltf(scene_path);
    if (o.gltf_probes && scene.light_probes.empty())
        throw io::FormatError(scene_path.string() +
                              ": --probes gltf: the scene has no light probe nodes (nodes "
                              "named " +
                              std::string(io::kLightProbeNodePrefix) + "...)");
    LightmapBakeSummary summary;
    o.lights.scene_to_world = glm::mat3(math::gltf_to_world());
    o.lights.punctual = scene.lights; // in the mesh's (scene) space already
    // The mixed lights' shadowmask channels, before anything is baked (a fifth overlapping light is refused).
    std::vector<ShadowmaskChannel> mixed_channels;
    try
    {
        mixed_channels = shadowmask_channels(o.lights);
    }
    catch (const std::invalid_argument& e)
    {
        throw io::FormatError(scene_path.string() + ": " + e.what());
    }
    if (o.unwrap)
    {
        UnwrapOptions u;
        u.texel_size = o.texel_size;
        u.width = o.width;
        u.height = o.height;
        UnwrapResult r;
        try
        {
            r = unwrap_lightmap(scene.mesh, u);
        }
        catch (const std::invalid_argument& e)
        {
            throw io::FormatError(scene_path.string() + ": --unwrap: " + e.what());
        }
        summary.unwrapped_charts = r.charts;
        summary.unwrap_texel_size = r.texel_size;
        o.width = r.width;
        o.height = r.height;
    }
    else if (scene.mesh.uvs1.size() != scene.mesh.vertex_count())
        throw io::FormatError(
            scene_path.string() +
            ": has no lightmap UVs (TEXCOORD_1): give every mesh a second UV set laid out for the "
            "lightmap (Blender: a second UV map, e.g. from Lightmap Pack), or let hemi make "
            "planar charts with --unwrap");
    // Every texture is decoded once, now: a corrupt one stops the bake before it starts.
    std::optional<LightmapSurfaces> surfaces;
    try
    {
        surfaces.emplace(scene.mesh, scene.materials, scene.images, scene.primitives);
    }
    catch (const std::bad_alloc&)
    {
        throw;
    }
    catch (const std::exception& e)
    {
        throw io::FormatError(scene_path.string() + ": " + e.what());
    }
    stage_done("scene"); // read, unwrapped, its textures decoded
    summary.triangles = scene.mesh.indices.size() / 3;
    summary.materials = scene.materials.size();
    summary.primitives = scene.primitives.size();
    summary.images = scene.images.size();
    summary.tangents_generated = scene.tangents_generated;
    summary.warnings = scene.warnings;
    std::vector<TriangleRange> ranges;
    for (size_t i = 0; i < scene.primitives.size(); ++i)
    {
        const io::Primitive& p = scene.primitives[i];
        const uint32_t material = p.material;
        const std::string name =
            material < scene.materials.size() && !scene.materials[material].name.empty()
                ? "primitive " + std::to_string(i) + " (" + scene.materials[material].name + ")"
                : "primitive " + std::to_string(i);
        ranges.push_back({p.first_index / 3, p.index_count / 3, name});
    }

    // The atlas size: given, or from the texel size (the square atlas whose texels cover that much of the
    // scene on average), else 512.
    uint32_t w = o.width, h = o.height;
    if (w == 0 || h == 0)
    {
        w = h = 512;
        if (o.texel_size > 0.0f)
        {
            double world = 0.0, uv = 0.0;
            const io::Mesh& m = scene.mesh;
            for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
            {
                const glm::dvec3 a(m.positions[m.indices[t]]), b(m.positions[m.indices[t + 1]]),
                    c(m.positions[m.indices[t + 2]]);
                world += 0.5 * glm::length(glm::cross(b - a, c - a));
                const glm::dvec2 p(m.uvs1[m.indices[t]]), q(m.uvs1[m.indices[t + 1]]),
                    r(m.uvs1[m.indices[t + 2]]);
                uv += 0.5 * std::abs((q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x));
            }
            const double side = uv > 0.0 ? std::sqrt(world / uv) / double(o.texel_size) : 512.0;
            w = h = uint32_t(std::clamp(std::ceil(side), 16.0, 8192.0));
        }
    }
    summary.width = w;
    summary.height = h;
    // Memory before the atlas is made, from the blocks the triangles touch (io::BlockGrid): the bake and
    // the asset store those, so a small scene in a large atlas costs what its texels cost.
    uint64_t coefficients = 0, largest_output = 0;
    for (const std::string& name : o.outputs)
    {
        coefficients += uint64_t(lightmap_output_size(name)) * 3;
        largest_output = std::max<uint64_t>(largest_output, uint64_t(lightmap_output_size(name)) * 3);
    }
    // With mixed lights, each texel's shadowmask and mixed direct light, through the whole bake (in tiles,
    // a tile's, and the rest in the tile file).
    const uint64_t mixed_bytes = mixed_channels.empty() ? 0 : kMixedBytesPerCoveredTexel;
    // The budget: --memory-budget, else what the machine has free (io::available_memory, which
    // HEMI_MEMORY_BUDGET and the process's limits lower); 0 when neither is known.
    const uint64_t budget = o.memory_budget ? o.memory_budget : io::available_memory();
    summary.memory_budget = budget;
    const std::string atlas_text = std::to_string(w) + "x" + std::to_string(h) + " lightmap";
    const uint64_t exr_bytes =
        o.exr_dir.empty() ? 0 : uint64_t(w) * h * largest_output * kExrBytesPerCoefficient;
    uint64_t slots = 0, output_slots = 0, seam_slots = 0;
    try
    {
        const io::BlockGrid touched = lightmap_blocks(scene.mesh, w, h);
        slots = touched.slots();
        output_slots = dilated_slots(touched, o.dilate);
        // The blocks the seams read, which a bake in tiles holds whole while it stitches each output: within
        // a block of those the seams read among the touched ones (a seam's points lie in touched texels).
        seam_slots = std::min<uint64_t>(
            output_slots, 9 * lightmap_seam_blocks(find_lightmap_seams(scene.mesh), touched).slots());
    }
    catch (const std::invalid_argument& e)
    {
        throw io::FormatError(scene_path.string() + ": " + e.what());
    }
    // The peak is the larger of two stages': the passes (the atlas's records, the bounces' map, the sums and
    // the pass in memory, or in tiles one tile of them; --denoise's filter after them, on the whole atlas or
    // in bands of rows) and the outputs (the texels' places, the float map of the output being made, the sums
    // when in memory).
    const uint64_t per_texel =
        kLightmapBytesPerCoveredTexel + mixed_bytes + (o.denoise ? kDenoiseBytesPerCoveredTexel : 0);
    const uint64_t per_tile_texel =
        o.denoise ? std::max(kTileBytesPerTexel + kTileNoiseBytesPerTexel, kDenoiseBandBytesPerTexel)
                  : kTileBytesPerTexel;
    // --denoise in tiles: a band holds at least one row and the rows its result depends on either side.
    const uint64_t least_band =
        o.denoise
            ? uint64_t(w) * uint64_t(3 + 4 * ((int64_t(1) << o.denoise_passes) - 1) + 2 * o.denoise_passes)
            : 0;
    const uint64_t sums_per_texel = kTileBytesPerTexel / 2 + (o.denoise ? kTileNoiseBytesPerTexel / 2 : 0);
    // With mixed lights the shadowmask's float maps (4 x RGB) stay beside every output's until the asset is
    // written.
    const uint64_t output_map_bytes =
        output_slots * (largest_output * kLightmapBytesPerLargestCoefficient + kDilationBytesPerSlot +
                        (mixed_channels.empty() ? 0 : 12 * kLightmapBytesPerLargestCoefficient)) +
        exr_bytes;
    // The probes cannot be tiled: they count in full against the budget, on top of either stage.
    // (In double first: a grid past 2^24 probes, which the probe bake refuses, must not wrap here.)
    // Automatic placement holds its candidates (ProbePlacementOptions::candidates_per_probe open ones a probe
    // of the budget, and up to twice as many while it tells the open ones from the others).
    const uint64_t probe_count =
        uint64_t(std::min(double(o.probes.x) * o.probes.y * o.probes.z, double(uint64_t(1) << 40))) +
        uint64_t(o.probe_budget) * 2 * ProbePlacementOptions{}.candidates_per_probe + o.probe_points.size() +
        (o.gltf_probes ? scene.light_probes.size() : 0);
    // Reflection probes are held whole too: each its gathered image (4 s x 2 s RGBA floats) while it is made,
    // then its mirror chain, glossy and diffuse maps (at most 2 s^2 RGB floats each, the chain 4/3 of that).
    const uint64_t reflection_side = o.reflection_probes.empty() ? 0 : o.reflection.size;
    const uint64_t reflection_bytes =
        reflection_side * reflection_side *
        (128 + uint64_t(o.reflection_probes.size()) * 24 * (2 + o.reflection.exponents.size()));
    const uint64_t probe_bytes =
        probe_count * (kProbeBytes + uint64_t(o.probe_depth) * o.probe_depth * kProbeDepthBytesPerTexel) +
        reflection_bytes;
    // What the bake holds besides the stages counted below: the ray tracer's BVH and, under a budget, what
    // the caller spent of it before (LightmapFileOptions::memory_held: hemi-bake's code and libraries) and
    // the scene just read (io::resident_memory since the start: the mesh, its textures and what reading
    // them left resident; issue 41 found every --memory-budget's peak ~10 MiB over it without these). The
    // memory the machine has free (io::available_memory) is what is left beside all the process holds.
    const uint64_t resident_now = io::resident_memory();
    const uint64_t held =
        (o.memory_budget
             ? o.memory_held + (resident_now > resident_at_start ? resident_now - resident_at_start : 0)
             : 0) +
        uint64_t(summary.triangles) * kEmbreeBytesPerTriangle + kTracerBytes +
        uint64_t(std::max(1u, std::thread::hardware_concurrency())) * kTracerBytesPerThread;
    if (budget != 0 && probe_bytes != 0 && held < budget && held + probe_bytes > budget)
        throw io::FormatError(scene_path.string() + ": --probes " + probes_named(o) + ": " +
                              std::to_string(probe_count) +
                              (o.probe_budget ? " light probes (the placement's candidates) need about "
                                              : " light probes need about ") +
                              io::format_bytes(probe_bytes) + " of memory, held whole, beside the " +
                              io::format_bytes(held) + " the process and the scene's ray tracer hold, but " +
                              (o.memory_budget ? "--memory-budget is " : "only ") + io::format_bytes(budget) +
                              (o.memory_budget ? "" : " is available") + ": ask for fewer probes");
    // One band of the bounce map's dilation (lightmap_bake.cpp: at most 2^20 slots and at least a tile's or
    // 1024, or three block rows, each slot's float, state and chart), or nothing without bounces.
    const auto bounce_band_bytes = [&](uint64_t tile)
    {
        const uint64_t row_slots =
            uint64_t((w + io::BlockGrid::kSize - 1) / io::BlockGrid::kSize) * io::BlockGrid::kTexels;
        const uint64_t band =
            std::max(std::min<uint64_t>(uint64_t(1) << 20, std::max<uint64_t>(tile, 1024)) + 4 * row_slots,
                     5 * row_slots);
        return o.bake.bounces > 0 ? std::min(band, slots) * (12 + kDilationBytesPerSlot) : 0;
    };
    // The rasteriser whole (band 0) or in bands of block rows of at most `band` slots (at least a row), each
    // with the block rows either side.
    const uint64_t raster_row_slots =
        uint64_t((w + io::BlockGrid::kSize - 1) / io::BlockGrid::kSize) * io::BlockGrid::kTexels;
    const uint64_t least_raster_band = raster_row_slots;
    // The two caches of pages of the records and slot indices when they are in files (PagedStore): at most
    // the arrays themselves.
    const uint64_t cache_items =
        (kPageCachePages + std::max(1u, std::thread::hardware_concurrency()) * PagedStore::kLocalPages) *
        PagedStore::kPageItems;
    const auto page_cache_bytes = [&](uint64_t texels)
    {
        return std::min(cache_items, texels) * kTexelRecordBytes +
               std::min(cache_items, slots) * kSlotTexelBytes;
    };
    const auto raster_band_bytes = [&](uint64_t band, bool paged)
    {
        if (band == 0)
            return slots * kRasterBytesPerSlot;
        return (paged ? 0 : slots * kSlotTexelBytes) + // (paged: nothing is read while it rasterises)
               std::min(slots, std::max(band, raster_row_slots) + 2 * raster_row_slots) *
                   kRasterTableBytesPerSlot;
    };
    // An output's texels are read 65,536 at a time: their sums (156 bytes) and the output's values.
    const auto read_chunk_bytes = [&](uint64_t texels)
    {
        return std::min<uint64_t>(texels, uint64_t(1) << 16) *
               (156 + largest_output * kLightmapBytesPerLargestCoefficient);
    };
    const auto whole_bytes = [&](uint64_t texels)
    {
        return held + probe_bytes +
               std::max({slots * kRasterBytesPerSlot + texels * kTexelRecordBytes,
                         slots * kLightmapBytesPerSlot + bounce_band_bytes(texels) + texels * per_texel,
                         output_map_bytes + read_chunk_bytes(texels) +
                             texels * (kPlaceBytesPerTexel + sums_per_texel + mixed_bytes)});
    };
    // In tiles (without --exr-dir) an output is made band by band (LightmapOutputBands): one band's floats
    // and dilation (at least a tile's texels or 4096, and a block row with the rows around it), and the
    // seams' blocks; the shadowmask, with mixed lights, too, after them.
    const auto tiled_output_bytes = [&](uint64_t texels, uint64_t tile)
    {
        if (exr_bytes)
            return output_map_bytes;
        const uint64_t row_slots =
            uint64_t((w + io::BlockGrid::kSize - 1) / io::BlockGrid::kSize) * io::BlockGrid::kTexels;
        const uint64_t halo_rows =
            (uint64_t(std::max(o.dilate, 0)) + io::BlockGrid::kSize - 1) / io::BlockGrid::kSize;
        const uint64_t band =
            std::min(output_slots, std::max<uint64_t>(tile, 4096) + (2 * halo_rows + 1) * row_slots);
        // (and the texels' values read 65,536 at a time: their sums, 156 bytes, and the output's values; the
        // shadowmask, with mixed lights, is made the same way after the outputs: 12 floats a slot)
        const uint64_t floats = std::max<uint64_t>(largest_output, mixed_channels.empty() ? 0 : 12);
        return band * (floats * kLightmapBytesPerLargestCoefficient + kDilationBytesPerSlot) +
               read_chunk_bytes(texels) + seam_slots * floats * kLightmapBytesPerLargestCoefficient;
    };
    // `paged`: the atlas's records and slot indices in pages of files.
    const auto tiled_bytes = [&](uint64_t texels, uint64_t tile, bool paged)
    {
        const uint64_t records = paged ? page_cache_bytes(texels) : texels * kTexelRecordBytes;
        const uint64_t passes =
            slots * (paged ? kPagedLightmapBytesPerSlot : kLightmapBytesPerSlot) + bounce_band_bytes(tile) +
            texels * (paged ? kPagedTiledBytesPerCoveredTexel : kTiledBytesPerCoveredTexel) +
            (paged ? page_cache_bytes(texels) : 0) +
            std::max(tile, std::min(texels, least_band)) * per_tile_texel + tile * mixed_bytes;
        // (the mixed lights' values read from the tile file 65,536 at a time)
        return held + probe_bytes +
               std::max({raster_band_bytes(least_raster_band, paged) + records, passes,
                         tiled_output_bytes(texels, tile) +
                             (paged ? page_cache_bytes(texels) : texels * kPlaceBytesPerTexel) +
                             std::min<uint64_t>(texels, uint64_t(1) << 16) * mixed_bytes});
    };
    const auto check_fits = [&](uint64_t texels, const std::string& what)
    {
        const uint64_t whole = whole_bytes(texels);
        if (budget == 0 || whole <= budget)
            return;
        const uint64_t least_tile = std::min<uint64_t>(texels, kMinTileTexels);
        const uint64_t least =
            std::min(tiled_bytes(texels, least_tile, false), tiled_bytes(texels, least_tile, true));
        if (least > budget)
            throw io::FormatError(
                what + ": needs about " + io::format_bytes(whole) + " of memory (" + io::format_bytes(least) +
                " in tiles of " + std::to_string(kMinTileTexels) + " texels" +
                (least < tiled_bytes(texels, least_tile, false) ? ", the atlas's records on disk" : "") +
                (o.denoise ? ", --denoise's filter in bands of rows" : "") + "; of either, " +
                io::format_bytes(held) + " the process, the scene and its ray tracer hold), but " +
                (o.memory_budget ? "--memory-budget is " : "only ") + io::format_bytes(budget) +
                (o.memory_budget ? "" : " is available"));
    };
    check_fits(slots, scene_path.string() + ": a " + atlas_text + " whose triangles touch " +
                          std::to_string(slots / io::BlockGrid::kTexels) + " blocks of 8x8 texels, with " +
                          std::to_string(coefficients) +
                          " coefficients per texel (--size, --texel-size, --bases" +
                          (exr_bytes ? ", --exr-dir" : "") + ")");
    LightmapUvReport report;
    // Overlapping UVs are resolved towards the faces a viewer can reach, with the bake's idea of a back.
    std::vector<uint8_t> double_sided(summary.triangles, 0);
    for (uint32_t t = 0; t < summary.triangles; ++t)
        double_sided[t] = surfaces->double_sided(t);
    // The atlas's records and slot indices go to pages of files beside the asset (LightmapAtlasStorage) when
    // the bake does not fit in memory and, kept in memory, they would leave room only for tiles of fewer than
    // kPagedBelowTileTexels texels (counted with the slots as the texels, which they bound).
    const uint64_t usable_now = budget - budget / 8;
    const bool paged =
        budget != 0 && whole_bytes(slots) > usable_now &&
        tiled_bytes(slots, std::min<uint64_t>(slots, kPagedBelowTileTexels), false) > usable_now;
    summary.paged_records = paged;
    // The rasteriser whole where it fits beside the records (the covered texels at most the slots), else in
    // the largest bands of block rows that do (check_fits has made sure that a row's does).
    uint64_t raster_band = 0;
    const uint64_t records =
        held + probe_bytes + (paged ? page_cache_bytes(slots) : slots * kTexelRecordBytes);
    if (budget != 0 && (paged || records + raster_band_bytes(0, false) > usable_now))
    {
        const uint64_t fixed =
            records + (paged ? 0 : slots * kSlotTexelBytes) + 2 * raster_row_slots * kRasterTableBytesPerSlot;
        raster_band = std::max(least_raster_band,
                               fixed < usable_now ? (usable_now - fixed) / kRasterTableBytesPerSlot : 0);
        if (raster_band >= slots)
            raster_band = 0;
    }
    summary.raster_band_slots = raster_band;
    // Overlapping UVs' candidates may take what the budget leaves beside the rasteriser's tables.
    const uint64_t raster_bytes = records + raster_band_bytes(raster_band, paged);
    const uint64_t overlap_budget = budget == 0 ? 0 : budget > raster_bytes ? budget - raster_bytes : 1;
    LightmapAtlas atlas;
    try
    {
        LightmapAtlasStorage storage;
        if (paged)
            storage.directory = std::filesystem::absolute(asset_path).parent_path();
        atlas = rasterize_lightmap(scene.mesh, w, h, report, ranges, double_sided, overlap_budget,
                                   size_t(raster_band), storage);
    }
    catch (const std::length_error& e)
    {
        throw io::FormatError(scene_path.string() + ": " + e.what() + " (" +
                              (o.memory_budget ? "--memory-budget is " : "only ") + io::format_bytes(budget) +
                              (o.memory_budget ? "" : " is available") +
                              "); give each instance its own lightmap UVs, or bake with --unwrap");
    }
    stage_done("atlas");
    summary.uv_report = report;
    if (!o.uv_report.empty() && leader)
        write_uv_report(o.uv_report, atlas, report);
    if (!report.ok())
        throw io::FormatError(scene_path.string() + ": " + report.problems.front());
    if (o.strict_uv && report.overlapping_texels)
        throw io::FormatError(
            scene_path.string() + ": " + std::to_string(report.overlapping_texels) +
            " lightmap texel(s) lie inside two or more triangles (e.g. triangles " +
            std::to_string(report.overlap_example[0]) + " and " + std::to_string(report.overlap_example[1]) +
            "), refused (--strict-uv): lightmap UVs (TEXCOORD_1) must not overlap; re-unwrap "
            "the scene or bake with --unwrap");
    if (atlas.texels.empty())
        throw io::FormatError(
            scene_path.string() + ": no texel of the " + std::to_string(w) + "x" + std::to_string(h) +
            " lightmap is covered by a triangle (" + std::to_string(report.triangles) +
            " triangle(s): " + std::to_string(report.outside) + " with lightmap UVs outside [0, 1], " +
            std::to_string(report.degenerate) + " of zero area in UV space, " +
            std::to_string(report.zero_area) +
            " of zero area in space); the lightmap would be empty: lay out TEXCOORD_1 inside [0, 1] "
            "or bake with --unwrap");
    const uint64_t covered = atlas.texels.size();
    check_fits(covered, scene_path.string() + ": a " + atlas_text + " with " + std::to_string(covered) +
                            " covered texels");
    // In tiles when the whole atlas does not fit: the largest tile the budget leaves room for (check_fits has
    // made sure that one of kMinTileTexels does).
    // At most covered - 1: a tile of every texel would keep the sums in memory. A bake in tiles that was
    // stopped resumes in tiles, whatever memory is free now (its checkpoint holds no sums).
    uint32_t tile_texels = 0;
    const bool tiles_to_resume =
        std::filesystem::exists(o.bake.checkpoint) && std::filesystem::exists(lightmap_tile_path(asset_path));
    // The choice leaves an eighth of the budget beside the estimate: the allocator's arenas and the threads'
    // timing move the peak (the post scene at 512^2 under 64 MiB, in tiles the estimate put at 64 MiB,
    // peaked at 61.4 MiB alone and at 68.1 MiB beside another test process).
    const uint64_t usable = budget - budget / 8;
    if (covered > 1 && ((budget != 0 && whole_bytes(covered) > usable) || tiles_to_resume))
    {
        const uint64_t fixed = tiled_bytes(covered, 0, paged);
        const uint64_t room = budget == 0 ? covered : fixed < usable ? (usable - fixed) / per_tile_texel : 0;
        tile_texels = uint32_t(std::min<uint64_t>(std::max<uint64_t>(room, kMinTileTexels), covered - 1));
    }
    // Records paged for an atlas whose covered texels then fit in memory after all (paged was decided from
    // the slots, which bound them): brought back, since a bake in memory reads them at random.
    if (paged && tile_texels == 0)
    {
        atlas.texels.keep_in_memory();
        atlas.slot_texel = atlas.slot_texel.in_memory();
        summary.paged_records = false;
    }
    summary.tile_texels = tile_texels;
    for (const std::string& warning : report.warnings)
        summary.warnings.push_back(warning);
    // The bake, the asset and hemi's runtime follow the covered texels; images for other renderers (hemi-bake
    // export's) still cover the whole atlas: say so when most of it is empty.
    if (uint64_t(atlas.texels.size()) * 20 < uint64_t(w) * h && uint64_t(w) * h > (uint64_t(1) << 20))
        summary.warnings.push_back(std::to_string(atlas.texels.size()) + " of the " + atlas_text + "'s " +
                                   std::to_string(uint64_t(w) * h) +
                                   " texels are covered (under 5%): the bake and the asset store only the "
                                   "8x8 blocks that hold texels and hemi's runtime only the 64x64 pages, but "
                                   "images for other renderers (hemi-bake export) cover the whole atlas; a "
                                   "smaller --size or a larger --texel-size gives the same density for less");

    summary.lights = scene.lights.size();
    summary.irradiance_bound = check_light_bound(o.lights, scene.materials, scene.mesh, scene_path).total;
    LightmapBakeOptions bake_options = o.bake;
    bake_options.keep_noise = o.denoise;
    bake_options.tile_texels = tile_texels;
    bake_options.tile_file = lightmap_tile_path(asset_path);
    Distribution& dist = o.bake.distribution ? *o.bake.distribution : local_distribution();
    const std::vector<uint64_t> items_before = dist.items_by_rank();
    LightmapSh sh = bake_lightmap_sh(scene.mesh, atlas, o.lights, bake_options, &*surfaces, progress);
    summary.texels_by_rank = dist.items_by_rank();
    for (size_t r = 0; r < summary.texels_by_rank.size() && r < items_before.size(); ++r)
        summary.texels_by_rank[r] -= items_before[r];
    // The outputs are shared among the ranks when every rank holds the bake's sums (not in tiles: those are
    // on rank 0's disk) and nothing else needs them whole on rank 0 (--exr-dir writes there; --denoise
    // filters there): each rank makes every ranks()-th output and sends it to rank 0, which writes the asset.
    const bool share_outputs = dist.ranks() > 1 && !sh.irradiance.empty() && o.exr_dir.empty() && !o.denoise;
    if (!leader && !share_outputs)
        return summary; // the texels are on rank 0: its outputs, its probes
    stage_done("bake"); // the sample points' search and every pass
    summary.tiles = sh.tiles_count;
    if (o.denoise)
    {
        // In memory, or in tiles band by band in the tile file (counted in the budget above).
        LightmapDenoiseOptions d;
        d.iterations = o.denoise_passes;
        // A band as large as the budget left room for: a tile, or one row and the rows around it it depends
        // on, whichever is larger (both counted above).
        d.tile_texels = size_t(std::max<uint64_t>(tile_texels, least_band));
        summary.denoised_texels = denoise_lightmap(scene.mesh, atlas, sh, d).texels;
    }
    if (o.denoise)
        stage_done("denoise");
    summary.rays = sh.rays;
    summary.pushed = sh.pushed;
    summary.invalid = sh.invalid;
    summary.trace_seconds = sh.trace_seconds;
    summary.resumed = sh.resumed;
    summary.checkpoint_error = sh.checkpoint_error;

    io::LightmapAsset asset;
    asset.mesh = scene.mesh;
    asset.materials = scene.materials;
    asset.images = scene.images;
    asset.primitives = scene.primitives;
    asset.width = w;
    asset.height = h;
    asset.rays = uint32_t(o.bake.rays);
    asset.bounces = uint32_t(o.bake.bounces);
    asset.seed = o.bake.seed;
    asset.covered_texels = uint32_t(atlas.texels.size());
    if (probe_kinds && leader)
    {
        LightmapBakeOptions probe_options = o.bake;
        probe_options.rays = o.probe_rays;
        if (o.probes != glm::uvec3(0))
        {
            asset.probes = probe_grid(scene.mesh, o.probes);
            asset.probes.depth_resolution = o.probe_depth;
            bake_light_probes(asset.probes, scene.mesh, atlas, sh, o.lights, probe_options, &*surfaces);
        }
        else if (o.probe_budget)
        {
            ProbePlacementOptions placement;
            placement.budget = o.probe_budget;
            placement.depth_resolution = o.probe_depth;
            ProbePlacementReport placed;
            asset.probes = place_light_probes(scene.mesh, atlas, sh, o.lights, probe_options, &*surfaces,
                                              placement, &placed);
            summary.probe_candidates = placed.candidates;
            summary.open_probe_candidates = placed.open;
            summary.probe_placement_error = placed.error;
        }
        else
            asset.probes = bake_probes_at(o.gltf_probes ? scene.light_probes : o.probe_points, o.probe_depth,
                                          scene.mesh, atlas, sh, o.lights, probe_options, &*surfaces);
        summary.probes = asset.probes.irradiance.size();
        for (uint8_t v : asset.probes.valid)
            summary.invalid_probes += !v;
    }
    if (!o.reflection_probes.empty() && leader)
    {
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (const glm::vec3& v : scene.mesh.positions)
        {
            lo = glm::min(lo, v);
            hi = glm::max(hi, v);
        }
        for (const ReflectionProbePlacement& placed : o.reflection_probes)
        {
            io::ReflectionProbe probe;
            probe.centre = placed.centre;
            // The scene's bounds, a little wider (a flat level's box is flat along one axis).
            const bool whole = placed.box_min == placed.box_max;
            const glm::vec3 pad(1e-3f * glm::length(hi - lo) + 1e-4f);
            probe.box_min = whole ? lo - pad : placed.box_min;
            probe.box_max = whole ? hi + pad : placed.box_max;
            probe.maps = bake_reflection_probe(scene.mesh, atlas, sh, o.lights, &*surfaces, placed.centre,
                                               o.reflection);
            asset.reflections.push_back(std::move(probe));
        }
        summary.reflection_probes = asset.reflections.size();
    }
    if (!asset.probes.empty() || !asset.reflections.empty())
        stage_done("probes");
    // The passes and the probes are done: the outputs need only each texel's place in the atlas and its
    // chart, which they read from its records (in memory, or in pages of a file), not the slots' indices.
    atlas.slot_texel = {};
    // Plain is the same in any tangent frame; the other outputs are stitched and measured only along the
    // seams whose two sides' frames agree (LightmapSeam::frames_agree).
    const std::vector<LightmapSeam> seams = find_lightmap_seams(scene.mesh);
    std::vector<LightmapSeam> framed;
    for (const LightmapSeam& seam : seams)
        if (seam.frames_agree)
            framed.push_back(seam);
    summary.seams = seams.size();
    summary.seams_across_frames = seams.size() - framed.size();
    const auto seams_of = [&](const std::string& name) -> const std::vector<LightmapSeam>&
    { return name == "plain" || name == "shadowmask" ? seams : framed; };
    // One output at a time: made, stitched, measured, encoded into the asset's half floats (and its EXR
    // written), then freed, so that the bake holds one output's float maps, not all of them. One
    // factorisation per set of seams, shared by the outputs (they share the grid); the ringing-free lift runs
    // again on the texels the stitch changed, since least squares does not keep a texel's function
    // non-negative.
    std::optional<LightmapSeamStitch> all, along_frames;
    // What the summary says of one output (sent to rank 0 with it when the ranks share the outputs).
    struct OutputReport
    {
        uint64_t adjusted = 0, blocks = 0, stitched_texels = 0, clamped = 0;
        double before_mean = 0.0, before_p95 = 0.0, after_mean = 0.0, after_p95 = 0.0;
        uint8_t stitched = 0, has_clamped = 0;
        int32_t scale_exponent = 0; // the power of two the output's halves are times (io/half_scale.h)
    };
    // Stitches `maps` (an output's, or its seams' blocks) along the output's seams with `stitch`, keeps
    // irradiance non-negative and the ringing-free lift where asked, and says so in `made`.
    const auto stitch_output = [&](const std::string& name, io::BlockMaps& maps,
                                   const LightmapSeamStitch& stitch, OutputReport& made)
    {
        const uint32_t k = maps.k;
        made.stitched = 1;
        made.stitched_texels = stitch.slots().size();
        stitch.apply(maps);
        if (name == "plain" || name == "rnm")
        {
            // Irradiance is never negative; least squares can swing a texel that only a seam's lookups
            // read (a gutter texel between a bright and a dark side) below 0. Such values go to 0, and
            // that seam agrees a little less.
            size_t clamped = 0;
            for (const size_t slot : stitch.slots())
                for (uint32_t j = 0; j < k; ++j)
                {
                    float* v = &maps.values[maps.index(j, slot)];
                    bool any = false;
                    for (int c = 0; c < 3; ++c)
                        if (v[c] < 0.0f)
                        {
                            v[c] = 0.0f;
                            any = true;
                        }
                    clamped += any;
                }
            made.has_clamped = 1;
            made.clamped = clamped;
        }
        else if (name == "shadowmask")
        {
            // Fractions of the light: kept in [0, 1] (the texels no stitch changes are).
            for (const size_t slot : stitch.slots())
                for (uint32_t j = 0; j < k; ++j)
                    for (int c = 0; c < 3; ++c)
                    {
                        float& v = maps.values[maps.index(j, slot) + size_t(c)];
                        v = std::clamp(v, 0.0f, 1.0f);
                    }
        }
        else if (o.non_negative)
        {
            std::vector<glm::vec3> texel(k);
            for (const size_t slot : stitch.slots())
            {
                for (uint32_t j = 0; j < k; ++j)
                    std::memcpy(&texel[j], &maps.values[maps.index(j, slot)], sizeof texel[j]);
                if (make_non_negative(name, texel))
                    for (uint32_t j = 0; j < k; ++j)
                        std::memcpy(&maps.values[maps.index(j, slot)], &texel[j], sizeof texel[j]);
            }
        }
        const LightmapSeamMetric m = measure_lightmap_seams(seams_of(name), maps);
        made.after_mean = m.mean;
        made.after_p95 = m.p95;
    };
    // Whether an output is stitched, and the stitch its seams share with the outputs before (one
    // factorisation per set of seams and grid).
    const auto stitched = [&](const std::string& name)
    { return o.stitch && !seams.empty() && (name == "plain" || name == "shadowmask" || !framed.empty()); };
    const auto stitch_of = [&](const std::string& name, std::optional<LightmapSeamStitch>& whole,
                               std::optional<LightmapSeamStitch>& framed_only,
                               const io::BlockGrid& grid) -> const LightmapSeamStitch&
    {
        std::optional<LightmapSeamStitch>& stitch =
            name == "plain" || name == "shadowmask" || framed.size() == seams.size() ? whole : framed_only;
        if (!stitch)
            stitch.emplace(seams_of(name), grid, o.stitch_closeness);
        return *stitch;
    };
    const auto make_output = [&](const std::string& name, OutputReport& made)
    {
        size_t adjusted = 0;
        io::LightmapOutput output{name, uint32_t(lightmap_output_size(name)),
                                  lightmap_maps(name, atlas, sh, o.dilate, o.non_negative, &adjusted)};
        made.adjusted = adjusted;
        made.blocks = output.maps.grid.blocks().size();
        const LightmapSeamMetric before = measure_lightmap_seams(seams_of(output.name), output.maps);
        made.before_mean = made.after_mean = before.mean;
        made.before_p95 = made.after_p95 = before.p95;
        if (stitched(output.name))
            stitch_output(output.name, output.maps,
                          stitch_of(output.name, all, along_frames, output.maps.grid), made);
        made.scale_exponent = io::half_scale_exponent(io::largest_magnitude(output.maps.values));
        return output;
    };
    // In tiles, each output band by band of block rows (LightmapOutputBands), so that one band's floats are
    // held, not the output's: a first sweep keeps the blocks the seams read (lightmap_seam_blocks) and the
    // largest value of the texels no stitch changes; the seams are measured and stitched over those blocks
    // alone; a second sweep makes the bands again and writes each into the asset's spool with the stitched
    // texels put in. The same bytes as make_output's (the dilation, the stitch and the scale are the same).
    std::optional<LightmapSeamStitch> seam_all, seam_along_frames; // over the seams' blocks
    const size_t band_slots = std::max<size_t>(summary.tile_texels, size_t(1) << 12);
    // An output between its two sweeps: its bands, the seams' blocks stitched, the texels the stitch moved,
    // and where the second sweep is.
    struct BandedOutput
    {
        uint32_t k = 0;
        std::optional<LightmapOutputBands> bands;
        io::BlockMaps seam;
        std::vector<uint8_t> moved;
        LightmapOutputBands::Band band;
        size_t next_seam = 0;
    };
    // The first sweep.
    const auto first_sweep = [&](const std::string& name, OutputReport& made, BandedOutput& out)
    {
        const uint32_t k = uint32_t(lightmap_output_size(name));
        out.k = k;
        out.bands.emplace(name, atlas, sh, o.dilate, o.non_negative, band_slots);
        LightmapOutputBands& bands = *out.bands;
        const io::BlockGrid& grid = bands.grid();
        made.blocks = grid.blocks().size();
        out.seam = io::BlockMaps(lightmap_seam_blocks(seams_of(name), grid), k);
        io::BlockMaps& seam = out.seam;
        const LightmapSeamStitch* stitch =
            stitched(name) ? &stitch_of(name, seam_all, seam_along_frames, seam.grid) : nullptr;
        out.moved.assign(seam.grid.slots(), 0); // the texels the stitch may change
        if (stitch)
            for (const size_t slot : stitch->slots())
                out.moved[slot] = 1;
        const size_t block_values = size_t(k) * io::BlockGrid::kTexels * 3;
        const std::vector<uint32_t>& seam_blocks = seam.grid.blocks();
        float largest = 0.0f;
        size_t adjusted = 0;
        LightmapOutputBands::Band band;
        for (size_t next_seam = 0; bands.next(band, &adjusted);)
            for (uint32_t b = 0; b < band.count; ++b)
            {
                const float* v = &band.maps.values[size_t(band.at + b) * block_values];
                const bool on_seam =
                    next_seam < seam_blocks.size() && seam_blocks[next_seam] == grid.blocks()[band.first + b];
                if (!on_seam)
                {
                    largest = std::max(largest, io::largest_magnitude(std::span(v, block_values)));
                    continue;
                }
                std::copy_n(v, block_values, &seam.values[next_seam * block_values]);
                for (uint32_t j = 0; j < k; ++j)
                    for (size_t t = 0; t < io::BlockGrid::kTexels; ++t)
                        if (!out.moved[next_seam * io::BlockGrid::kTexels + t])
                            largest = std::max(largest, io::largest_magnitude(std::span(
                                                            &v[(j * io::BlockGrid::kTexels + t) * 3], 3)));
                ++next_seam;
            }
        made.adjusted = adjusted;
        const LightmapSeamMetric before = measure_lightmap_seams(seams_of(name), seam);
        made.before_mean = made.after_mean = before.mean;
        made.before_p95 = made.after_p95 = before.p95;
        if (stitch)
        {
            stitch_output(name, seam, *stitch, made);
            for (const size_t slot : stitch->slots())
                for (uint32_t j = 0; j < k; ++j)
                    largest = std::max(
                        largest, io::largest_magnitude(std::span(&seam.values[seam.index(j, slot)], 3)));
        }
        made.scale_exponent = io::half_scale_exponent(largest);
        bands.restart();
    };
    // The second sweep, pulled by the writer a piece at a time: each band made again, its stitched texels put
    // in from the seams' blocks.
    const auto pull = [](BandedOutput& out, uint64_t first, std::span<float> values)
    {
        const uint32_t k = out.k;
        const size_t block_values = size_t(k) * io::BlockGrid::kTexels * 3;
        const io::BlockGrid& grid = out.bands->grid();
        const std::vector<uint32_t>& seam_blocks = out.seam.grid.blocks();
        LightmapOutputBands::Band& band = out.band;
        for (size_t done = 0; done < values.size();)
        {
            const uint64_t at = first + done, block = at / block_values;
            while (block >= uint64_t(band.first) + band.count)
            {
                if (!out.bands->next(band))
                    throw std::logic_error("an output's bands ended before its values");
                for (uint32_t b = 0; b < band.count; ++b)
                {
                    while (out.next_seam < seam_blocks.size() &&
                           seam_blocks[out.next_seam] < grid.blocks()[band.first + b])
                        ++out.next_seam;
                    if (out.next_seam == seam_blocks.size() ||
                        seam_blocks[out.next_seam] != grid.blocks()[band.first + b])
                        continue;
                    for (uint32_t j = 0; j < k; ++j)
                        for (size_t t = 0; t < io::BlockGrid::kTexels; ++t)
                            if (out.moved[out.next_seam * io::BlockGrid::kTexels + t])
                                std::copy_n(&out.seam.values[out.seam.index(
                                                j, out.next_seam * io::BlockGrid::kTexels + t)],
                                            3,
                                            &band.maps.values[band.maps.index(
                                                j, size_t(band.at + b) * io::BlockGrid::kTexels + t)]);
                }
            }
            const size_t in_block = size_t(at % block_values),
                         count = std::min(values.size() - done, block_values - in_block);
            std::copy_n(&band.maps.values[size_t(block - band.first + band.at) * block_values + in_block],
                        count, values.begin() + ptrdiff_t(done));
            done += count;
        }
    };
    const auto write_output_in_bands =
        [&](const std::string& name, OutputReport& made, io::LightmapAssetWriter& writer)
    {
        BandedOutput out;
        first_sweep(name, made, out);
        writer.add_output(name, out.k, out.bands->grid(), made.scale_exponent,
                          [&](uint64_t first, std::span<float> values) { pull(out, first, values); });
    };
    const auto take_report = [&](const std::string& name, const OutputReport& made)
    {
        if (o.non_negative && name != "plain" && name != "rnm")
            summary.non_negative[name] = size_t(made.adjusted);
        if (&name == &o.outputs.front())
            summary.blocks = size_t(made.blocks);
        summary.seam_difference[name] = {{made.before_mean, made.before_p95},
                                         {made.after_mean, made.after_p95}};
        if (made.stitched)
            summary.stitched_texels = std::max(summary.stitched_texels, size_t(made.stitched_texels));
        if (made.has_clamped)
            summary.stitch_clamped[name] = size_t(made.clamped);
        summary.output_scales[name] = std::ldexp(1.0, made.scale_exponent);
    };
    // The lights as the run time needs them (the sun in the mesh's space), and with mixed lights the
    // shadowmask: dilated and stitched like plain (it does not depend on the tangent frame), kept in [0, 1].
    if (leader)
    {
        if (o.lights.sun)
        {
            io::LightmapLight sun;
            sun.light.type = io::PunctualLight::Type::Directional;
            sun.light.name = "sun";
            sun.light.color = o.lights.sun_irradiance;
            sun.light.intensity = 1.0f;
            sun.light.direction =
                -glm::normalize(glm::transpose(o.lights.scene_to_world) * o.lights.sun_direction);
            sun.light.mode = o.lights.sun_mode;
            sun.angular_diameter_degrees = o.lights.sun_diameter_degrees;
            asset.lights.push_back(sun);
        }
        for (const io::PunctualLight& p : o.lights.punctual)
            asset.lights.push_back({p, 0.0f, -1});
        for (const ShadowmaskChannel& c : mixed_channels)
            asset.lights[size_t(c.light + (o.lights.sun ? 1 : 0))].channel = c.channel;
        summary.light_table = asset.lights;
    }
    // (In tiles it is made band by band as the asset is written, below.)
    const bool outputs_in_bands = summary.tile_texels && o.exr_dir.empty();
    if (leader && !mixed_channels.empty() && !outputs_in_bands)
    {
        io::BlockMaps mask = lightmap_maps("shadowmask", atlas, sh, o.dilate, false);
        const LightmapSeamMetric before = measure_lightmap_seams(seams, mask);
        LightmapSeamMetric after = before;
        if (o.stitch && !seams.empty())
        {
            if (!all)
                all.emplace(seams, mask.grid, o.stitch_closeness);
            all->apply(mask);
            for (float& v : mask.values)
                v = std::clamp(v, 0.0f, 1.0f);
            after = measure_lightmap_seams(seams, mask);
        }
        summary.seam_difference["shadowmask"] = {{before.mean, before.p95}, {after.mean, after.p95}};
        if (!o.exr_dir.empty())
        {
            const std::vector<float> dense = mask.dense();
            const size_t plane = size_t(w) * h * 3;
            std::vector<io::ExrChannel> exr;
            for (uint32_t c = 0; c < 4; ++c)
                exr.push_back({std::string(1, "RGBA"[c]), dense.data() + c * plane, 3, true});
            const std::filesystem::path file = lightmap_exr_path(o.exr_dir, asset_path, "shadowmask");
            const std::vector<std::pair<std::string, std::string>> attributes = {
                {"hemi.output", "shadowmask"},
                {"hemi.layout",
                 "per texel the fraction of the direct light of the mixed light of channel R, G, "
                 "B, A that reaches it; rows from the top (v = 0) of the TEXCOORD_1 atlas"}};
            io::write_exr_channels(file, w, h, exr, attributes);
            summary.exr_files.push_back(file);
        }
        asset.shadowmask = std::move(mask);
    }
    if (share_outputs)
    {
        // Each rank makes its outputs and sends rank 0 the made and the encoded section; rank 0 adds them in
        // order (the same bytes as one process's).
        std::optional<io::LightmapAssetWriter> writer;
        if (leader)
            writer.emplace(asset, asset_path.string() + ".spool");
        dist.run_jobs(
            uint32_t(o.outputs.size()),
            [&](uint32_t i)
            {
                OutputReport made;
                const io::LightmapOutput output = make_output(o.outputs[i], made);
                std::vector<std::byte> bytes = io::LightmapAssetWriter::encode_output(output, w, h);
                bytes.insert(bytes.begin(), reinterpret_cast<const std::byte*>(&made),
                             reinterpret_cast<const std::byte*>(&made) + sizeof made);
                return bytes;
            },
            [&](uint32_t i, std::vector<std::byte>&& bytes)
            {
                if (bytes.size() < sizeof(OutputReport))
                    throw std::runtime_error("a rank sent output " + o.outputs[i] + " cut short");
                OutputReport made;
                std::memcpy(&made, bytes.data(), sizeof made);
                take_report(o.outputs[i], made);
                writer->add_encoded_output(o.outputs[i],
                                           std::span<const std::byte>(bytes).subspan(sizeof made));
            });
        if (!leader)
            return summary;
        writer->write(asset_path);
    }
    else
    {
        // Each output's half floats go to a spool file beside the asset as they are made, not to memory.
        io::LightmapAssetWriter writer(asset, asset_path.string() + ".spool");
        for (const std::string& name : o.outputs)
        {
            OutputReport made;
            if (outputs_in_bands)
            {
                write_output_in_bands(name, made, writer);
                take_report(name, made);
                continue;
            }
            const io::LightmapOutput output = make_output(name, made);
            take_report(name, made);
            writer.add_output(output);
            if (o.exr_dir.empty())
                continue;
            // An EXR is a dense image: one output at a time is expanded to the whole atlas.
            const std::vector<float> dense = output.maps.dense();
            // Half floats where the values fit them (what the asset stores), floats for brighter light.
            const bool half = io::largest_magnitude(output.maps.values) <= 65504.0f;
            std::vector<io::ExrChannel> channels;
            const size_t plane = size_t(w) * h * 3;
            for (uint32_t k = 0; k < output.k; ++k)
                for (const char* c : {"R", "G", "B"})
                {
                    char channel_name[32];
                    std::snprintf(channel_name, sizeof channel_name, "c%u.%s", k, c);
                    const size_t channel = size_t(c[0] == 'R' ? 0 : c[0] == 'G' ? 1 : 2);
                    channels.push_back({channel_name, dense.data() + k * plane + channel, 3, half});
                }
            const std::vector<std::pair<std::string, std::string>> attributes = {
                {"hemi.output", output.name},
                {"hemi.k", std::to_string(output.k)},
                {"hemi.layout",
                 "coefficient k of a texel in channels c<k>.R, c<k>.G, c<k>.B; rows from the top "
                 "(v = 0) of the TEXCOORD_1 atlas"},
                {"hemi.frame",
                 "irradiance in each texel's tangent frame of the normal-map UV set (TEXCOORD_0): "
                 "E(n) = sum_k c_k b_k(n), n the tangent-space normal-map normal"}};
            const std::filesystem::path file = lightmap_exr_path(o.exr_dir, asset_path, output.name);
            io::write_exr_channels(file, w, h, channels, attributes);
            summary.exr_files.push_back(file);
        }
        // In tiles the shadowmask too is made band by band, as the writer encodes it (the same bytes as made
        // whole above: the same dilation, the stitch over the seams' blocks, kept in [0, 1]).
        BandedOutput mask;
        if (outputs_in_bands && !mixed_channels.empty())
        {
            OutputReport made;
            first_sweep("shadowmask", made, mask);
            summary.seam_difference["shadowmask"] = {{made.before_mean, made.before_p95},
                                                     {made.after_mean, made.after_p95}};
            writer.set_shadowmask(mask.bands->grid(), [&](uint64_t first, std::span<float> values)
                                  { pull(mask, first, values); });
        }
        writer.write(asset_path);
    }
    stage_done("outputs"); // made, stitched, encoded, written (and the EXRs)
    summary.stage_seconds = std::move(stages);
    remove_checkpoint(o.bake.checkpoint); // the finished work is in the asset now, and the tiles with it
    std::error_code ignored;
    std::filesystem::remove(bake_options.tile_file, ignored);
    summary.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return summary;
}

void write_lightmap_bake_json(const std::filesystem::path& path, const LightmapBakeSummary& s,
                              const LightmapFileOptions& o)
{
    nlohmann::json j;
    j["width"] = s.width;
    j["height"] = s.height;
    j["covered_texels"] = s.uv_report.covered_texels;
    j["overlapping_texels"] = s.uv_report.overlapping_texels;
    j["grazed_texels"] =
        s.uv_report.grazed_instead; // given to a visible face grazing them (lightmap_atlas.h)
    j["stored_blocks"] = s.blocks;  // 8x8 blocks of the atlas the asset stores per output
    j["peak_memory_bytes"] = io::peak_memory();
    j["memory_budget_bytes"] = s.memory_budget;
    j["tile_texels"] = s.tile_texels; // 0: the whole atlas in memory
    j["tiles_per_pass"] = s.tiles;
    j["raster_band_slots"] = s.raster_band_slots; // 0: the atlas rasterised whole
    j["paged_records"] = s.paged_records;         // the atlas's records in pages of temporary files
    j["triangles"] = s.triangles;
    // The most direct irradiance the lights can give a point (light_bound.h), and the power of two each
    // output's half floats are times (io/half_scale.h: 1 for light in the ordinary range).
    j["irradiance_bound"] = s.irradiance_bound;
    j["output_scales"] = s.output_scales;
    j["materials"] = s.materials;
    j["primitives"] = s.primitives;
    j["images"] = s.images;
    j["outputs"] = o.outputs;
    j["rays_per_texel"] = o.bake.rays;
    j["sun_rays_per_texel"] = o.lights.sun ? o.bake.sun_rays : 0;
    j["seed"] = o.bake.seed;
    j["bounces"] = o.bake.bounces;
    j["environment"] = o.lights.environment.pixels.empty() ? "uniform" : "image";
    j["punctual_lights"] = s.lights;
    // Every light with its bake mode and, for a mixed one, its shadowmask channel.
    nlohmann::json lights = nlohmann::json::array();
    for (const io::LightmapLight& l : s.light_table)
    {
        static const char* const types[] = {"directional", "point", "spot"};
        nlohmann::json light = {{"name", l.light.name},
                                {"type", types[int(l.light.type)]},
                                {"mode", io::light_mode_name(l.light.mode)}};
        if (l.channel >= 0)
            light["shadowmask_channel"] = std::string(1, "RGBA"[l.channel]);
        lights.push_back(light);
    }
    j["lights"] = lights;
    j["rays"] = s.rays;
    j["texels_moved_out_of_walls"] = s.pushed;
    j["texels_inside_geometry"] = s.invalid;
    if (o.non_negative)
        j["non_negative_texels_changed"] = s.non_negative; // per directional output
    nlohmann::json seams = {{"edges", s.seams}};
    if (s.denoised_texels)
        j["denoised_texels"] = s.denoised_texels;
    seams["across_tangent_frames"] = s.seams_across_frames; // stitched in plain only
    seams["stitched"] = s.stitched_texels > 0;
    seams["stitched_texels"] = s.stitched_texels;
    for (const auto& [name, n] : s.stitch_clamped)
        seams["negative_clamped"][name] = n;
    for (const auto& [name, difference] : s.seam_difference)
        seams["outputs"][name] = {
            {"before", {{"mean", difference.first.first}, {"p95", difference.first.second}}},
            {"after", {{"mean", difference.second.first}, {"p95", difference.second.second}}}};
    j["seams"] = seams; // relative |difference| of the two sides' lookups along the seams (lightmap_seams.h)
    if (s.unwrapped_charts)
        j["unwrap"] = {{"charts", s.unwrapped_charts}, {"texel_size", s.unwrap_texel_size}};
    if (s.probes)
    {
        j["probes"] = {{"placement", probes_named(o)},
                       {"count", s.probes},
                       {"inside_geometry", s.invalid_probes},
                       {"rays_per_probe", o.probe_rays},
                       {"depth_resolution", o.probe_depth}};
        if (o.probe_budget) // automatic placement: its candidates and the placed probes' error at the others
            j["probes"]["candidates"] = {{"points", s.probe_candidates},
                                         {"open", s.open_probe_candidates},
                                         {"placement_error", s.probe_placement_error}};
    }
    if (s.reflection_probes)
        j["reflection_probes"] = {{"count", s.reflection_probes}, {"size", o.reflection.size}};
    j["trace_seconds"] = s.trace_seconds;
    j["total_seconds"] = s.total_seconds;
    nlohmann::json stage_seconds = nlohmann::json::object();
    for (const auto& [stage, seconds] : s.stage_seconds)
        stage_seconds[stage] = seconds;
    j["stage_seconds"] = stage_seconds;
    j["rays_per_second"] = s.trace_seconds > 0.0 ? double(s.rays) / s.trace_seconds : 0.0;
    j["resumed"] = s.resumed;
    j["ranks"] = s.texels_by_rank.size();
    j["texels_by_rank"] = s.texels_by_rank; // the origin search and all passes: who did what
    j["tangents_generated"] = s.tangents_generated;
    j["warnings"] = s.warnings;
    j["texel_size"] = {{"min", s.uv_report.min_texel_size}, {"max", s.uv_report.max_texel_size}};
    std::vector<std::string> exrs;
    for (const std::filesystem::path& p : s.exr_files)
        exrs.push_back(p.string());
    j["exr_files"] = exrs;
    io::write_text_atomically(path, j.dump(2) + "\n");
}

} // namespace hemi::bake
