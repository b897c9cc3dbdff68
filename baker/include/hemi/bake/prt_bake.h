#pragma once
// The PRT bake of Sloan 2006 (Sec. 3), traced with Embree and multi-threaded with TBB.
//
// Per vertex it computes two transfer operators of distant lighting of order n (L = n^2 SH coefficients,
// object space):
//   M   (9 x L): lighting -> incident radiance at the vertex, in quadratic SH (object space). What normal
//                mapping needs: the pixel evaluates the clamped-cosine convolution of this radiance at its
//                normal-map normal (fold_transfer turns it into each basis's K x L matrix).
//   t   (1 x L): lighting -> irradiance at the vertex normal (the cosine applied exactly, every band): the
//                transfer vector of classic diffuse PRT (Sloan et al. 2002), the paper's comparison without
//                normal maps, and the exit radiance that interreflection bounces carry.
// Transfer kinds:
//   unshadowed     : M = identity (bands 0-2), t = A_l y(n); no rays.
//   shadowed       : the unshadowed operators minus what the rays that hit the model block (a control
//                    variate: unoccluded vertices come out exact, and the white furnace holds there exactly).
//   interreflected : shadowed, plus B bounces of diffuse interreflection. Bounce b gathers, along the same
//                    rays, the exit radiance (albedo / pi) * t_{b-1} interpolated at the hit point.
// Rays per vertex are a jittered spherical Fibonacci set with a per-vertex random offset; the random stream
// is a counter-based hash of (seed, vertex, ray), so the result does not depend on the thread count and the
// same seed gives the same bytes. The rays, the Embree scene they are traced in and the checkpoints are the
// baker's shared parts: hemi/bake/ray_generator.h, embree_scene.h and checkpoint.h.

#include <hemi/bake/distribution.h>
#include <hemi/io/mesh.h>
#include <hemi/io/prt_asset.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace hemi::bake
{

enum class TransferKind
{
    Unshadowed,
    Shadowed,
    Interreflected,
};
// "unshadowed", "shadowed", "interreflected"; parse throws std::invalid_argument naming the bad value.
std::string_view to_string(TransferKind kind);
TransferKind parse_transfer_kind(std::string_view name);

struct PrtBakeOptions
{
    TransferKind kind = TransferKind::Interreflected;
    int order = 5;       // lighting SH order n in [3, 6]: L = n^2
    int rays = 256;      // rays per vertex (>= 1); ignored for unshadowed transfer
    int bounces = 2;     // interreflection bounces (>= 0); used by TransferKind::Interreflected only
    float albedo = 0.6f; // grey diffuse albedo of the model for interreflection, in [0, 1)
    uint64_t seed = 1;   // random stream of the ray directions
    // Ray origins move off the surface by this fraction of the bounding-box diagonal (self-intersection).
    float ray_offset = 1e-4f;
    // Checkpoint file (empty: none). The bake saves its finished work there at most every
    // `checkpoint_seconds` (atomically, between slices of `rays_per_slice` rays) and, when started again with
    // the same mesh and options, resumes from it, giving the same bytes as an uninterrupted bake. A
    // checkpoint of another mesh or other options, or an unreadable one, is ignored and replaced. The bake
    // does not delete it: the caller does once the result is safe (bake_prt_file, after writing the asset).
    std::filesystem::path checkpoint;
    double checkpoint_seconds = 30.0;
    // Rays traced between two progress calls (and possible checkpoints); slices are whole 256-vertex groups.
    uint64_t rays_per_slice = uint64_t(1) << 20;
    // Who computes the vertices (distribution.h): null, this process; else the ranks of a job, which all call
    // bake_prt_transfer with the same arguments and all return the same transfer. Only the leader resumes
    // and saves the checkpoint and reports progress.
    Distribution* distribution = nullptr;
};

struct PrtBakeProgress
{
    int pass = 0;   // 0: direct (visibility), 1..B: interreflection bounces
    int passes = 1; // total passes
    uint64_t vertices_done = 0, vertex_count = 0;
    // Set (from then on) once a checkpoint could not be written: why. The bake goes on without checkpoints;
    // callers report it when it first appears, not after the bake.
    std::string checkpoint_error;
};
using PrtProgressCallback = std::function<void(const PrtBakeProgress&)>;

struct PrtTransfer
{
    uint32_t vertex_count = 0;
    int order = 0;
    std::vector<float> radiance;   // N x 9 x L: M per vertex, row-major, object space
    std::vector<float> irradiance; // N x L: t per vertex
    uint64_t rays_traced = 0;      // rays traced by this call (not those of a resumed checkpoint)
    double seconds = 0.0;          // wall time of this call
    double trace_seconds = 0.0;    // of which the ray passes (not the setup and the BVH build)
    bool resumed = false;          // true when a checkpoint supplied finished work
    int resumed_pass = 0;          // where it resumed: pass, and first vertex of that pass
    uint32_t resumed_vertex = 0;
    std::string checkpoint_error; // why checkpointing stopped (e.g. a full disk); the bake itself went on
    int l() const { return order * order; }
};

// Throws std::invalid_argument for bad options or a mesh without normals for every vertex, and
// std::runtime_error when Embree fails (with Embree's message). `progress` is called from the calling
// thread between slices; an exception it throws stops the bake (what is in the
// checkpoint stays). Slices are `rays_per_slice` rays.
PrtTransfer bake_prt_transfer(const io::Mesh& mesh, const PrtBakeOptions& options,
                              const PrtProgressCallback& progress = {});

// Traces exactly the rays of the bake's first pass (same origins, directions, Embree scene and packets) and
// does nothing else: Embree's own throughput on the bake's rays, what hemi-bench compares the bake's rays/s
// with. The rays are made first; `seconds` receives the time of the tracing alone. Returns the number of
// rays that hit. Holds every ray at once (32 bytes a ray): for benchmarks, not for production meshes.
uint64_t trace_bake_rays(const io::Mesh& mesh, const PrtBakeOptions& options, double& seconds);

// The K x L matrix of one technique for every vertex (N x K x L, row-major per vertex), in the vertex's
// tangent frame: a hemispherical basis name of math::bases() ("sh9", "hl2", "h4", "h6", "sal4", "sep4", ...)
// folds M with the tangent rotation, the cosine convolution and the basis projection; "prt" is t itself
// (K = 1). The mesh must have tangents. Throws std::invalid_argument for an unknown technique.
std::vector<float> fold_technique(const PrtTransfer& transfer, const io::Mesh& mesh,
                                  std::string_view technique);
// K of a technique name (as above); throws std::invalid_argument for an unknown one.
int technique_size(std::string_view technique);

// Every technique `hemi-bake prt` writes by default, in the paper's order.
const std::vector<std::string>& default_techniques();

struct PrtAssetOptions
{
    PrtBakeOptions bake;
    std::vector<std::string> techniques = default_techniques();
    uint32_t cpca_clusters = 0, cpca_vectors = 0; // 0: no CPCA
};

struct PrtTechniqueSummary
{
    std::string name;
    int k = 0;
    size_t dense_bytes = 0, cpca_bytes = 0;
    double cpca_rms = 0.0, cpca_relative = 0.0; // RMS error, and that over the RMS of the dense matrices
};

struct PrtBakeSummary
{
    uint32_t vertices = 0, triangles = 0;
    uint64_t rays = 0;
    double trace_seconds = 0.0, total_seconds = 0.0;
    bool tangents_generated = false;
    size_t materials = 0, primitives = 0, images = 0; // the surfaces the asset carries
    std::vector<std::string> warnings;                // io::GltfScene's: what the scene reader simplified
    bool resumed = false; // from a checkpoint, at pass resumed_pass, vertex resumed_vertex
    int resumed_pass = 0;
    uint32_t resumed_vertex = 0;
    std::string checkpoint_error; // non-empty: checkpoints stopped for this reason (the asset is complete)
    std::vector<PrtTechniqueSummary> techniques;
    // The ranks that shared the bake and the vertices (over all passes) each computed; {n} on one process.
    std::vector<uint64_t> vertices_by_rank;
    double rays_per_second() const { return trace_seconds > 0.0 ? double(rays) / trace_seconds : 0.0; }
};

// Bakes the transfer of `mesh`, folds it for every requested technique and, when asked, compresses each with
// CPCA (dense matrices are kept too). The asset's surfaces are one default material over the whole mesh, no
// images: the caller replaces them with the scene's (bake_prt_file does).
io::PrtAsset make_prt_asset(const io::Mesh& mesh, const PrtAssetOptions& options, PrtBakeSummary& summary,
                            const PrtProgressCallback& progress = {});

// `hemi-bake prt`: reads a glTF 2.0 scene (.gltf or .glb), bakes it and writes the asset atomically, with the
// scene's materials, primitives and images (their encoded bytes: the asset does not refer to the scene's
// files) and its TEXCOORD_1. The summary carries the scene reader's warnings. Unless options.bake.checkpoint
// names another file, the bake checkpoints to ASSET.partial (resuming from it when it matches) and removes it
// once the asset is written. Before any work it checks that the asset and the checkpoint can be written
// (io::check_writable: a missing or read-only folder, a folder in the way, no space), so a bake to an
// unwritable place fails in a moment, not after hours. Throws io::FormatError for bad input files or an
// unwritable output, std::invalid_argument for bad options.
PrtBakeSummary bake_prt_file(const std::filesystem::path& scene, const std::filesystem::path& asset,
                             const PrtAssetOptions& options, const PrtProgressCallback& progress = {});

// The summary and the options as a JSON report (written atomically).
void write_prt_bake_json(const std::filesystem::path& path, const PrtBakeSummary& summary,
                         const PrtAssetOptions& options);

} // namespace hemi::bake
