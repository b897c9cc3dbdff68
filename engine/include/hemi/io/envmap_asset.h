#pragma once
// A baked environment asset (Heidrich & Seidel 1999, §4): the parabolic mirror map with its solid-angle
// mipmaps, the prefiltered glossy maps (one per Phong exponent), the diffuse map and Fresnel tables, in the
// .hemi container (io/asset.h: versioned, checksummed, written atomically). What hemi-bake envmap writes.
//
// Every map is a math::ParabolicImage (both halves, math/paraboloid.h's conventions), stored as f32 RGB
// (environments hold radiances far beyond half float's 65504: a sun).
// Sections (little-endian):
//   envmap.info    u32 layout version (1), u32 N (level 0's size), u32 levels, u32 glossy maps,
//                  u32 Fresnel tables, u32 Fresnel samples, u32 source width, u32 source height, f32 the
//                  mirror map's extent (math/paraboloid.h: each half covers [-extent, extent]^2)
//   envmap.mirror  the levels N, N/2, ..., 1 one after another, each 2 x size x size x 3 f32
//   envmap.glossy  per map: f32 exponent, u32 size, f32 extent, 2 x size x size x 3 f32
//   envmap.diffuse u32 size, f32 extent, 2 x size x size x 3 f32 (the glossy map of exponent 1: E / pi)
//   envmap.fresnel per table: f32 index of refraction, then the samples (f32, at cos = i / (samples - 1))

#include <hemi/math/paraboloid.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace hemi::io
{

struct EnvmapAsset
{
    uint32_t source_width = 0, source_height = 0;
    std::vector<math::ParabolicImage> mirror; // the mip chain, level 0 first
    std::vector<float> exponents;             // one per glossy map
    std::vector<math::ParabolicImage> glossy;
    math::ParabolicImage diffuse;
    std::vector<float> iors; // one per Fresnel table
    uint32_t fresnel_samples = 0;
    std::vector<float> fresnel; // iors.size() x fresnel_samples
};

// The first inconsistency of an asset (sizes, counts, exponents, indices of refraction), or an empty string:
// what the writer refuses and what render::EnvironmentLighting checks.
std::string envmap_problem(const EnvmapAsset& asset);

// Throws std::invalid_argument for an inconsistent asset, FormatError naming the file when it cannot be
// written.
void write_envmap_asset(const std::filesystem::path& path, const EnvmapAsset& asset);
// Throws FormatError naming the file and the problem (missing, truncated, corrupt, another kind of asset,
// sizes that disagree, non-finite values).
EnvmapAsset read_envmap_asset(const std::filesystem::path& path);
// The same from bytes in memory (an engine's pack file, a memory-mapped archive); `name` names them in
// errors.
EnvmapAsset read_envmap_asset(std::span<const std::byte> bytes, const std::string& name = "<memory>");

class AssetReader;
class AssetWriter;
// The same sections inside another asset, named <prefix>.info, .mirror, .glossy, .diffuse and .fresnel (a
// lightmap asset's reflection probes; the environment asset's own prefix is "envmap"). The writer does not
// check the asset (the caller does, with envmap_problem); the reader throws FormatError naming the file.
void add_envmap_sections(AssetWriter& writer, const EnvmapAsset& asset, const std::string& prefix);
EnvmapAsset read_envmap_sections(const AssetReader& reader, const std::string& prefix);

} // namespace hemi::io
