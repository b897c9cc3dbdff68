#pragma once
// The directional lightmap bake (Habel & Wimmer 2010, "Efficient Irradiance Normal Mapping"): per texel of a
// lightmap atlas, the incident radiance over the hemisphere of the texel's tangent frame, ray traced with
// Embree, projected into SH9 and convolved with the clamped cosine; then, from that SH9 irradiance, the
// coefficients of each basis the runtime evaluates at the normal-map normal.
//
// The radiance of a texel is that of the hemisphere around its (shading) normal: rays that hit the scene
// carry no light yet (no emission or bounces in this first step), rays that escape carry the environment's,
// and rays below the triangle's own plane are blocked by it. So a texel's SH9 radiance is zero over its lower
// hemisphere and E(n) = sum_j s_j y_j(n) is its irradiance at any normal n of the tangent frame.
//
// Units: radiance in the scene's linear RGB; the sun's value is the irradiance it gives a surface facing it.
// Directions are in world space, z up, like hemi-render's environments.

#include <hemi/bake/distribution.h>
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/texel_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/mesh.h>

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hemi::bake
{

// Light from infinitely far away: the environment (uniform, or an equirectangular EXR in hemi-render's z-up
// convention, Cycles' mapping: u = 0.5 - atan2(y, x) / 2 pi, v = acos(z) / pi from the top) and a sun.
struct LightmapLights
{
    glm::vec3 uniform{1.0f};   // when `environment` is empty: radiance from every direction
    io::ImageRgba environment; // equirect radiance (linear), constant over each pixel; empty: uniform
    float environment_scale = 1.0f;
    std::string environment_name; // for messages: the file `environment` came from

    bool sun = false;
    glm::vec3 sun_direction{0.0f, 0.0f, 1.0f}; // unit, towards the sun (world)
    glm::vec3 sun_irradiance{0.0f};            // on a surface facing the sun
    float sun_diameter_degrees = 0.53f;        // the disc the shadow rays sample; 0 is a point (hard shadows)
    // How the sun is baked (io::LightMode; hemi-bake's --sun-mode): baked, mixed (its indirect light in the
    // lightmap, its visibility in a shadowmask channel) or realtime (not baked). The environment is always
    // baked; each punctual light has its own (io::PunctualLight::mode).
    io::LightMode sun_mode = io::LightMode::Baked;

    // glTF punctual lights in the mesh's space (io::GltfScene::lights), one shadow ray each per texel (hard
    // shadows). A point or spot light of intensity I gives I / d^2 at distance d, times glTF's recommended
    // range window clamp(1 - (d / range)^4, 0, 1) when it has a range, and a spot light glTF's smooth cone
    // factor saturate((cos a - cos outer) / (cos inner - cos outer))^2; a directional light gives its
    // intensity. Times the light's colour.
    std::vector<io::PunctualLight> punctual;

    // The rotation from the mesh's space to the world the lights are given in: identity for a mesh in
    // hemi's z-up world; render::gltf_to_world()'s rotation for a glTF scene (y up), which is what
    // bake_lightmap_file uses, so that lights match hemi-render's.
    glm::mat3 scene_to_world{1.0f};

    // Radiance of the environment towards the scene from direction `d` (unit, mesh space).
    glm::vec3 environment_radiance(const glm::vec3& d) const;
};

// A mixed light's shadowmask channel: which light (-1 the sun, else LightmapLights::punctual[light]) and the
// channel (0-3) of the RGBA8 shadowmask its visibility goes to.
struct ShadowmaskChannel
{
    int light = -1;
    int channel = 0;
};
// The mixed lights' channels, in order (the sun first, then the punctual lights): each takes the lowest
// channel that no mixed light whose reach overlaps its own holds, so lights far apart share one. A light's
// reach is everywhere for the sun and a directional light, the sphere of its range for a point or spot light
// (everywhere without a range). Throws std::invalid_argument naming a light whose reach overlaps four mixed
// lights that already hold the four channels (make it baked or realtime, or give it a shorter range).
std::vector<ShadowmaskChannel> shadowmask_channels(const LightmapLights& lights);
// Whether punctual light `p` can light point `x` (mesh space): inside its range, or it has none.
bool light_reaches(const io::PunctualLight& p, const glm::vec3& x);

// What a ray that hits the scene sees there: per triangle, its material's albedo (base colour factor times
// the sRGB-decoded base colour texture, linear RGB) and emission (emissive factor times the emissive
// texture), looked up bilinearly at the hit's UV set with KHR_texture_transform and the sampler's wrap modes;
// and whether the material is double-sided (a back-face hit of a single-sided one carries no light).
class LightmapSurfaces
{
  public:
    // Decodes every image once. Throws io::FormatError naming a corrupt image, std::invalid_argument for a
    // primitive out of range or a material index out of range.
    LightmapSurfaces(const io::Mesh& mesh, const std::vector<io::Material>& materials,
                     const std::vector<io::EncodedImage>& images,
                     const std::vector<io::Primitive>& primitives);

    glm::vec3 albedo(uint32_t triangle, float u, float v) const; // Embree's barycentrics of the hit
    glm::vec3 emission(uint32_t triangle, float u, float v) const;
    // The material's tangent-space normal (glTF's: +y up the image): its normal texture's texel c, bilinear,
    // as (2c - 1) with x and y times the normal scale, normalised, like the material system's shader; +z for
    // a material without one.
    glm::vec3 tangent_normal(uint32_t triangle, float u, float v) const;
    bool double_sided(uint32_t triangle) const;
    bool emissive() const { return emissive_; } // any material emits
    const std::vector<io::Material>& materials() const { return materials_; }
    const std::vector<io::ImageRgba8>& images() const { return images_; }

  private:
    glm::vec4 sample(const io::TextureRef& t, uint32_t triangle, float u, float v, bool srgb) const;
    const io::Mesh* mesh_;
    std::vector<io::Material> materials_;
    std::vector<io::ImageRgba8> images_;
    std::vector<uint32_t> material_of_;
    bool emissive_ = false;
};

struct LightmapBakeOptions
{
    int rays = 256;    // hemisphere rays per texel for the environment
    int sun_rays = 16; // shadow rays per texel towards the sun's disc
    uint64_t seed = 1;
    float ray_offset = 1e-4f; // of the scene's diagonal: how far ray origins leave the surface
    // Passes of indirect light: a ray that hits a surface carries albedo / pi times the irradiance the
    // previous pass left at that point (looked up in the atlas at the hit's TEXCOORD_1, bilinearly), so B
    // bounces add B passes; with surfaces, what a ray hits also emits (in the first pass).
    int bounces = 0;
    std::filesystem::path checkpoint; // empty: none
    double checkpoint_seconds = 30.0;
    // Estimate each texel's noise (LightmapSh::noise), for the denoiser: 32 bytes more per texel, in the
    // bake and its checkpoint.
    bool keep_noise = false;
    // Who computes the texels (distribution.h): null, this process; else the ranks of a job, which all call
    // bake_lightmap_sh with the same arguments and all return the same result. Only the leader resumes and
    // saves the checkpoint and reports progress.
    Distribution* distribution = nullptr;
    // Bounded memory (hemi-bake lightmap --memory-budget): 0 keeps every texel's sums in memory; else the
    // bake runs each pass in tiles of this many texels and keeps the sums of the passes in `tile_file` on
    // disk (texel_file.h), one tile of them in memory at a time. Per texel, the sums and the pass being
    // gathered (156 bytes each, 172 each with keep_noise) leave memory for a tile's worth; the file holds
    // two copies of the sums (312 bytes a texel, 344 with keep_noise), and memory keeps 12 bytes more for
    // the bounces. The same bytes as a bake without tiles, for any tile size. The leader's value counts on
    // every rank. With a checkpoint, the file is its companion and stays (the caller removes both once the
    // result is written: bake_lightmap_file does); a checkpoint is then saved at the end of a tile, not of a
    // slice. Without one, the file goes with the LightmapSh that holds it.
    uint32_t tile_texels = 0;
    std::filesystem::path tile_file;
};

struct LightmapProgress
{
    int pass = 0, passes = 1; // 0: direct light; 1..B: bounces
    uint64_t texels_done = 0, texels = 0;
    std::string checkpoint_error;
};

// SH9 irradiance per covered texel, in the texel's tangent frame (x = tangent, y = bitangent, z = normal).
struct LightmapSh
{
    uint32_t width = 0, height = 0;
    std::vector<std::array<glm::vec3, 9>> irradiance; // one per atlas.texels entry
    // Per texel, the irradiance the plain and rnm outputs store, integrated from the same rays directly
    // against each direction's clamped cosine instead of through SH9 (whose three bands give a single
    // direction's clamped cosine only approximately: 6% high straight on, more off at grazing angles): E at
    // the normal, then E(B_i) * 2 / (1 + B_i.z) for rnm's three. The bounces take E at the normal from it.
    // Empty in a LightmapSh made by hand: the outputs then project the SH9.
    std::vector<std::array<glm::vec3, 4>> direct;
    // Per texel, the variance of the bake's estimate of four of its values, the denoiser's guides
    // (lightmap_denoise.h): the luminance of plain (direct[0], E at the normal) and of SH9's three band-1
    // coefficients (irradiance[1..3], the light's direction). Each stream of samples (the hemisphere rays,
    // the environment's rays, the sun's rays; punctual lights are exact) adds, per value, the sum over its
    // samples of (the sample's share - the mean share of its k = 6 nearest in the stream's pattern)^2 /
    // (1 + 1 / k) (ray_generator.h, SampleNeighbours; the environment's pattern is a ring cut at a place of
    // each texel's own, and no pair across the cut counts): unbiased for independent samples (the sun's), and
    // for the stratified sets the bake draws it sees how the light changes from one stratum to the next, not
    // the slow change across the set that stratification integrates away. It still runs above the actual
    // error, by a factor that depends on the light (hemi-denoise-quality prints it: in RMS 1.4x on the sample
    // level, 2.8x on a floor and wall under a sky and a sun): a stratified set's own samples cannot tell how
    // well the set integrates. Each pass adds its own (its rays are drawn anew); a bounce ray's share is what
    // it reads of the previous pass's map, whose noise shows as spread between neighbouring rays. Empty
    // unless the bake estimated it (LightmapBakeOptions::keep_noise), and in a LightmapSh made by hand.
    using Noise = std::array<float, 4>;
    std::vector<Noise> noise;
    // With mixed lights (shadowmask_channels): per texel, the fraction of the direct light of each channel's
    // light that reaches it (of its shadow rays, those not blocked; a channel no light of which reaches the
    // texel is 1), and the mixed lights' direct irradiance at its normal as their shadow rays gave it. The
    // sums above hold none of the mixed lights' direct light, and all of their bounces: the bounce rays pick
    // up the first pass's irradiance with mixed_direct added. Empty without mixed lights, and in tiles (then
    // in `tiles`: read_mixed()).
    std::vector<std::array<float, 4>> shadowmask;
    std::vector<glm::vec3> mixed_direct;
    // Per texel: 0 when the texel lies inside geometry (more than half of its first-pass rays hit the backs
    // of single-sided surfaces, after the push below): its outputs come from its valid neighbours.
    std::vector<uint8_t> valid;
    size_t pushed = 0;  // texels moved through a back face that their footprint reached (against leaks)
    size_t invalid = 0; // texels left inside geometry
    uint64_t rays = 0;
    double trace_seconds = 0.0;
    bool resumed = false;
    std::string checkpoint_error;
    // A bake in tiles (LightmapBakeOptions::tile_texels) leaves irradiance, direct, noise, shadowmask and
    // mixed_direct empty: their values are in `tiles` (copy `tiles_copy`: fields irradiance, direct, noise;
    // copy 0: fields tiles_mixed_field, shadowmask, and the next, mixed_direct), read back by read() and
    // read_mixed(). On the leader only; the other ranks of a job return without them. Null otherwise.
    std::shared_ptr<TexelFile> tiles;
    int tiles_copy = 0;
    uint32_t tiles_count = 0; // tiles in the last pass (1 without tiles)
    bool tiles_noise = false;
    int tiles_mixed_field = -1; // -1: no mixed light

    size_t texels() const { return tiles ? tiles->items() : irradiance.size(); }
    bool has_direct() const { return tiles || !direct.empty(); }
    bool has_noise() const { return tiles ? tiles_noise : !noise.empty(); }
    bool has_mixed() const { return tiles ? tiles_mixed_field >= 0 : !shadowmask.empty(); }
    // Texels [first, first + count) from memory or from `tiles`, into each array that is not null: their
    // SH9 irradiance, direct values (has_direct()) and noise (has_noise()).
    void read(uint32_t first, uint32_t count, std::array<glm::vec3, 9>* irradiance,
              std::array<glm::vec3, 4>* direct = nullptr, Noise* noise = nullptr) const;
    // The same for the mixed lights' shadowmask and direct light (has_mixed()).
    void read_mixed(uint32_t first, uint32_t count, std::array<float, 4>* shadowmask,
                    glm::vec3* mixed_direct = nullptr) const;
    // Reads every texel into irradiance, direct, noise, shadowmask and mixed_direct, and lets the tiles go
    // (the denoiser works on the whole atlas in memory).
    void load();
};

// Throws std::invalid_argument for bad options or lights (non-finite values, a sun direction of zero length,
// bounces without surfaces). `surfaces` may be null: hits are then black (no emission, no bounces).
LightmapSh bake_lightmap_sh(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapLights& lights,
                            const LightmapBakeOptions& options, const LightmapSurfaces* surfaces = nullptr,
                            const std::function<void(const LightmapProgress&)>& progress = {});

// The lightmap outputs besides math::bases(): "plain", the non-directional lightmap (K = 1: the irradiance at
// the surface normal, E(+z); lightmap_maps takes it from LightmapSh::direct), and "rnm", the three lightmap
// colours of radiosity normal mapping (K = 3: the irradiance towards each math::rnm_basis() direction B_i,
// normalised so that uniform radiance 1 over the texel's hemisphere gives pi each: E(B_i) * 2 / (1 + B_i.z),
// B_i.z = 1/sqrt 3. Without the factor an open plane, whose lower hemisphere is dark, would give pi (1 +
// 1/sqrt 3) / 2 = 2.48, and a flat wall lit by Listing 1 or an SSBump map would render 0.79 of its albedo
// instead of the plain lightmap's value). Every other name is a basis of math::bases(), whose coefficients
// are its projection_from_sh9 of the SH9 irradiance. Throws std::invalid_argument listing the known names.
// (lightmap_coefficients below is the projection for every name; lightmap_maps uses LightmapSh::direct for
// plain and rnm where the bake filled it.)
int lightmap_output_size(std::string_view name);
// Also "shadowmask" (K = 4, from LightmapSh::shadowmask: channel c in all three colours of coefficient c) is
// made by lightmap_maps like an output, for the same dilation and stitching; the asset stores it as RGBA8
// (io::LightmapAsset::shadowmask).
// The coefficients of one texel's SH9 irradiance in the output `name`: lightmap_output_size(name) RGB values.
std::vector<glm::vec3> lightmap_coefficients(std::string_view name,
                                             const std::array<glm::vec3, 9>& irradiance);
// Every texel's coefficients as K maps (io::BlockMaps: only the blocks of the atlas that hold covered texels
// or their dilation; BlockMaps::dense() gives render::TexelCoefficients' layout). Texels that no triangle
// covers take the average of their covered neighbours within `dilate` texels (so bilinear filtering at a
// chart's border does not pull in black), else 0. A texel the bake judged inside geometry (LightmapSh::valid)
// takes the average of its covered valid neighbours of the same chart (LightmapTexel::chart) the same way,
// else keeps its own value.
// With `non_negative`, every texel's coefficients of a directional basis go through
// make_non_negative first (plain and rnm, integrated directly where the bake filled LightmapSh::direct, are
// integrals of radiance and never negative); `adjusted`, when
// given, counts the texels it changed.
io::BlockMaps lightmap_maps(std::string_view name, const LightmapAtlas& atlas, const LightmapSh& sh,
                            int dilate = 2, bool non_negative = false, size_t* adjusted = nullptr);
// The same from the texels' places alone: places[i] the (x, y) of atlas.texels[i] in a width x height atlas
// and charts[i] its chart (what a bake keeps of its atlas once the passes and probes are done, 12 bytes a
// texel instead of the texel's record; without charts, an invalid texel is filled from any valid one).
io::BlockMaps lightmap_maps(std::string_view name, uint32_t width, uint32_t height,
                            std::span<const glm::uvec2> places, const LightmapSh& sh, int dilate = 2,
                            bool non_negative = false, size_t* adjusted = nullptr,
                            std::span<const uint32_t> charts = {});
// The same band by band of block rows, one band's floats held at a time (what a bake in tiles makes its
// outputs with): each band is dilated with the rows the dilation reaches around it, so that its values are
// lightmap_maps' own, bit for bit. band_slots bounds a band and its rows around (at least one block row and
// those around it; SIZE_MAX: the whole atlas in one band, lightmap_maps). The places must be in the atlas's
// order (LightmapTexels'); otherwise one band.
class LightmapOutputBands
{
  public:
    // `maps` over the band's blocks and the rows around them: grid()'s blocks [first, first + count) are
    // its blocks [at, at + count).
    struct Band
    {
        io::BlockMaps maps;
        uint32_t first = 0, count = 0, at = 0;
    };
    LightmapOutputBands(std::string_view name, uint32_t width, uint32_t height,
                        std::span<const glm::uvec2> places, const LightmapSh& sh, int dilate,
                        bool non_negative, std::span<const uint32_t> charts, size_t band_slots);
    // The places and charts read from the atlas's records (in memory or in pages: LightmapAtlasStorage),
    // which must outlive this.
    LightmapOutputBands(std::string_view name, const LightmapAtlas& atlas, const LightmapSh& sh, int dilate,
                        bool non_negative, size_t band_slots);
    ~LightmapOutputBands();
    LightmapOutputBands(const LightmapOutputBands&) = delete;
    LightmapOutputBands& operator=(const LightmapOutputBands&) = delete;

    const io::BlockGrid& grid() const; // the output's blocks (lightmap_maps' grid)
    // The next band, false after the last; `adjusted` counts the texels make_non_negative changed.
    bool next(Band& band, size_t* adjusted = nullptr);
    void restart(); // from the first band again

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Ringing-free coefficients (hemi-bake lightmap --non-negative): a basis fitted to SH9 irradiance rings where
// the light is concentrated (a low sun's delta lobe gives negative irradiance at normals facing away from
// it), and normal mapping shows it as dark or negative pixels. Per colour channel, the K coefficients of
// output `name` are raised where the irradiance they give falls below 1% of its mean, at 1024 normals spread
// evenly over the cap within 75 degrees of the surface normal (normal maps tilt less; at the horizon a
// linear function could only be non-negative with no direction left): each step raises the lowest normal to
// that floor by the least change of coefficients (in the L2 norm over the hemisphere), until none is below
// half the floor (after 64 steps, which has not happened, the coefficients are blended towards the constant
// of the same mean instead). Coefficients that do not ring are returned unchanged; a channel whose mean is
// not positive becomes 0. Bilinear filtering and dilation mix texels convexly, so rendered irradiance stays
// non-negative too. Returns whether anything changed.
bool make_non_negative(std::string_view name, std::span<glm::vec3> coefficients);

// The side of the depth maps probe_grid asks for (io::LightProbes::depth_resolution).
constexpr uint32_t kProbeDepthResolution = 8;

// An empty grid of `count` probes over the mesh's bounding box, at the centres of its cells, with depth maps
// of kProbeDepthResolution texels a side (what hemi-bake lightmap --probes bakes). Throws
// std::invalid_argument for a count of 0 along an axis.
io::LightProbes probe_grid(const io::Mesh& mesh, const glm::uvec3& count);

// Light probes for dynamic objects, which the lightmap does not light: at each point of `probes`' grid
// (probes.count, probes.lo and probes.hi set by the caller, in the mesh's space) or at its scattered points
// (probes.points with their reaches; the call sets count, lo and hi from them), the radiance over the whole
// sphere from `rays` stratified sphere rays, projected into SH9 and convolved with the clamped cosine:
// irradiance in the mesh's frame (io::LightProbes). A ray that escapes carries the environment (an image
// environment is importance-sampled by `rays` rays of its own), the sun's disc (sun_rays) and every
// punctual light add their shadowed light, and a ray that lands on the front of a surface carries its
// emission plus its albedo / pi times the lightmap's irradiance there (E at the surface normal from `sh`,
// bilinear at the hit's TEXCOORD_1): the same light and bounces as the lightmap's. With
// probes.depth_resolution R > 0 (at most io::kMaxProbeDepthResolution), the same rays' distances to the first
// surface make each probe's R x R depth map (io::LightProbes::depth), what the lookup needs to leave out the
// probes a point cannot see. A probe more than half of
// whose rays see the backs of single-sided surfaces is inside geometry (valid 0). Counter-based rays: the
// same seed gives the same bytes on any thread count. Throws std::invalid_argument for a bad grid or rays.
void bake_light_probes(io::LightProbes& probes, const io::Mesh& mesh, const LightmapAtlas& atlas,
                       const LightmapSh& sh, const LightmapLights& lights, const LightmapBakeOptions& options,
                       const LightmapSurfaces* surfaces = nullptr);

// Reflection probes (bake_reflection_probe in hemi/bake/reflection_probe.h).
struct ReflectionProbeOptions
{
    // Level 0 of each parabolic half (a power of two, 8 to 4096); the radiance is first gathered into an
    // equirectangular image of 4 size x 2 size pixels (math/sh_environment.h's convention, in the mesh's
    // frame), each pixel the mean of `rays` rays (a square number: stratified over the pixel).
    uint32_t size = 128;
    int rays = 16;
    std::vector<double> exponents{10, 100}; // the glossy maps' Phong exponents
    uint64_t seed = 1;
};

// Where hemi-bake lightmap --reflection-probe puts a probe (LightmapFileOptions::reflection_probes), in the
// mesh's space: its centre and its influence box (box_min == box_max: the scene's bounding box).
struct ReflectionProbePlacement
{
    glm::vec3 centre{0.0f}, box_min{0.0f}, box_max{0.0f};
};

// The whole job hemi-bake lightmap runs: read the glTF scene, rasterise its TEXCOORD_1 atlas (refused when
// the scene has none, or its UVs overlap and strict_uv is set), bake, and write the lightmap asset
// (io/lightmap_asset.h) and, with exr_dir, one EXR per output with named channels ("c<k>.R", ".G", ".B",
// half) and the layout in its header (hemi.output, hemi.k, hemi.layout, hemi.frame). Lights are in hemi's
// z-up world (the scene is placed there by render::gltf_to_world(), as hemi-render places it).
struct LightmapFileOptions
{
    LightmapBakeOptions bake;
    LightmapLights lights;
    uint32_t width = 0, height = 0; // the atlas; 0 x 0: from texel_size, else 512 x 512
    float texel_size = 0.0f;        // world units per texel: the atlas size that gives the scene that density
    std::vector<std::string> outputs = {"sh9", "hl2", "h4", "h6", "sal4", "plain", "rnm"};
    std::filesystem::path exr_dir; // empty: no EXRs
    int dilate = 2;
    // Light probes (bake_light_probes; docs/probes.md), at most one of: a grid of `probes` probes over the
    // scene's bounding box, each half a cell inside it; automatic placement (place_light_probes in
    // hemi/bake/probe_placement.h) of at most probe_budget probes; probes at probe_points (the mesh's space:
    // the glTF's frame; read_probe_points reads them from a file); with gltf_probes, probes at the scene's
    // nodes named hemi_probe* (io::GltfScene::light_probes; refused when it has none). None of them: no
    // probes. probe_rays sphere rays per probe.
    glm::uvec3 probes{0};
    uint32_t probe_budget = 0;
    std::vector<glm::vec3> probe_points;
    bool gltf_probes = false;
    int probe_rays = 1024;
    // The side of each probe's depth map (io::LightProbes::depth_resolution), 0 to
    // io::kMaxProbeDepthResolution; 0: none, and the lookup blends the probes trilinearly alone.
    uint32_t probe_depth = kProbeDepthResolution;
    // Reflection probes (bake_reflection_probe, hemi/bake/reflection_probe.h), baked after the light probes
    // into the asset's `reflections`; their size, rays and exponents from `reflection`. Empty: none.
    std::vector<ReflectionProbePlacement> reflection_probes;
    ReflectionProbeOptions reflection;
    // Overlapping lightmap UVs: resolved with a warning (lightmap_atlas.h), or refused with strict_uv.
    bool strict_uv = false;
    // A PNG of the atlas, written after rasterising and before the bake: covered texels grey, overlapping
    // ones red, empty black; at most 2048 pixels a side (a pixel shows the worst of its texels). Empty: none.
    std::filesystem::path uv_report;
    // Make the lightmap UVs (unwrap_lightmap: planar charts at one texel density) instead of reading
    // TEXCOORD_1, with texel_size and width x height as its options; the asset keeps the unwrapped mesh.
    bool unwrap = false;
    // Ringing-free directional outputs (make_non_negative); the summary counts the texels it changed.
    bool non_negative = false;
    // Seam stitching (lightmap_seams.h: LightmapSeamStitch) of every output after the bake, on by default;
    // stitch_closeness is its weight on keeping the baked values.
    bool stitch = true;
    double stitch_closeness = 0.01;
    // The chart-aware denoiser (lightmap_denoise.h) on the baked texels before the outputs are made from
    // them, with denoise_passes a-trous passes; off by default.
    bool denoise = false;
    int denoise_passes = 3;
    // The memory the bake may use, in bytes (--memory-budget); 0: what the machine has free
    // (io::available_memory). A bake whose estimate exceeds it runs in tiles (LightmapBakeOptions::
    // tile_texels) as large as the budget leaves room for, its sums in lightmap_tile_path(asset); one that
    // cannot fit even in tiles of 4096 texels is refused before it starts, naming both.
    uint64_t memory_budget = 0;
    // Bytes of memory_budget spent before the call, which the bake counts as held throughout: 0 when the
    // budget is for the bake alone; hemi-bake, whose --memory-budget is a ceiling on its whole process's
    // peak, passes what the process holds when it starts (io::resident_memory: its code and libraries).
    // The scene the bake reads and the ray tracer's BVH are counted by the bake itself.
    uint64_t memory_held = 0;
    // Called after each stage of the job with its name, in order: "scene", "atlas", "bake", "denoise" (with
    // denoise), then the outputs' and the asset's (LightmapBakeSummary::stage_seconds names them all). An
    // exception thrown from it stops the job there as a kill would, leaving the checkpoint and the tiles for
    // a rerun to resume from: what the tests use to stop a bake at a named point. Empty: none.
    std::function<void(std::string_view stage)> on_stage;
};

struct LightmapBakeSummary
{
    uint32_t width = 0, height = 0;
    size_t triangles = 0, materials = 0, primitives = 0, images = 0, lights = 0;
    LightmapUvReport uv_report;
    std::vector<std::string> warnings; // the scene reader's and the UV report's
    uint64_t rays = 0;
    size_t pushed = 0, invalid = 0; // LightmapSh's: texels moved out of walls, texels left inside geometry
    size_t probes = 0, invalid_probes = 0, reflection_probes = 0;
    // With probe_budget: the fine grid's points, those in open space, and the placed probes' error at the
    // others (ProbePlacementReport).
    size_t probe_candidates = 0, open_probe_candidates = 0;
    double probe_placement_error = 0.0;
    size_t blocks = 0;             // 8x8 blocks of the atlas stored per output (covered texels and dilation)
    double irradiance_bound = 0.0; // the lights' most direct irradiance at any point (light_bound.h)
    std::map<std::string, double> output_scales; // per output, the power of two its halves are times
    std::map<std::string, size_t> non_negative;  // with non_negative: per directional output, texels changed
    // Seams (lightmap_seams.h): the edges where the surface continues from one chart into another, and per
    // output how far the two sides' lookups differ there (relative mean and 95th percentile), before and
    // after stitching (the same without it), and the texels the stitch could change.
    size_t denoised_texels = 0; // with denoise
    size_t seams = 0, stitched_texels = 0;
    size_t seams_across_frames = 0; // seams whose sides' tangent frames differ: plain alone measures them
    // Per irradiance output (plain, rnm): stitched texels (coefficient maps of one texel counted each) that
    // least squares took below 0 and that were set to 0.
    std::map<std::string, size_t> stitch_clamped;
    using SeamDifference = std::pair<double, double>; // mean, p95
    std::map<std::string, std::pair<SeamDifference, SeamDifference>> seam_difference;
    size_t unwrapped_charts = 0; // with unwrap
    float unwrap_texel_size = 0.0f;
    double trace_seconds = 0.0, total_seconds = 0.0;
    // Wall time per stage, in order: scene (read, textures decoded), atlas (rasterised), bake (sample points
    // and passes), denoise, probes, outputs (made, stitched, encoded and written).
    std::vector<std::pair<std::string, double>> stage_seconds;
    bool resumed = false, tangents_generated = false;
    uint64_t memory_budget = 0; // the budget the bake kept to (0: none known)
    uint32_t tile_texels = 0;   // texels per tile; 0: the whole atlas in memory
    uint32_t tiles = 0;         // tiles per pass (the last pass's; 1 without tiles)
    // Slots per band of the rasteriser (rasterize_lightmap's band_slots); 0: the whole atlas at once.
    uint64_t raster_band_slots = 0;
    // The atlas's texel records and slot indices kept in pages of temporary files (LightmapAtlasStorage).
    bool paged_records = false;
    // The ranks that shared the bake and the texels each computed, over the origin search and all passes;
    // {n * (2 + bounces)} on one process.
    std::vector<uint64_t> texels_by_rank;
    std::string checkpoint_error;
    std::vector<std::filesystem::path> exr_files;
    // The lights as the asset stores them (io::LightmapAsset::lights): modes and shadowmask channels.
    std::vector<io::LightmapLight> light_table;
};

// Where a bake in tiles keeps the sums of its passes: ASSET.tiles (removed once the asset is written).
std::filesystem::path lightmap_tile_path(const std::filesystem::path& asset);

// Where --exr-dir DIR puts an output of the asset ASSET: DIR/<ASSET's stem>.<output>.exr.
std::filesystem::path lightmap_exr_path(const std::filesystem::path& dir, const std::filesystem::path& asset,
                                        const std::string& output);

// Checks that every output can be written before reading the scene; checkpoints to ASSET.partial unless
// options.bake.checkpoint says otherwise. Throws io::FormatError naming the file and the problem, or
// std::invalid_argument for bad options.
LightmapBakeSummary bake_lightmap_file(const std::filesystem::path& scene, const std::filesystem::path& asset,
                                       const LightmapFileOptions& options,
                                       const std::function<void(const LightmapProgress&)>& progress = {});
void write_lightmap_bake_json(const std::filesystem::path& path, const LightmapBakeSummary& summary,
                              const LightmapFileOptions& options);

} // namespace hemi::bake
