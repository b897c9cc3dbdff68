#pragma once
// A baked lightmap asset (Habel & Wimmer 2010): the mesh with its lightmap UVs, the scene's materials with
// their images, and per output (a basis of math::bases(), "plain" or "rnm") K coefficient maps of the
// atlas, in the .hemi container (io/asset.h: versioned, checksummed, written atomically). Self-contained,
// like a PRT asset.
//
// Sections (all little-endian; W x H atlas, K = the output's size):
//   lightmap.info  u32 layout version (3; 4 with a shadowmask), u32 W, u32 H, u32 rays per texel, u64 seed,
//   u32 bounces,
//                  u32 covered texels
//   mesh.*, scene.*, image.<i>: the mesh (mesh.uvs1 required) and the scene's surfaces, exactly as a PRT
//                  asset stores them (prt_asset.h)
//   L.<output>     u32 K, u32 N, i32 e, N u32 block indices (strictly ascending), then N x K x 64 x 3 f16
//                  (IEEE binary16): the 8 x 8 blocks of the atlas that hold a texel (io/block_maps.h: block
//                  by * ceil(W / 8) + bx; in a block, coefficient after coefficient, each 8 rows of 8 RGB
//                  texels, rows from the top, v = 0); texels of the blocks not stored are 0. A value is its
//                  half times 2^e (io/half_scale.h: e = 0 unless the output's largest magnitude is outside
//                  [2^-6, 2^15], so light of any magnitude keeps the halves' precision). So the asset's
//                  size follows the texels the scene covers (and their dilation), not the atlas. Layout 2
//                  (still read) had no e (e = 0); layout 1 (still read) stored K x H x W x 3 f16 for the
//                  whole atlas. The coefficients are irradiance
//                  in each texel's tangent frame (the normal-map UV set's), so sum_k c_k b_k(n) at the
//                  normal-map normal n is E(n); "plain" is E at the surface normal, "rnm" E towards each
//                  math::rnm_basis() direction (normalised to pi under uniform radiance).
//   lightmap.probes (optional) u32 NX, NY, NZ, u32 kind (0 a grid, 1 scattered: N x 1 x 1 probes placed
//                  by lightmap.probe_points), f32 lo.xyz, f32 hi.xyz, then NX * NY * NZ probes of
//                  9 x 3 f32 (SH9 irradiance, coefficient j channel c at j * 3 + c), x fastest, then y, z,
//                  then NX * NY * NZ u8 valid flags, then with mixed lights NX * NY * NZ x 4 u8: each probe's
//                  occlusion of the shadowmask's four channels (LightProbes::occlusion), times 255.
//   lightmap.probe_points (with scattered probes) per probe f32 position xyz, f32 reach
//                  (LightProbes::points).
//   lightmap.probe_depth (optional, with lightmap.probes) u32 R, f32 max_distance, then per probe R x R
//                  texels of 2 f16: the mean distance and its deviation, each over max_distance
//                  (LightProbes::depth, io/light_probes.h): what each probe sees, for the lookup that blends
//                  only the probes a point can see.
//   lightmap.lights (optional) u32 count, then per light: u32 type (0 directional, 1 point, 2 spot), u32 bake
//                  mode (0 baked, 1 mixed, 2 realtime), i32 shadowmask channel (0-3, -1 none), f32 colour
//                  RGB, f32 intensity, f32 range (0: infinite), f32 inner and outer cone (radians), f32
//                  position xyz, f32 direction xyz (unit, where the light points), f32 angular diameter
//                  (degrees: the disc of hemi-bake's --sun; 0 for glTF's lights), u32 name length, the
//                  name (UTF-8). Every light the bake was given, in the mesh's space.
//   lightmap.reflections (optional) u32 count (at most 256), then per probe f32 centre xyz, f32 box_min xyz,
//                  f32 box_max xyz (ReflectionProbe); probe i's maps in the sections reflection<i>.info,
//                  .mirror, .glossy, .diffuse and .fresnel, laid out as an environment asset's envmap.*
//                  (io/envmap_asset.h).
//   lightmap.shadowmask (with mixed lights) u32 N, N u32 block indices (strictly ascending, as an output's),
//                  then N x 64 x 4 u8: per texel of a block (8 rows of 8, rows from the top) the fraction of
//                  the direct light of the mixed light of channel R, G, B and A that reaches it, times 255.

#include <hemi/io/block_maps.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/gltf.h>
#include <hemi/io/light_probes.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <glm/vec3.hpp>

#include <array>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hemi::io
{

struct LightmapOutput
{
    std::string name; // "sh9", "hl2", "h4", "h6", "sal4", ... , "plain", "rnm"
    uint32_t k = 0;
    // K maps of the W x H atlas, the blocks that hold texels: the values themselves (stored as half floats
    // times a power-of-two scale, io/half_scale.h).
    BlockMaps maps;
};

// A light the bake was given, as an engine's runtime needs it to light the lightmap's mixed lights.
struct LightmapLight
{
    PunctualLight light;                   // in the mesh's space; light.mode: how it was baked
    float angular_diameter_degrees = 0.0f; // the sun's disc (the shadowmask's penumbra); 0: a point
    int channel = -1;                      // the shadowmask channel (0-3) of a mixed light; -1 otherwise
};

// A reflection probe (bake::bake_reflection_probe; docs/probes.md): what the lit level looks like from
// `centre` as parabolic maps, and the box it lights (its influence volume, for box projection), all in the
// mesh's space.
struct ReflectionProbe
{
    glm::vec3 centre{0.0f}, box_min{0.0f}, box_max{0.0f};
    EnvmapAsset maps;
};

constexpr size_t kMaxReflectionProbes = 256;

struct LightmapAsset
{
    Mesh mesh; // with uvs1
    std::vector<Material> materials;
    std::vector<EncodedImage> images;
    std::vector<Primitive> primitives;
    uint32_t width = 0, height = 0;
    uint32_t rays = 0, bounces = 0, covered_texels = 0;
    uint64_t seed = 0;
    std::vector<LightmapOutput> outputs;
    LightProbes probes;                       // optional
    std::vector<LightmapLight> lights;        // optional (assets baked before bake modes have none)
    std::vector<ReflectionProbe> reflections; // optional, at most kMaxReflectionProbes
    // With mixed lights: the shadowmask, 4 maps of the atlas (k = 4; map c holds channel c's fraction in [0,
    // 1] in all three colours), stored as RGBA8; k = 0 without one.
    BlockMaps shadowmask;

    // Throws std::invalid_argument listing the outputs the asset has.
    const LightmapOutput& output(const std::string& name) const;
};

// Throws std::invalid_argument for an inconsistent asset (a value that is not finite among them),
// FormatError naming the file when it cannot be written.
void write_lightmap_asset(const std::filesystem::path& path, const LightmapAsset& asset);

// The same file with its outputs added one at a time, each encoded at once into its half-float section, so
// that a bake can free an output's float maps before it makes the next (hemi-bake lightmap holds one output
// in floats instead of all). `asset` is everything else (its outputs are not read; its probes must be
// final); the writer keeps a reference to it until write(). The bytes are write_lightmap_asset's of the whole
// asset. With a `spool` file (AssetWriter's), each output's half floats go to disk as they are encoded and
// the writer holds none of them: a bake's memory then holds one output at a time, in floats, and nothing
// else of its outputs. Throws as write_lightmap_asset does: the constructor for the rest of the asset (or a
// spool it cannot create), add_output for an output, write() for no outputs, mixed lights with no shadowmask
// (neither the asset's nor set_shadowmask's), a shadowmask value outside [0, 1], or a file that cannot be
// written.
class LightmapAssetWriter
{
  public:
    explicit LightmapAssetWriter(const LightmapAsset& asset, const std::filesystem::path& spool = {});
    ~LightmapAssetWriter();
    LightmapAssetWriter(const LightmapAssetWriter&) = delete;
    LightmapAssetWriter& operator=(const LightmapAssetWriter&) = delete;
    void add_output(const LightmapOutput& output);
    // An output whose values are made as they are written (a bake in tiles, band by band): K maps over
    // `grid` (the atlas's size), its halves times 2^exponent (io/half_scale.h), and values(first, out) the
    // values from index `first` on in BlockMaps' layout, asked for in order, a piece at a time. A value that
    // is not finite throws std::invalid_argument when it comes.
    void add_output(const std::string& name, uint32_t k, const BlockGrid& grid, int32_t exponent,
                    const std::function<void(uint64_t first, std::span<float> out)>& values);
    // The same in two steps, for an output made elsewhere (another rank of a distributed bake): its section's
    // bytes for an asset of width x height, then those bytes added under its name.
    static std::vector<std::byte> encode_output(const LightmapOutput& output, uint32_t width,
                                                uint32_t height);
    void add_encoded_output(const std::string& name, std::span<const std::byte> bytes);
    // With mixed lights, the shadowmask made as it is written, when the asset holds none (a bake in tiles,
    // band by band): its 4 maps over `grid` (the atlas's size), values(first, out) the values from index
    // `first` on in BlockMaps' layout, asked for a block at a time in order during write(), each in [0, 1]
    // (write() throws std::invalid_argument for one that is not). The function must live until write().
    void set_shadowmask(const BlockGrid& grid,
                        std::function<void(uint64_t first, std::span<float> out)> values);
    void write(const std::filesystem::path& path);

  private:
    struct Sections;
    const LightmapAsset* asset_;
    std::unique_ptr<Sections> sections_;
    size_t outputs_ = 0;
    bool mixed_ = false; // the asset has mixed lights: a shadowmask is written
    BlockGrid shadowmask_grid_;
    std::function<void(uint64_t first, std::span<float> out)> shadowmask_values_;
};
// Throws FormatError naming the file and the problem (missing, truncated, corrupt, another kind of asset,
// sizes that disagree, non-finite values).
LightmapAsset read_lightmap_asset(const std::filesystem::path& path);
// The same from bytes in memory (an engine's pack file, a memory-mapped archive); `name` names them in
// errors.
LightmapAsset read_lightmap_asset(std::span<const std::byte> bytes, const std::string& name = "<memory>");

// What a .hemi file holds, from its sections: "prt", "lightmap" or "envmap". Throws FormatError naming the
// file when it is not a hemi asset or neither kind.
std::string asset_kind(const std::filesystem::path& path);

} // namespace hemi::io
