#pragma once
// A baked PRT asset (Sloan 2006): the mesh, the per-vertex transfer of each technique (dense K x L matrices
// and/or their CPCA compression) and references to the textures, in the .hemi container (io/asset.h:
// versioned, checksummed, written atomically).
//
// Sections (all little-endian; N vertices, L = order^2, K = the technique's size, D = K * L):
//   prt.info           u32 layout version (1), u32 N, u32 order, u32 transfer kind (0 unshadowed,
//                      1 shadowed, 2 interreflected), u32 bounces, u32 rays, u64 seed, f32 albedo, u32 0
//   mesh.positions     N x 3 f32      mesh.normals   N x 3 f32      mesh.tangents  N x 4 f32 (glTF, w = sign)
//   mesh.uvs           N x 2 f32      mesh.indices   u32 triangle list
//   tex.base_color     UTF-8 path of the base colour texture, relative to the asset's folder (may be empty)
//   tex.normal         UTF-8 path of the tangent-space normal map, likewise
//   T.<technique>      N x D f32: vertex v's K x L matrix, row-major, at v * D
//   C.<technique>      CPCA (Sloan et al. 2003): u32 clusters C, u32 vectors V, f32 rms error, then
//                      C x D f32 cluster means, C x V x D f32 PCA vectors, N u32 cluster of each vertex,
//                      N x V f32 weights. Vertex v's matrix is mean[c] + sum_j w[v][j] vector[c][j].
// Techniques are named as math::technique() knows them ("gs", "hl2", "sal4", "h4", "h6", "sep4", "prt").

#include <hemi/io/mesh.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hemi::io
{

struct PrtCpca
{
    uint32_t clusters = 0, vectors = 0;
    float rms_error = 0.0f;             // RMS over all matrix elements of (reconstruction - dense)
    std::vector<float> means;           // C x D
    std::vector<float> basis;           // C x V x D
    std::vector<uint32_t> cluster;      // N
    std::vector<float> weights;         // N x V
};

struct PrtTechnique
{
    std::string name;
    uint32_t k = 0;
    std::vector<float> matrices; // N x K x L, empty when only the CPCA form is stored
    std::optional<PrtCpca> cpca;
};

struct PrtAsset
{
    Mesh mesh;
    uint32_t order = 5;
    uint32_t transfer_kind = 2; // bake::TransferKind
    uint32_t bounces = 0, rays = 0;
    uint64_t seed = 0;
    float albedo = 0.0f;
    std::string base_color_texture, normal_texture; // relative to the asset's folder; empty when none
    std::vector<PrtTechnique> techniques;

    uint32_t l() const { return order * order; }
    // Throws std::invalid_argument naming the technique and listing those the asset holds.
    const PrtTechnique& technique(const std::string& name) const;
};

constexpr uint32_t kPrtLayoutVersion = 1;

// Validates sizes, finiteness and index ranges (std::invalid_argument), then writes atomically
// (FormatError naming the file on I/O failure).
void write_prt_asset(const std::filesystem::path& path, const PrtAsset& asset);

// Throws FormatError naming the file and the problem: anything AssetReader refuses (missing, wrong magic,
// version, truncated, corrupted), a missing section, inconsistent sizes, an unknown technique, an index or
// cluster out of range, or a non-finite value.
PrtAsset read_prt_asset(const std::filesystem::path& path);

// The texture paths of `asset` resolved against the folder of the asset file (empty when none).
std::filesystem::path resolve_texture(const std::filesystem::path& asset_path, const std::string& reference);

} // namespace hemi::io
