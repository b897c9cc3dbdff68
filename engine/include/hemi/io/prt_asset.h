#pragma once
// A baked PRT asset (Sloan 2006): the mesh, the per-vertex transfer of each technique (dense K x L matrices
// and/or their CPCA compression) and the scene's materials with their images, in the .hemi container
// (io/asset.h: versioned, checksummed, written atomically). Self-contained: the images' encoded bytes are in
// the asset, so it renders wherever it is copied to.
//
// Sections (all little-endian; N vertices, L = order^2, K = the technique's size, D = K * L):
//   prt.info           u32 layout version (2), u32 N, u32 order, u32 transfer kind (0 unshadowed,
//                      1 shadowed, 2 interreflected), u32 bounces, u32 rays, u64 seed, f32 albedo, u32 0
//   mesh.positions     N x 3 f32      mesh.normals   N x 3 f32      mesh.tangents  N x 4 f32 (glTF, w = sign)
//   mesh.uvs           N x 2 f32      mesh.indices   u32 triangle list
//   mesh.uvs1          N x 2 f32, TEXCOORD_1; only when the mesh has it
//   scene.materials    UTF-8 JSON {"materials": [...], "images": [{"name", "mime_type", "bytes"}]}: every
//                      io::Material field by name (textures as {"image", "texcoord", "offset", "scale",
//                      "rotation", "sampler": {"mag", "min", "mipmaps", "wrap_s", "wrap_t"}}, absent when
//                      none), and each image's name, mime type and byte count
//   scene.primitives   P x 3 u32: first index, index count, material (io::Primitive), covering mesh.indices
//   image.<i>          image i's encoded PNG or JPEG bytes, as the source scene stored them
//   T.<technique>      N x D f32: vertex v's K x L matrix, row-major, at v * D
//   C.<technique>      CPCA (Sloan et al. 2003): u32 clusters C, u32 vectors V, f32 rms error, then
//                      C x D f32 cluster means, C x V x D f32 PCA vectors, N u32 cluster of each vertex,
//                      N x V f32 weights. Vertex v's matrix is mean[c] + sum_j w[v][j] vector[c][j].
// Techniques are named as math::technique() knows them ("gs", "hl2", "sal4", "h4", "h6", "sep4", "prt").

#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace hemi::io
{

struct PrtCpca
{
    uint32_t clusters = 0, vectors = 0;
    float rms_error = 0.0f;        // RMS over all matrix elements of (reconstruction - dense)
    std::vector<float> means;      // C x D
    std::vector<float> basis;      // C x V x D
    std::vector<uint32_t> cluster; // N
    std::vector<float> weights;    // N x V
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
    // The scene's surfaces, self-contained: a moved asset still renders (no file outside it is read).
    std::vector<Material> materials;
    std::vector<EncodedImage> images;  // the encoded PNG/JPEG bytes of the source scene
    std::vector<Primitive> primitives; // ranges of mesh.indices covering all of them, each with its material
                                       // (at least one: an asset is written with its surfaces)
    std::vector<PrtTechnique> techniques;

    uint32_t l() const { return order * order; }
    // Throws std::invalid_argument naming the technique and listing those the asset holds.
    const PrtTechnique& technique(const std::string& name) const;
};

// 2: materials, primitives and images in the asset. Layout 1 (texture paths) is refused with a message to
// re-bake.
constexpr uint32_t kPrtLayoutVersion = 2;

// Validates sizes, finiteness and index ranges (std::invalid_argument), then writes atomically
// (FormatError naming the file on I/O failure).
void write_prt_asset(const std::filesystem::path& path, const PrtAsset& asset);

// Throws FormatError naming the file and the problem: anything AssetReader refuses (missing, wrong magic,
// version, truncated, corrupted), an asset of an older layout, a missing section, inconsistent sizes, an
// unknown technique, an index or cluster out of range, a non-finite value, a malformed material section, or
// surfaces io::surface_problem refuses (a material's image out of range, primitives that do not cover the
// indices, a UV set other than 0 or 1, an image that is not the PNG or JPEG its mime type says). Images are
// checked by signature, not decoded: io::decode_image does that where they are used.
PrtAsset read_prt_asset(const std::filesystem::path& path);
// The same from bytes in memory (an engine's pack file, a memory-mapped archive); `name` names them in
// errors.
PrtAsset read_prt_asset(std::span<const std::byte> bytes, const std::string& name = "<memory>");

} // namespace hemi::io
