#pragma once
// A baked lightmap asset (Habel & Wimmer 2010): the mesh with its lightmap UVs, the scene's materials with
// their images, and per output (a basis of math::bases(), "plain" or "rnm") K coefficient maps of the
// atlas, in the .hemi container (io/asset.h: versioned, checksummed, written atomically). Self-contained,
// like a PRT asset.
//
// Sections (all little-endian; W x H atlas, K = the output's size):
//   lightmap.info  u32 layout version (1), u32 W, u32 H, u32 rays per texel, u64 seed, u32 bounces,
//                  u32 covered texels
//   mesh.*, scene.*, image.<i>: the mesh (mesh.uvs1 required) and the scene's surfaces, exactly as a PRT
//                  asset stores them (prt_asset.h)
//   L.<output>     u32 K, then K x H x W x 3 f16 (IEEE binary16): coefficient k of texel (x, y), channel c at
//                  ((k * H + y) * W + x) * 3 + c, rows from the top (v = 0): render::TexelCoefficients' layout.
//                  The coefficients are irradiance in each texel's tangent frame (the normal-map UV set's), so
//                  sum_k c_k b_k(n) at the normal-map normal n is E(n); "plain" is E at the surface normal,
//                  "rnm" E towards each math::rnm_basis() direction.

#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hemi::io
{

struct LightmapOutput
{
    std::string name; // "sh9", "hl2", "h4", "h6", "sal4", ... , "plain", "rnm"
    uint32_t k = 0;
    std::vector<float> maps; // K x H x W x 3, as in L.<output> (stored as half floats)
};

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

    // Throws std::invalid_argument listing the outputs the asset has.
    const LightmapOutput& output(const std::string& name) const;
};

// Throws std::invalid_argument for an inconsistent asset (a value that does not fit a half float among
// them), FormatError naming the file when it cannot be written.
void write_lightmap_asset(const std::filesystem::path& path, const LightmapAsset& asset);
// Throws FormatError naming the file and the problem (missing, truncated, corrupt, another kind of asset,
// sizes that disagree, non-finite values).
LightmapAsset read_lightmap_asset(const std::filesystem::path& path);

// What a .hemi file holds, from its sections: "prt" or "lightmap". Throws FormatError naming the file when
// it is not a hemi asset or neither kind.
std::string asset_kind(const std::filesystem::path& path);

} // namespace hemi::io
