#include <hemi/bake/cpca.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/math/basis.h>
#include <hemi/math/sh.h>

#include <hemi/io/asset.h>

#include "hemi/shared/transfer.h"

#include <embree3/rtcore.h>
#include <nlohmann/json.hpp>
#define XXH_INLINE_ALL
#include <xxhash.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <fstream>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

std::string_view to_string(TransferKind kind)
{
    switch (kind)
    {
    case TransferKind::Unshadowed: return "unshadowed";
    case TransferKind::Shadowed: return "shadowed";
    case TransferKind::Interreflected: return "interreflected";
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

// Counter-based random numbers (SplitMix64 finaliser): the value depends only on its inputs, never on
// scheduling.
uint64_t mix(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
float uniform01(uint64_t seed, uint64_t a, uint64_t b)
{
    return float(mix(mix(mix(seed) ^ a) ^ (b * 0x632be59bd9b4e019ull)) >> 40) * (1.0f / 16777216.0f);
}

// Ray i of R for a vertex: jittered spherical Fibonacci (stratified in z, golden-angle spaced in phi) with a
// per-vertex random rotation about z. Uniform on the sphere; each ray stands for 4 pi / R steradians.
glm::vec3 ray_direction(uint64_t seed, uint32_t vertex, int i, int rays)
{
    const float z = 1.0f - 2.0f * (float(i) + uniform01(seed, vertex, uint64_t(i) + 1)) / float(rays);
    const float offset = uniform01(seed, vertex, 0);
    float frac = float(i) * 0.6180339887f + offset;
    frac -= std::floor(frac);
    const float phi = 2.0f * float(M_PI) * frac, s = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

struct EmbreeScene
{
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::mutex error_mutex; // Embree may report from its worker threads
    std::string error;

    explicit EmbreeScene(const io::Mesh& mesh)
    {
        device = rtcNewDevice(nullptr);
        if (!device)
            throw std::runtime_error("hemi: Embree device creation failed (error " +
                                     std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
        rtcSetDeviceErrorFunction(
            device,
            [](void* user, RTCError, const char* message) {
                auto* self = static_cast<EmbreeScene*>(user);
                std::lock_guard<std::mutex> lock(self->error_mutex);
                self->error = message ? message : "unknown Embree error";
            },
            this);
        scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.vertex_count()));
        auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                  RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
                                                                  mesh.indices.size() / 3));
        if (!vb || !ib)
        {
            rtcReleaseGeometry(geometry);
            fail("allocating the geometry");
        }
        for (size_t v = 0; v < mesh.vertex_count(); ++v)
            for (int c = 0; c < 3; ++c)
                vb[v * 3 + c] = mesh.positions[v][c];
        std::copy(mesh.indices.begin(), mesh.indices.end(), ib);
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(scene, geometry);
        rtcReleaseGeometry(geometry);
        rtcCommitScene(scene);
        bool failed;
        {
            std::lock_guard<std::mutex> lock(error_mutex);
            failed = !error.empty();
        }
        if (failed)
            fail("building the scene");
    }
    ~EmbreeScene() { release(); }
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    void release()
    {
        if (scene)
            rtcReleaseScene(scene);
        if (device)
            rtcReleaseDevice(device);
        scene = nullptr;
        device = nullptr;
    }

    // From the constructor: the destructor will not run, so the handles are released here.
    [[noreturn]] void fail(const std::string& what)
    {
        std::string message;
        {
            std::lock_guard<std::mutex> lock(error_mutex);
            message = "hemi: Embree failed " + what + (error.empty() ? "" : ": " + error);
        }
        release();
        throw std::runtime_error(message);
    }

    // Closest hit along the ray; returns false on a miss.
    bool intersect(const glm::vec3& origin, const glm::vec3& dir, uint32_t& prim, float& u, float& v) const
    {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rh{};
        rh.ray.org_x = origin.x;
        rh.ray.org_y = origin.y;
        rh.ray.org_z = origin.z;
        rh.ray.dir_x = dir.x;
        rh.ray.dir_y = dir.y;
        rh.ray.dir_z = dir.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = 0xffffffffu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
            return false;
        prim = rh.hit.primID;
        u = rh.hit.u;
        v = rh.hit.v;
        return true;
    }
};

void check(const io::Mesh& mesh, const PrtBakeOptions& o)
{
    if (o.order < 3 || o.order > 6)
        throw std::invalid_argument("hemi: PRT lighting order " + std::to_string(o.order) + " is not in [3, 6]");
    if (o.rays < 1 && o.kind != TransferKind::Unshadowed)
        throw std::invalid_argument("hemi: PRT bake needs at least 1 ray per vertex, got " + std::to_string(o.rays));
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

// Where a bake stands: passes before `pass` are complete, and so are vertices [0, next_vertex) of `pass`.
struct BakeState
{
    uint32_t pass, next_vertex;
};

constexpr uint32_t kCheckpointVersion = 2;

// Everything the bake's result depends on: the geometry, every option that changes a number, the layout.
uint64_t checkpoint_key(const io::Mesh& mesh, const PrtBakeOptions& o)
{
    XXH64_state_t* h = XXH64_createState();
    XXH64_reset(h, kCheckpointVersion);
    XXH64_update(h, mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
    XXH64_update(h, mesh.normals.data(), mesh.normals.size() * sizeof(glm::vec3));
    XXH64_update(h, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
    const int ints[4] = {int(o.kind), o.order, o.rays, o.bounces};
    const float floats[2] = {o.albedo, o.ray_offset};
    XXH64_update(h, ints, sizeof ints);
    XXH64_update(h, floats, sizeof floats);
    XXH64_update(h, &o.seed, sizeof o.seed);
    const int embree_version = RTC_VERSION;
    XXH64_update(h, &embree_version, sizeof embree_version);
    const uint64_t key = XXH64_digest(h);
    XXH64_freeState(h);
    return key;
}

void save_checkpoint(const std::filesystem::path& path, uint64_t key, const BakeState& state, const PrtTransfer& t,
                     const std::vector<float>& exitant, const std::vector<float>& bounce)
{
    io::AssetWriter w;
    w.add_array<uint64_t>("ckpt.key", std::span<const uint64_t>(&key, 1));
    w.add("ckpt.state", std::as_bytes(std::span<const BakeState>(&state, 1)));
    w.add_array<float>("ckpt.radiance", t.radiance);
    w.add_array<float>("ckpt.irradiance", t.irradiance);
    w.add_array<float>("ckpt.exitant", exitant);
    w.add_array<float>("ckpt.bounce", bounce);
    w.write(path);
}

// Restores a checkpoint written for the same key; false (and nothing touched) when there is none, it is
// unreadable or corrupt, or it belongs to another mesh or other options.
bool load_checkpoint(const std::filesystem::path& path, uint64_t key, int passes, BakeState& state, PrtTransfer& t,
                     std::vector<float>& exitant, std::vector<float>& bounce)
{
    if (!std::filesystem::exists(path))
        return false;
    try
    {
        const io::AssetReader r(path);
        const std::vector<uint64_t> stored = r.array<uint64_t>("ckpt.key");
        const std::span<const std::byte> s = r.section("ckpt.state");
        if (stored.size() != 1 || stored[0] != key || s.size() != sizeof(BakeState))
            return false;
        BakeState loaded;
        std::memcpy(&loaded, s.data(), sizeof loaded);
        std::vector<float> radiance = r.array<float>("ckpt.radiance"), irradiance = r.array<float>("ckpt.irradiance"),
                           ex = r.array<float>("ckpt.exitant"), bo = r.array<float>("ckpt.bounce");
        if (radiance.size() != t.radiance.size() || irradiance.size() != t.irradiance.size() ||
            ex.size() != exitant.size() || bo.size() != bounce.size())
            return false;
        // Only states save_checkpoint writes: inside the bake, never at its very start or end.
        if (loaded.pass >= uint32_t(passes) || loaded.next_vertex >= t.vertex_count ||
            (loaded.pass == 0 && loaded.next_vertex == 0))
            return false;
        state = loaded;
        t.radiance = std::move(radiance);
        t.irradiance = std::move(irradiance);
        exitant = std::move(ex);
        bounce = std::move(bo);
        return true;
    }
    catch (const io::FormatError&)
    {
        return false;
    }
}

// How far ray origins move off the surface along the normal: a fraction of the bounding-box diagonal.
float ray_offset_distance(const io::Mesh& mesh, const PrtBakeOptions& o)
{
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : mesh.positions)
    {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    return o.ray_offset * glm::length(hi - lo);
}

} // namespace

PrtTransfer bake_prt_transfer(const io::Mesh& mesh, const PrtBakeOptions& o, const PrtProgressCallback& progress)
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
    tbb::parallel_for(uint32_t(0), n, [&](uint32_t v) {
        for (int i = 0; i < 9; ++i)
            out.radiance[(size_t(v) * 9 + i) * L + i] = 1.0f;
        float y[36];
        math::sh_eval(o.order, glm::normalize(mesh.normals[v]), std::span<float>(y, L));
        for (int c = 0; c < L; ++c)
            out.irradiance[size_t(v) * L + c] = cosine[c] * y[c];
    });
    if (o.kind == TransferKind::Unshadowed)
        return out;

    EmbreeScene embree(mesh);
    const float offset = ray_offset_distance(mesh, o);
    const float weight = 4.0f * float(M_PI) / float(o.rays);
    const int passes = 1 + (o.kind == TransferKind::Interreflected ? o.bounces : 0);

    // Exit radiance per vertex of the previous pass, as an L-vector over the lighting: (albedo / pi) t_{b-1}.
    std::vector<float> exitant(size_t(n) * L), bounce_irradiance(size_t(n) * L);
    BakeState state{0, 0};
    const uint64_t key = checkpoint_key(mesh, o);
    if (!o.checkpoint.empty() && load_checkpoint(o.checkpoint, key, passes, state, out, exitant, bounce_irradiance))
    {
        out.resumed = true;
        out.resumed_pass = int(state.pass);
        out.resumed_vertex = state.next_vertex;
    }
    auto last_checkpoint = std::chrono::steady_clock::now();
    bool checkpointing = !o.checkpoint.empty();
    // Slices of rays_per_slice rays: progress and checkpoints happen between slices, on this thread.
    const uint32_t slice =
        std::max<uint32_t>(256, uint32_t(std::min<uint64_t>(n, o.rays_per_slice / uint64_t(o.rays))) / 256 * 256);
    for (int pass = int(state.pass); pass < passes; ++pass)
    {
        const bool resuming_mid_pass = pass == int(state.pass) && state.next_vertex > 0;
        if (pass > 0 && !resuming_mid_pass)
        {
            // Bounce 1 gathers the direct (shadowed) irradiance; later bounces the previous bounce's.
            const std::vector<float>& previous = pass == 1 ? out.irradiance : bounce_irradiance;
            for (size_t i = 0; i < exitant.size(); ++i)
                exitant[i] = float(o.albedo / M_PI) * previous[i];
            std::fill(bounce_irradiance.begin(), bounce_irradiance.end(), 0.0f);
        }
        constexpr uint32_t kChunk = 256;
        auto work = [&](const tbb::blocked_range<uint32_t>& range) {
            float y[36], x[36];
            std::vector<float> m_acc(size_t(9) * L), t_acc(L);
            for (uint32_t v = range.begin(); v != range.end(); ++v)
            {
                std::fill(m_acc.begin(), m_acc.end(), 0.0f);
                std::fill(t_acc.begin(), t_acc.end(), 0.0f);
                const glm::vec3 normal = glm::normalize(mesh.normals[v]);
                const glm::vec3 origin = mesh.positions[v] + offset * normal;
                for (int r = 0; r < o.rays; ++r)
                {
                    const glm::vec3 d = ray_direction(o.seed, v, r, o.rays);
                    uint32_t prim;
                    float bu, bv;
                    if (!embree.intersect(origin, d, prim, bu, bv))
                        continue;
                    math::sh_eval(o.order, d, std::span<float>(y, L));
                    const float cosine_weight = std::max(0.0f, glm::dot(normal, d));
                    if (pass == 0)
                    {
                        // The blocked radiance: the receiver (y_i for M, the clamped cosine for t) times y_c.
                        for (int c = 0; c < L; ++c)
                            x[c] = y[c];
                    }
                    else
                    {
                        // Bounced light arrives only from above the surface and leaves only the front of
                        // the surface it hit (counter-clockwise seen from outside): a ray below the tangent
                        // plane that hits the surface next to its origin carries no light to it.
                        const uint32_t* tri = &mesh.indices[size_t(prim) * 3];
                        const glm::vec3 face = glm::cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                                                          mesh.positions[tri[2]] - mesh.positions[tri[0]]);
                        if (cosine_weight <= 0.0f || glm::dot(face, d) >= 0.0f)
                            continue;
                        // Embree's barycentrics: p = (1 - u - v) p0 + u p1 + v p2.
                        const float w0 = 1.0f - bu - bv;
                        for (int c = 0; c < L; ++c)
                            x[c] = w0 * exitant[size_t(tri[0]) * L + c] + bu * exitant[size_t(tri[1]) * L + c] +
                                   bv * exitant[size_t(tri[2]) * L + c];
                    }
                    for (int i = 0; i < 9; ++i)
                        for (int c = 0; c < L; ++c)
                            m_acc[size_t(i) * L + c] += y[i] * x[c];
                    for (int c = 0; c < L; ++c)
                        t_acc[c] += cosine_weight * x[c];
                }
                const float sign = pass == 0 ? -weight : weight;
                float* m = &out.radiance[size_t(v) * 9 * L];
                for (size_t i = 0; i < m_acc.size(); ++i)
                    m[i] += sign * m_acc[i];
                float* t = pass == 0 ? &out.irradiance[size_t(v) * L] : &bounce_irradiance[size_t(v) * L];
                for (int c = 0; c < L; ++c)
                    t[c] += sign * t_acc[c];
            }
        };
        uint32_t first = resuming_mid_pass ? state.next_vertex : 0;
        if (progress)
            progress({pass, passes, first, n});
        while (first < n)
        {
            const uint32_t last = std::min(n, first + slice);
            tbb::parallel_for(tbb::blocked_range<uint32_t>(first, last, kChunk), work);
            out.rays_traced += uint64_t(last - first) * uint64_t(o.rays);
            first = last;
            if (first == n && pass > 0)
                for (size_t i = 0; i < out.irradiance.size(); ++i)
                    out.irradiance[i] += bounce_irradiance[i];
            if (checkpointing && (first < n || pass + 1 < passes) &&
                std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint).count() >=
                    o.checkpoint_seconds)
            {
                const BakeState now = first < n ? BakeState{uint32_t(pass), first} : BakeState{uint32_t(pass + 1), 0};
                try
                {
                    save_checkpoint(o.checkpoint, key, now, out, exitant, bounce_irradiance);
                }
                catch (const std::exception& e)
                {
                    // A checkpoint is insurance, not the result: the bake goes on without further ones.
                    out.checkpoint_error = e.what();
                    checkpointing = false;
                }
                last_checkpoint = std::chrono::steady_clock::now();
            }
            if (progress)
                progress({pass, passes, first, n});
        }
    }
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

uint64_t trace_bake_rays(const io::Mesh& mesh, const PrtBakeOptions& o, double& seconds)
{
    check(mesh, o);
    EmbreeScene embree(mesh);
    const float offset = ray_offset_distance(mesh, o);
    const uint32_t n = uint32_t(mesh.vertex_count());
    std::atomic<uint64_t> hits{0};
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n, 256), [&](const tbb::blocked_range<uint32_t>& range) {
        uint64_t local = 0;
        for (uint32_t v = range.begin(); v != range.end(); ++v)
        {
            const glm::vec3 origin = mesh.positions[v] + offset * glm::normalize(mesh.normals[v]);
            for (int r = 0; r < o.rays; ++r)
            {
                uint32_t prim;
                float bu, bv;
                local += embree.intersect(origin, ray_direction(o.seed, v, r, o.rays), prim, bu, bv);
            }
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

std::vector<float> fold_technique(const PrtTransfer& transfer, const io::Mesh& mesh, std::string_view technique)
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
    tbb::parallel_for(uint32_t(0), n, [&](uint32_t v) {
        // Rotate M's rows (SH9 of incident radiance) from object space into the tangent frame.
        // A file's tangent need not be exactly perpendicular to its normal: Gram-Schmidt, so that the frame
        // is a rotation.
        const glm::vec3 nrm = glm::normalize(mesh.normals[v]);
        glm::vec3 tan = glm::vec3(mesh.tangents[v]) - glm::dot(glm::vec3(mesh.tangents[v]), nrm) * nrm;
        if (glm::dot(tan, tan) < 1e-12f)
            tan = std::abs(nrm.x) < 0.9f ? glm::cross(nrm, glm::vec3(1, 0, 0)) : glm::cross(nrm, glm::vec3(0, 1, 0));
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
                throw std::invalid_argument("hemi: technique '" + options.techniques[i] + "' requested twice");
    }
    if ((options.cpca_clusters == 0) != (options.cpca_vectors == 0))
        throw std::invalid_argument("hemi: CPCA needs both a cluster and a vector count");
    if (options.cpca_vectors > HEMI_CPCA_MAX_VECTORS)
        throw std::invalid_argument("hemi: CPCA with " + std::to_string(options.cpca_vectors) +
                                    " vectors per cluster; the runtime pass supports up to " +
                                    std::to_string(HEMI_CPCA_MAX_VECTORS));
    if (mesh.tangents.size() != mesh.vertex_count() || mesh.uvs.size() != mesh.vertex_count())
        throw std::invalid_argument("hemi: the PRT bake needs a tangent and UV per vertex");

    const PrtTransfer transfer = bake_prt_transfer(mesh, options.bake, progress);
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
    summary.materials = 1;
    summary.primitives = 1;
    summary.vertices = uint32_t(mesh.vertex_count());
    summary.triangles = uint32_t(mesh.indices.size() / 3);
    summary.rays = transfer.rays_traced;
    summary.trace_seconds = transfer.seconds;
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
            t.cpca = compress_cpca(t.matrices, n, t.k * L, std::min(options.cpca_clusters, n), options.cpca_vectors);
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
    const io::GltfScene scene = io::read_gltf(scene_path);
    PrtBakeSummary summary;
    PrtAssetOptions o = options;
    if (o.bake.checkpoint.empty())
        o.bake.checkpoint = asset_path.string() + ".partial";
    io::PrtAsset asset = make_prt_asset(scene.mesh, o, summary, progress); // scene.mesh: uvs1 included
    summary.tangents_generated = scene.tangents_generated;
    asset.materials = scene.materials;
    asset.images = scene.images;
    asset.primitives = scene.primitives;
    summary.materials = asset.materials.size();
    summary.primitives = asset.primitives.size();
    summary.images = asset.images.size();
    summary.warnings = scene.warnings;
    io::write_prt_asset(asset_path, asset);
    std::error_code ignored;
    std::filesystem::remove(o.bake.checkpoint, ignored); // the finished work is in the asset now
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
    io::write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream f(tmp);
        f << j.dump(2) << "\n";
        f.close();
        if (f.fail())
            throw io::FormatError(path.string() + ": cannot write the JSON report");
    });
}

} // namespace hemi::bake
