#include <hemi/bake/checkpoint.h>
#include <hemi/bake/cpca.h>
#include <hemi/bake/embree_scene.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/math/basis.h>
#include <hemi/math/sh.h>

#include "hemi/shared/transfer.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

std::string_view to_string(TransferKind kind)
{
    switch (kind)
    {
    case TransferKind::Unshadowed:
        return "unshadowed";
    case TransferKind::Shadowed:
        return "shadowed";
    case TransferKind::Interreflected:
        return "interreflected";
    }
    return "?";
}

TransferKind parse_transfer_kind(std::string_view name)
{
    for (TransferKind k : {TransferKind::Unshadowed, TransferKind::Shadowed, TransferKind::Interreflected})
        if (to_string(k) == name)
            return k;
    throw std::invalid_argument("hemi: unknown transfer kind '" + std::string(name) +
                                "' (known: unshadowed, shadowed, interreflected)");
}

namespace
{

void check(const io::Mesh& mesh, const PrtBakeOptions& o)
{
    if (o.order < 3 || o.order > 6)
        throw std::invalid_argument("hemi: PRT lighting order " + std::to_string(o.order) +
                                    " is not in [3, 6]");
    if (o.rays < 1 && o.kind != TransferKind::Unshadowed)
        throw std::invalid_argument("hemi: PRT bake needs at least 1 ray per vertex, got " +
                                    std::to_string(o.rays));
    if (o.bounces < 0)
        throw std::invalid_argument("hemi: negative bounce count " + std::to_string(o.bounces));
    if (!(o.albedo >= 0.0f && o.albedo < 1.0f))
        throw std::invalid_argument("hemi: interreflection albedo " + std::to_string(o.albedo) +
                                    " is not in [0, 1)");
    if (o.rays_per_slice == 0)
        throw std::invalid_argument("hemi: rays_per_slice must be positive");
    if (!(o.ray_offset >= 0.0f && o.ray_offset < 0.1f))
        throw std::invalid_argument("hemi: ray offset must be in [0, 0.1)");
    if (std::string problem = io::mesh_problem(mesh, io::MeshNeeds::Normals); !problem.empty())
        throw std::invalid_argument("hemi: PRT bake: " + problem);
}

constexpr uint32_t kCheckpointVersion = 3; // 3: the rays' angles from a table of turns (ray_generator.cpp)

// Everything the bake's result depends on: the geometry, every option that changes a number, the layout.
uint64_t checkpoint_key(const io::Mesh& mesh, const PrtBakeOptions& o)
{
    CheckpointKey key(kCheckpointVersion);
    key.add_array<glm::vec3>(mesh.positions);
    key.add_array<glm::vec3>(mesh.normals);
    key.add_array<uint32_t>(mesh.indices);
    const int ints[4] = {int(o.kind), o.order, o.rays, o.bounces};
    const float floats[2] = {o.albedo, o.ray_offset};
    key.add_value(ints);
    key.add_value(floats);
    key.add_value(o.seed);
    key.add_value(EmbreeScene::embree_version());
    return key.digest();
}

} // namespace

PrtTransfer bake_prt_transfer(const io::Mesh& mesh, const PrtBakeOptions& o,
                              const PrtProgressCallback& progress)
{
    check(mesh, o);
    const auto t0 = std::chrono::steady_clock::now();
    const uint32_t n = uint32_t(mesh.vertex_count());
    const int L = o.order * o.order;
    PrtTransfer out;
    out.vertex_count = n;
    out.order = o.order;
    out.radiance.assign(size_t(n) * 9 * L, 0.0f);
    out.irradiance.assign(size_t(n) * L, 0.0f);

    // Unshadowed: M = identity on bands 0-2, t = A_l y_lm(n).
    std::vector<float> cosine(L);
    for (int l = 0; l < o.order; ++l)
        for (int m = -l; m <= l; ++m)
            cosine[math::sh_index(l, m)] = float(math::clamped_cosine_factor(l));
    tbb::parallel_for(uint32_t(0), n,
                      [&](uint32_t v)
                      {
                          for (int i = 0; i < 9; ++i)
                              out.radiance[(size_t(v) * 9 + i) * L + i] = 1.0f;
                          float y[36];
                          math::sh_eval(o.order, glm::normalize(mesh.normals[v]), std::span<float>(y, L));
                          for (int c = 0; c < L; ++c)
                              out.irradiance[size_t(v) * L + c] = cosine[c] * y[c];
                      });
    if (o.kind == TransferKind::Unshadowed)
        return out;

    const EmbreeScene embree(mesh);
    const float offset = embree.ray_offset(o.ray_offset);
    const float weight = 4.0f * float(M_PI) / float(o.rays);
    const int passes = 1 + (o.kind == TransferKind::Interreflected ? o.bounces : 0);

    // Exit radiance per vertex of the previous pass, as an L-vector over the lighting: (albedo / pi) t_{b-1}.
    std::vector<float> exitant(size_t(n) * L), bounce_irradiance(size_t(n) * L);
    // The finished work, all of it: M and t so far, and the bounce being gathered with its source.
    Distribution& dist = o.distribution ? *o.distribution : local_distribution();
    const uint64_t key = checkpoint_key(mesh, o);
    dist.check_same(key, "baked a PRT transfer whose mesh or options");
    SliceCheckpoint checkpoint(dist.leader() ? o.checkpoint : std::filesystem::path(), key, uint32_t(passes),
                               n,
                               {{"radiance", std::as_writable_bytes(std::span<float>(out.radiance))},
                                {"irradiance", std::as_writable_bytes(std::span<float>(out.irradiance))},
                                {"exitant", std::as_writable_bytes(std::span<float>(exitant))},
                                {"bounce", std::as_writable_bytes(std::span<float>(bounce_irradiance))}},
                               o.checkpoint_seconds);
    SlicePosition state;
    if (const std::optional<SlicePosition> resumed = checkpoint.resume(dist)) // every rank from the leader's
    {
        state = *resumed;
        out.resumed = true;
        out.resumed_pass = int(state.pass);
        out.resumed_vertex = state.next_item;
    }
    // Slices of rays_per_slice rays: progress and checkpoints happen between slices, on this thread.
    const uint32_t slice = std::max<uint32_t>(
        256, uint32_t(std::min<uint64_t>(n, o.rays_per_slice / uint64_t(o.rays))) / 256 * 256);
    const auto trace_start = std::chrono::steady_clock::now();
    for (int pass = int(state.pass); pass < passes; ++pass)
    {
        const bool resuming_mid_pass = pass == int(state.pass) && state.next_item > 0;
        if (pass > 0 && !resuming_mid_pass)
        {
            // Bounce 1 gathers the direct (shadowed) irradiance; later bounces the previous bounce's.
            const std::vector<float>& previous = pass == 1 ? out.irradiance : bounce_irradiance;
            for (size_t i = 0; i < exitant.size(); ++i)
                exitant[i] = float(o.albedo / M_PI) * previous[i];
            std::fill(bounce_irradiance.begin(), bounce_irradiance.end(), 0.0f);
        }
        constexpr uint32_t kChunk = 256;
        auto work = [&](const tbb::blocked_range<uint32_t>& range)
        {
            // A vertex's rays, traced together (EmbreeScene's packets); then, per ray that counts, its SH
            // y (a column of Y) and what it carries, x (a column of X; X = Y in the first pass) and its
            // clamped cosine w; then M += sign Y_{0..8} X^T and t += sign X w as matrix products (Eigen's,
            // blocked).
            std::vector<glm::vec3> directions(size_t(o.rays));
            std::vector<Ray> rays(size_t(o.rays));
            std::vector<std::optional<RayHit>> hits(size_t(o.rays));
            Eigen::MatrixXf Y(L, o.rays), X(L, pass == 0 ? 0 : o.rays);
            Eigen::VectorXf w(o.rays);
            for (uint32_t v = range.begin(); v != range.end(); ++v)
            {
                const glm::vec3 normal = glm::normalize(mesh.normals[v]);
                const glm::vec3 origin = offset_ray_origin(mesh.positions[v], normal, offset);
                sphere_directions(o.seed, v, directions);
                for (size_t r = 0; r < rays.size(); ++r)
                    rays[r] = {origin, 0.0f, directions[r], INFINITY};
                embree.intersect(rays, hits);
                Eigen::Index k = 0; // the rays that count so far
                for (size_t r = 0; r < rays.size(); ++r)
                {
                    const glm::vec3& d = directions[r];
                    const std::optional<RayHit>& hit = hits[r];
                    if (!hit)
                        continue;
                    const float cosine_weight = std::max(0.0f, glm::dot(normal, d));
                    // The first pass: the blocked radiance, the receiver (y_i for M, the clamped cosine for
                    // t) times y_c.
                    if (pass > 0)
                    {
                        // Bounced light arrives only from above the surface and leaves only the front of
                        // the surface it hit (counter-clockwise seen from outside): a ray below the tangent
                        // plane that hits the surface next to its origin carries no light to it.
                        if (cosine_weight <= 0.0f ||
                            glm::dot(embree.geometric_normal(hit->primitive), d) >= 0.0f)
                            continue;
                        const uint32_t* tri = &mesh.indices[size_t(hit->primitive) * 3];
                        const float bu = hit->u, bv = hit->v, w0 = 1.0f - bu - bv;
                        float* x = X.col(k).data();
                        for (int c = 0; c < L; ++c)
                            x[c] = w0 * exitant[size_t(tri[0]) * L + c] +
                                   bu * exitant[size_t(tri[1]) * L + c] +
                                   bv * exitant[size_t(tri[2]) * L + c];
                    }
                    math::sh_eval(o.order, d, std::span<float>(Y.col(k).data(), size_t(L)));
                    w[k] = cosine_weight;
                    ++k;
                }
                const float sign = pass == 0 ? -weight : weight;
                Eigen::Map<Eigen::Matrix<float, 9, Eigen::Dynamic, Eigen::RowMajor>> m(
                    &out.radiance[size_t(v) * 9 * L], 9, L);
                Eigen::Map<Eigen::VectorXf> t(
                    pass == 0 ? &out.irradiance[size_t(v) * L] : &bounce_irradiance[size_t(v) * L], L);
                if (k == 0)
                    continue;
                if (pass == 0)
                {
                    m.noalias() += sign * (Y.topLeftCorner(9, k) * Y.leftCols(k).transpose());
                    t.noalias() += sign * (Y.leftCols(k) * w.head(k));
                }
                else
                {
                    m.noalias() += sign * (Y.topLeftCorner(9, k) * X.leftCols(k).transpose());
                    t.noalias() += sign * (X.leftCols(k) * w.head(k));
                }
            }
        };
        const uint32_t first = resuming_mid_pass ? state.next_item : 0;
        if (first == n)
            continue; // resumed after this pass was added in
        if (progress && dist.leader())
            progress({pass, passes, first, n, checkpoint.error()});
        // What a vertex's work writes (it adds to M, and to t or the bounce), which every rank gathers.
        float* t_array = pass == 0 ? out.irradiance.data() : bounce_irradiance.data();
        const ItemArray arrays[2] = {{reinterpret_cast<std::byte*>(out.radiance.data()), size_t(9) * L * 4},
                                     {reinterpret_cast<std::byte*>(t_array), size_t(L) * 4}};
        dist.run(
            first, n, slice, arrays,
            [&](uint32_t begin, uint32_t end)
            { tbb::parallel_for(tbb::blocked_range<uint32_t>(begin, end, kChunk), work); },
            [&](uint32_t next)
            {
                checkpoint.slice_done(uint32_t(pass), next);
                if (progress)
                    progress({pass, passes, next, n, checkpoint.error()});
            });
        out.rays_traced += uint64_t(n - first) * uint64_t(o.rays);
        if (pass > 0)
            for (size_t i = 0; i < out.irradiance.size(); ++i)
                out.irradiance[i] += bounce_irradiance[i];
        checkpoint.slice_done(uint32_t(pass), n);
        if (progress && dist.leader())
            progress({pass, passes, n, n, checkpoint.error()});
    }
    out.checkpoint_error = checkpoint.error();
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.trace_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - trace_start).count();
    return out;
}

uint64_t trace_bake_rays(const io::Mesh& mesh, const PrtBakeOptions& o, double& seconds)
{
    check(mesh, o);
    const EmbreeScene embree(mesh);
    const float offset = embree.ray_offset(o.ray_offset);
    const uint32_t n = uint32_t(mesh.vertex_count());
    // Every ray first (not timed), then only the tracing: the bake's queries, vertex by vertex.
    const size_t per = size_t(o.rays);
    std::vector<Ray> rays(size_t(n) * per);
    tbb::parallel_for(uint32_t(0), n,
                      [&](uint32_t v)
                      {
                          std::vector<glm::vec3> directions(per);
                          sphere_directions(o.seed, v, directions);
                          const glm::vec3 origin =
                              offset_ray_origin(mesh.positions[v], glm::normalize(mesh.normals[v]), offset);
                          for (size_t r = 0; r < per; ++r)
                              rays[v * per + r] = {origin, 0.0f, directions[r], INFINITY};
                      });
    std::atomic<uint64_t> hits{0};
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n, 256),
                      [&](const tbb::blocked_range<uint32_t>& range)
                      {
                          uint64_t local = 0;
                          std::vector<std::optional<RayHit>> found(per);
                          for (uint32_t v = range.begin(); v != range.end(); ++v)
                          {
                              embree.intersect(std::span<const Ray>(rays).subspan(v * per, per), found);
                              for (const std::optional<RayHit>& hit : found)
                                  local += hit.has_value();
                          }
                          hits += local;
                      });
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return hits;
}

int technique_size(std::string_view technique)
{
    return math::technique(technique).size;
}

std::vector<float> fold_technique(const PrtTransfer& transfer, const io::Mesh& mesh,
                                  std::string_view technique)
{
    const math::BasisDesc& basis = math::technique(technique);
    const uint32_t n = transfer.vertex_count;
    const int L = transfer.l();
    if (basis.id == HEMI_BASIS_VERTEX_IRRADIANCE)
        return transfer.irradiance;
    if (mesh.vertex_count() != n || mesh.tangents.size() != n)
        throw std::invalid_argument("hemi: folding " + std::string(technique) +
                                    " needs the baked mesh with a tangent per vertex");
    const TransferFold fold(basis);
    std::vector<float> out(size_t(n) * basis.size * L);
    tbb::parallel_for(uint32_t(0), n,
                      [&](uint32_t v)
                      {
                          // Rotate M's rows (SH9 of incident radiance) from object space into the tangent
                          // frame. A file's tangent need not be exactly perpendicular to its normal:
                          // Gram-Schmidt, so that the frame is a rotation.
                          const glm::vec3 nrm = glm::normalize(mesh.normals[v]);
                          glm::vec3 tan =
                              glm::vec3(mesh.tangents[v]) - glm::dot(glm::vec3(mesh.tangents[v]), nrm) * nrm;
                          if (glm::dot(tan, tan) < 1e-12f)
                              tan = std::abs(nrm.x) < 0.9f ? glm::cross(nrm, glm::vec3(1, 0, 0))
                                                           : glm::cross(nrm, glm::vec3(0, 1, 0));
                          const glm::mat3 r = object_to_tangent(nrm, glm::normalize(tan), mesh.tangents[v].w);
                          const std::vector<float> d9 = unshadowed_transfer(r, 3); // the 9 x 9 SH9 rotation
                          std::vector<float> rm(size_t(9) * L, 0.0f);
                          const float* m = &transfer.radiance[size_t(v) * 9 * L];
                          for (int i = 0; i < 9; ++i)
                              for (int j = 0; j < 9; ++j)
                              {
                                  const float dij = d9[size_t(i) * 9 + j];
                                  if (dij != 0.0f)
                                      for (int c = 0; c < L; ++c)
                                          rm[size_t(i) * L + c] += dij * m[size_t(j) * L + c];
                              }
                          const std::vector<float> t = fold.apply(rm, L);
                          std::copy(t.begin(), t.end(), out.begin() + ptrdiff_t(v) * basis.size * L);
                      });
    return out;
}

} // namespace hemi::bake

namespace hemi::bake
{

const std::vector<std::string>& default_techniques()
{
    static const std::vector<std::string> names = {"prt", "gs", "sep4", "sal4", "hl2", "h4", "h6"};
    return names;
}

io::PrtAsset make_prt_asset(const io::Mesh& mesh, const PrtAssetOptions& options, PrtBakeSummary& summary,
                            const PrtProgressCallback& progress)
{
    const auto t0 = std::chrono::steady_clock::now();
    if (options.techniques.empty())
        throw std::invalid_argument("hemi: no techniques to bake");
    for (size_t i = 0; i < options.techniques.size(); ++i)
    {
        math::technique(options.techniques[i]); // throws for an unknown name
        for (size_t j = 0; j < i; ++j)
            if (options.techniques[j] == options.techniques[i])
                throw std::invalid_argument("hemi: technique '" + options.techniques[i] +
                                            "' requested twice");
    }
    if ((options.cpca_clusters == 0) != (options.cpca_vectors == 0))
        throw std::invalid_argument("hemi: CPCA needs both a cluster and a vector count");
    if (options.cpca_vectors > HEMI_CPCA_MAX_VECTORS)
        throw std::invalid_argument("hemi: CPCA with " + std::to_string(options.cpca_vectors) +
                                    " vectors per cluster; the runtime pass supports up to " +
                                    std::to_string(HEMI_CPCA_MAX_VECTORS));
    if (mesh.tangents.size() != mesh.vertex_count() || mesh.uvs.size() != mesh.vertex_count())
        throw std::invalid_argument("hemi: the PRT bake needs a tangent and UV per vertex");

    Distribution& dist = options.bake.distribution ? *options.bake.distribution : local_distribution();
    const std::vector<uint64_t> items_before = dist.items_by_rank();
    const PrtTransfer transfer = bake_prt_transfer(mesh, options.bake, progress);
    std::vector<uint64_t> vertices_by_rank = dist.items_by_rank();
    for (size_t r = 0; r < vertices_by_rank.size() && r < items_before.size(); ++r)
        vertices_by_rank[r] -= items_before[r];
    if (options.bake.distribution && !options.bake.distribution->leader())
        return {}; // the transfer is on rank 0: its folds, CPCA and asset
    io::PrtAsset asset;
    asset.mesh = mesh;
    asset.order = uint32_t(options.bake.order);
    asset.transfer_kind = uint32_t(options.bake.kind);
    asset.bounces = options.bake.kind == TransferKind::Interreflected ? uint32_t(options.bake.bounces) : 0;
    asset.rays = options.bake.kind == TransferKind::Unshadowed ? 0 : uint32_t(options.bake.rays);
    asset.seed = options.bake.seed;
    asset.albedo = options.bake.albedo;
    asset.materials = {io::Material{}};
    asset.materials[0].name = "default";
    asset.primitives = {io::Primitive{0, uint32_t(mesh.indices.size()), 0}};
    summary = {};
    summary.vertices_by_rank = std::move(vertices_by_rank);
    summary.materials = 1;
    summary.primitives = 1;
    summary.vertices = uint32_t(mesh.vertex_count());
    summary.triangles = uint32_t(mesh.indices.size() / 3);
    summary.rays = transfer.rays_traced;
    summary.trace_seconds = transfer.trace_seconds;
    summary.resumed = transfer.resumed;
    summary.resumed_pass = transfer.resumed_pass;
    summary.resumed_vertex = transfer.resumed_vertex;
    summary.checkpoint_error = transfer.checkpoint_error;
    const uint32_t n = transfer.vertex_count, L = uint32_t(transfer.l());
    for (const std::string& name : options.techniques)
    {
        io::PrtTechnique t;
        t.name = name;
        t.k = uint32_t(technique_size(name));
        t.matrices = fold_technique(transfer, mesh, name);
        PrtTechniqueSummary s;
        s.name = name;
        s.k = int(t.k);
        s.dense_bytes = t.matrices.size() * sizeof(float);
        if (options.cpca_clusters)
        {
            t.cpca = compress_cpca(t.matrices, n, t.k * L, std::min(options.cpca_clusters, n),
                                   options.cpca_vectors);
            const io::PrtCpca& c = *t.cpca;
            s.cpca_bytes = (c.means.size() + c.basis.size() + c.cluster.size() + c.weights.size()) * 4;
            s.cpca_rms = c.rms_error;
            double squares = 0.0;
            for (float v : t.matrices)
                squares += double(v) * v;
            const double rms = std::sqrt(squares / double(t.matrices.size()));
            s.cpca_relative = rms > 0.0 ? c.rms_error / rms : 0.0;
        }
        summary.techniques.push_back(s);
        asset.techniques.push_back(std::move(t));
    }
    summary.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return asset;
}

PrtBakeSummary bake_prt_file(const std::filesystem::path& scene_path, const std::filesystem::path& asset_path,
                             const PrtAssetOptions& options, const PrtProgressCallback& progress)
{
    PrtAssetOptions o = options;
    if (o.bake.checkpoint.empty())
        o.bake.checkpoint = checkpoint_path(asset_path);
    // Under a distribution, the other ranks only compute: rank 0 checks and writes every output.
    const bool leader = !o.bake.distribution || o.bake.distribution->leader();
    // Fail fast: the outputs' folders are checked before the scene is even read.
    // One job per output: a second bake to the same asset (and checkpoint) is refused, naming the first.
    std::optional<io::OutputLock> lock;
    if (leader)
    {
        io::check_writable(asset_path);
        io::check_writable(o.bake.checkpoint);
        lock.emplace(asset_path);
    }
    const io::GltfScene scene = io::read_gltf(scene_path);
    // The asset carries the scene's images: each is decoded once now, so a corrupt one stops the bake
    // before it starts rather than the renderer after it.
    io::check_images(scene.images, scene_path.string());
    PrtBakeSummary summary;
    io::PrtAsset asset = make_prt_asset(scene.mesh, o, summary, progress); // scene.mesh: uvs1 included
    if (!leader)
        return summary;
    summary.tangents_generated = scene.tangents_generated;
    asset.materials = scene.materials;
    asset.images = scene.images;
    asset.primitives = scene.primitives;
    summary.materials = asset.materials.size();
    summary.primitives = asset.primitives.size();
    summary.images = asset.images.size();
    summary.warnings = scene.warnings;
    if (!scene.lights.empty())
        summary.warnings.push_back(
            std::to_string(scene.lights.size()) +
            " KHR_lights_punctual light(s) ignored: PRT relights the scene from distant "
            "environments at run time (hemi-bake lightmap bakes them)");
    io::write_prt_asset(asset_path, asset);
    remove_checkpoint(o.bake.checkpoint); // the finished work is in the asset now
    return summary;
}

void write_prt_bake_json(const std::filesystem::path& path, const PrtBakeSummary& s, const PrtAssetOptions& o)
{
    nlohmann::json j;
    j["transfer"] = std::string(to_string(o.bake.kind));
    j["order"] = o.bake.order;
    j["rays_per_vertex"] = o.bake.rays;
    j["bounces"] = o.bake.bounces;
    j["albedo"] = o.bake.albedo;
    j["seed"] = o.bake.seed;
    j["vertices"] = s.vertices;
    j["triangles"] = s.triangles;
    j["tangents_generated"] = s.tangents_generated;
    j["materials"] = s.materials;
    j["primitives"] = s.primitives;
    j["images"] = s.images;
    j["warnings"] = s.warnings;
    j["rays"] = s.rays;
    j["trace_seconds"] = s.trace_seconds;
    j["total_seconds"] = s.total_seconds;
    j["rays_per_second"] = s.rays_per_second();
    j["ranks"] = s.vertices_by_rank.size();
    j["vertices_by_rank"] = s.vertices_by_rank; // over all passes: how the ranks shared the work
    if (s.resumed)
        j["resumed"] = {{"pass", s.resumed_pass}, {"vertex", s.resumed_vertex}};
    if (o.cpca_clusters)
        j["cpca"] = {{"clusters", o.cpca_clusters}, {"vectors", o.cpca_vectors}};
    for (const PrtTechniqueSummary& t : s.techniques)
    {
        nlohmann::json e = {{"name", t.name}, {"k", t.k}, {"dense_bytes", t.dense_bytes}};
        if (o.cpca_clusters)
        {
            e["cpca_bytes"] = t.cpca_bytes;
            e["cpca_rms_error"] = t.cpca_rms;
            e["cpca_relative_error"] = t.cpca_relative;
        }
        j["techniques"].push_back(e);
    }
    io::write_text_atomically(path, j.dump(2) + "\n");
}

} // namespace hemi::bake
