// hemi-bench: performance of hemi's kernels, reported as ratios measured in the same run.
//
//   stream/triad                      a[i] = b[i] + s*c[i] over 3 x 256 MiB, all cores (TBB): the memory
//                                     bandwidth every other ratio is measured against (STREAM counts 3
//                                     arrays).
//   transfer/{gpu,cpu}/N:n/K:k/L:l    the PRT transfer multiply. Counters:
//                                       GBps     = matrix bytes (N*K*L*4) / time
//                                       bw_ratio = time / (matrix bytes / triad bandwidth); 1.0 is the limit.
//                                     gpu: the reported time is the GPU timestamp difference around the
//                                     dispatches (UseManualTime); the counter wall_ms is submit + wait on the
//                                     host. cpu: wall clock of transfer_multiply_host.
//   sh/rotate/order:6/rgb             building an order-6 SH rotation and applying it to RGB lighting.
//   table1/MODEL/TECH[/cpu]           Sloan 2006 Table 1, re-measured: one frame of a baked PRT asset
//                                     (render::PrtView) at 640 x 480 for MODEL = simple (703 vertices),
//                                     complex (29,197) and 1M (1,000,688), TECH = gs, sep4, sal4, hl2, h4,
//                                     h6, gs+cpca, sep4+cpca (1 cluster x 24 vectors). Time = GPU timestamps
//                                     of the whole frame; counters fps, transfer_ms (coefficient pass),
//                                     raster_ms, wall_ms. /cpu: the paper's non-GPU path, the multiply on the
//                                     host (transfer_multiply_host / cpca_multiply_host) then the upload of
//                                     the coefficients, then the same raster pass; counters cpu_ms,
//                                     upload_ms, raster_ms. Frame cost does not depend on the matrices'
//                                     values, so the assets hold unshadowed transfer (the 1M model's CPCA
//                                     data are random, with the real shapes: CPCA of 1M x 225 values is a
//                                     bake-time job).
//   material/overhead/complex/...     the PRT material (each Table 1 technique) against the fair baseline
//                                     (Technique::Lambert: the same textures, one light), same mesh, frames
//                                     interleaved: medians of each pass and of their ratio, with the ratio's
//                                     10th and 90th percentiles.
//   bake/complex                      the PRT bake's first (visibility) pass on the complex model, 64 rays
//                                     per vertex: rays_per_s over the passes' time (not the BVH build), and
//                                     embree_ratio = Embree's own rays/s tracing the same rays in the same
//                                     packets with nothing else (bake::trace_bake_rays) / the bake's.
//   ssbump/...                        the SSBump bake (1024^2, 300 rays) and its tracer against Embree.
//   lightmap/material/level/WxH/TECH  the lightmap material against the fair baseline on the sample's level
//                                     (the same interleaved medians),
//                                     baked and read back as hemi-bake lightmap and hemi-render do.
//   lightmap/bake/level/...           the lightmap bake of the sample's level (1280^2, 2 bounces): time,
//                                     rays/s, peak memory, and embree_ratio = the bake's time over the time
//                                     Embree takes for the same rays with the same queries.
//   lightmap/bake/large/...           the same for a level of 8 x 5 rooms and corridors (4096^2, 11.9 M
//                                     covered texels; samples::make_large_level). --write-large-level=FILE
//                                     writes that level as a .glb and exits (for bench/level_scaling.sh).
//   lightmap/bake/dense/...           the many-room level at 2048^2 with each triangle cut into 16 x 16: a
//                                     generated level of a million triangles (990,208).
//   lightmap/bake/q3/...              a real one: OpenArena's oa_dm3, its patches tessellated to 969,708
//                                     triangles, its own 512^2 lightmap UVs. Every bake benchmark reports
//                                     triangles, covered_texels, rays_per_s and its own peak_rss_MiB.
//   lightmap/denoise/large/...        hemi-bake lightmap --denoise's filter on that level at 1024^2 (760,546
//                                     covered texels), baked with 32 rays, a sun and a bounce: time, and
//                                     filter_over_bake = the filter's time over that bake's (both wall
//                                     clock, all cores).
//
// Run with --benchmark_filter=... to pick; HEMI_DEVICE chooses the Vulkan device. A benchmark that throws is
// reported as an error (the others still run) and makes the exit status 1.
//
// --smoke (or HEMI_BENCH_SMOKE=1): every benchmark once (one iteration) at its smallest size, on a device
// with the Khronos validation layer on; any exception or validation message makes the exit status 1. CI
// runs it so that a benchmark that no longer runs fails; its times mean nothing.

#include "factored_scene.h"
#include "level.h"
#include "models.h"
#include "relief.h"
#include "tools/q3_level.h"
#include "vulkan_calls.h"

#include <hemi/bake/cpca.h>
#include <hemi/bake/embree_scene.h>
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/lightmap_denoise.h>
#include <hemi/bake/lightmap_unwrap.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/bake/ssbump.h>
#include <hemi/gpu/commands.h>
#include <hemi/gpu/device.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/gltf.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/mesh.h>
#include <hemi/math/paraboloid.h>
#include <hemi/math/sh.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/draw_queue.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/probe_object.h>
#include <hemi/render/transfer.h>
#include <hemi/render/view/prt_view.h>

#include <glm/gtc/matrix_transform.hpp>

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace
{

double g_triad_gbps = 0.0; // measured by stream/triad, which runs first

struct TransferCase
{
    uint32_t n, k, l;
};

// A row of Table 1: the model, its tessellation and whether its CPCA data are random (with the real shapes:
// CPCA of 1M x 225 values is a bake-time job).
struct Table1Row
{
    std::string label;
    hemi::samples::PrtModel model = hemi::samples::PrtModel::Simple;
    float detail = 1.0f;
    bool random_cpca = false;
};

// What a run measures: the full sizes, or with --smoke the smallest of every benchmark.
struct Sizes
{
    bool smoke = false;
    size_t triad_floats = size_t(64) << 20; // 64 Mi floats = 256 MiB per array
    std::vector<TransferCase> transfer = {{31726, 9, 25}, {1000000, 9, 25}};
    std::vector<Table1Row> table1 = {{"simple", hemi::samples::PrtModel::Simple, 1.0f, false},
                                     {"complex", hemi::samples::PrtModel::Complex, 1.0f, false},
                                     {"1M", hemi::samples::PrtModel::Complex, 5.89f, true}};
    // The model of material/overhead and of the PRT bake.
    Table1Row overhead = {"complex", hemi::samples::PrtModel::Complex, 1.0f, false};
    uint32_t relief = 1024;        // the SSBump benchmarks' height field, relief x relief
    uint32_t lightmap_atlas = 512; // the level that lightmap/material draws
    uint32_t bake_atlas = 1280;    // the level that lightmap/bake/level bakes
    // The many-room level that lightmap/bake/large bakes (samples::make_large_level): rooms along x and z,
    // atlas side. 8 x 5 rooms at 4096^2: 11.9 M covered texels, 3,682 triangles.
    uint32_t large_rooms_x = 8, large_rooms_z = 5, large_atlas = 4096;
    // lightmap/bake/dense: that level at dense_atlas^2, each triangle cut into dense_split^2.
    uint32_t dense_atlas = 2048, dense_split = 16;
    int q3_patch_level = 32;  // lightmap/bake/q3: oa_dm3's patches as 32 x 32 quads each (969,708 triangles)
    uint32_t prefilter = 512; // the parabolic maps' level 0 that prefilter/ filters (hemi-bake envmap's)
    float unwrap_detail = 4.18f; // the knot that lightmap/unwrap unwraps: about a million triangles
};

Sizes smoke_sizes()
{
    Sizes s;
    s.smoke = true;
    s.triad_floats = size_t(1) << 20;
    s.transfer = {{1024, 9, 25}};
    // The 1M row's own path (random CPCA data) on the simple model: "simple:random".
    s.table1 = {{"simple", hemi::samples::PrtModel::Simple, 1.0f, false},
                {"simple:random", hemi::samples::PrtModel::Simple, 1.0f, true}};
    s.overhead = s.table1[0];
    s.relief = 64;
    s.lightmap_atlas = 64; // make_level's smallest
    s.bake_atlas = 64;
    s.large_rooms_x = s.large_rooms_z = 2;
    s.large_atlas = 256;
    s.dense_atlas = 256;
    s.dense_split = 2;
    s.q3_patch_level = 1;
    s.prefilter = 64;
    s.unwrap_detail = 0.3f;
    return s;
}

Sizes g_sizes;

// The lightmap outputs that lightmap/material draws (and its asset holds).
const char* const kLightmapTechniques[] = {"sh9", "h6", "h4", "hl2", "plain", "rnm"};

std::atomic<int> g_failures{0};
std::atomic<uint64_t> g_validation_messages{0};

// Registers fn(state, args...) as `name`. An exception ends that benchmark with an error (the others still
// run) and makes the exit status 1. In a smoke run every benchmark runs one iteration; a full run's own
// MinTime and Iterations are set with full_min_time and full_iterations.
template <class F, class... Args>
benchmark::internal::Benchmark* add(const std::string& name, F fn, Args... args)
{
    benchmark::internal::Benchmark* b = benchmark::RegisterBenchmark(
        name.c_str(),
        [=](benchmark::State& state)
        {
            std::string error;
            try
            {
                fn(state, args...);
            }
            catch (const std::exception& e)
            {
                error = e.what();
            }
            catch (...)
            {
                error = "an exception that is not a std::exception";
            }
            if (!error.empty())
            {
                ++g_failures;
                std::fprintf(stderr, "%s threw: %s\n", name.c_str(), error.c_str());
                state.SkipWithError(error.c_str());
            }
        });
    if (g_sizes.smoke)
        b->Iterations(1);
    return b;
}

void full_min_time(benchmark::internal::Benchmark* b, double seconds)
{
    if (!g_sizes.smoke)
        b->MinTime(seconds);
}

void full_iterations(benchmark::internal::Benchmark* b, int64_t n)
{
    if (!g_sizes.smoke)
        b->Iterations(n);
}

struct Rng
{
    uint64_t s;
    float next()
    {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return float((s >> 40) & 0xffffff) / float(0x1000000) * 2.0f - 1.0f;
    }
};

std::vector<float> random_floats(size_t n, uint64_t seed)
{
    std::vector<float> v(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 20),
                      [&](const tbb::blocked_range<size_t>& r)
                      {
                          Rng rng{seed ^ (r.begin() * 0x9E3779B97F4A7C15ull)};
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              v[i] = rng.next();
                      });
    return v;
}

void stream_triad(benchmark::State& state)
{
    const size_t n = g_sizes.triad_floats;
    std::vector<float> a(n), b(n, 1.0f), c(n, 2.0f);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n),
                      [&](const tbb::blocked_range<size_t>& r)
                      {
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              a[i] = 0.0f; // first touch in parallel
                      });
    const float s = 3.0f;
    for (auto _ : state)
    {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16),
                          [&](const tbb::blocked_range<size_t>& r)
                          {
                              float* __restrict pa = a.data();
                              const float* __restrict pb = b.data();
                              const float* __restrict pc = c.data();
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  pa[i] = pb[i] + s * pc[i];
                          });
        benchmark::DoNotOptimize(a.data());
        benchmark::ClobberMemory();
    }
    double bytes = 3.0 * double(n) * sizeof(float);
    state.SetBytesProcessed(int64_t(bytes) * state.iterations());
    state.counters["GBps"] =
        benchmark::Counter(bytes * 1e-9 * double(state.iterations()), benchmark::Counter::kIsRate);
}

// Derived after the run (the rate counter needs the loop's time): we time the triad once more here.
double measure_triad_gbps()
{
    const size_t n = g_sizes.triad_floats;
    std::vector<float> a(n, 0.0f), b(n, 1.0f), c(n, 2.0f);
    double best = 1e30;
    for (int rep = 0; rep < 5; ++rep)
    {
        auto t0 = std::chrono::steady_clock::now();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16),
                          [&](const tbb::blocked_range<size_t>& r)
                          {
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  a[i] = b[i] + 3.0f * c[i];
                          });
        benchmark::DoNotOptimize(a.data());
        best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return 3.0 * double(n) * sizeof(float) / best * 1e-9;
}

void set_bandwidth_counters(benchmark::State& state, size_t bytes, double seconds_per_iteration)
{
    double gbps = double(bytes) / seconds_per_iteration * 1e-9;
    state.counters["GBps"] = gbps;
    state.counters["bw_ratio"] = g_triad_gbps > 0 ? g_triad_gbps / gbps : 0.0;
    state.counters["triad_GBps"] = g_triad_gbps;
}

std::unique_ptr<hemi::gpu::Device> g_device; // destroyed before main returns, so that its leaks count

// The Vulkan device, made at first use; with the validation layer in a smoke run (HEMI_VALIDATION overrides
// that). Validation warnings and errors are printed and counted.
hemi::gpu::Device& bench_device()
{
    if (!g_device)
    {
        hemi::gpu::DeviceDesc desc;
        desc.validation = g_sizes.smoke;
        desc.log = [](hemi::gpu::LogLevel level, bool validation, std::string_view message)
        {
            if (level < hemi::gpu::LogLevel::Warning)
                return;
            if (validation)
                ++g_validation_messages;
            std::fprintf(stderr, "%s%.*s\n", validation ? "validation: " : "", int(message.size()),
                         message.data());
        };
        g_device = std::make_unique<hemi::gpu::Device>(desc);
    }
    return *g_device;
}

void transfer_cpu(benchmark::State& state, TransferCase c)
{
    std::vector<float> raw = random_floats(size_t(c.n) * c.k * c.l, 1);
    hemi::render::TransferMatrices m(c.n, c.k, c.l, raw);
    raw = {};
    std::vector<glm::vec3> light(c.l, glm::vec3(0.5f, 0.25f, 0.125f));
    std::vector<float> out(size_t(c.n) * c.k * 4);
    hemi::render::transfer_multiply_host(m, light, out); // warm-up: first touch of the output
    double total = 0.0;
    for (auto _ : state)
    {
        auto t0 = std::chrono::steady_clock::now();
        hemi::render::transfer_multiply_host(m, light, out);
        total += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        benchmark::DoNotOptimize(out.data());
    }
    set_bandwidth_counters(state, m.matrix_bytes(), total / double(state.iterations()));
}

void transfer_gpu(benchmark::State& state, TransferCase c)
{
    hemi::gpu::Device& device = bench_device();
    std::vector<float> raw = random_floats(size_t(c.n) * c.k * c.l, 1);
    auto m = std::make_unique<hemi::render::TransferMatrices>(c.n, c.k, c.l, raw);
    raw = {};
    hemi::render::TransferPass pass(device, *m);
    const size_t bytes = m->matrix_bytes();
    m.reset();
    std::vector<glm::vec3> light(c.l, glm::vec3(0.5f, 0.25f, 0.125f));
    hemi::gpu::CommandContext ctx(device);
    hemi::gpu::TimestampQueries queries(device, 2);
    pass.run(light); // warm-up: lavapipe compiles the shader variant and faults in the output on first use
    double wall = 0.0, gpu = 0.0;
    for (auto _ : state)
    {
        VkCommandBuffer cmd = ctx.begin();
        queries.reset(cmd);
        queries.write(cmd, 0, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT);
        pass.record(cmd, light);
        queries.write(cmd, 1, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
        auto t0 = std::chrono::steady_clock::now();
        ctx.submit_and_wait();
        double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::vector<double> ns = queries.read_ns();
        double g = (ns[1] - ns[0]) * 1e-9;
        state.SetIterationTime(g);
        wall += w;
        gpu += g;
    }
    double iters = double(state.iterations());
    set_bandwidth_counters(state, bytes, gpu / iters);
    state.counters["wall_ms"] = wall / iters * 1e3;
    state.SetLabel(std::string(device.name()));
}

// Per-frame cost of rotating order-6 RGB lighting (36 coefficients): building the band matrices for a new
// rotation and applying them, as a renderer does once per object per frame.
void sh_rotate_order6_rgb(benchmark::State& state)
{
    std::vector<glm::vec3> in(36), out(36);
    for (int i = 0; i < 36; ++i)
        in[i] = glm::vec3(float(i), 0.5f * float(i), 1.0f);
    float angle = 0.0f;
    for (auto _ : state)
    {
        angle += 0.01f;
        glm::mat3 r(glm::rotate(glm::mat4(1.0f), angle, glm::normalize(glm::vec3(0.3f, 0.5f, 0.8f))));
        hemi::math::ShRotation rotation(6, r);
        rotation.apply(in, out);
        benchmark::DoNotOptimize(out.data());
    }
}

// ---- Table 1 ----------------------------------------------------------------------------------------

struct Table1Model
{
    hemi::io::Mesh mesh;
    hemi::bake::PrtTransfer transfer; // unshadowed, order 5
};

const Table1Model& table1_model(const Table1Row& row)
{
    static std::map<std::string, std::unique_ptr<Table1Model>> cache;
    auto& slot = cache[row.label];
    if (!slot)
    {
        cache.clear(); // one model in memory at a time (the 1M one is large)
        auto m = std::make_unique<Table1Model>();
        m->mesh = hemi::samples::make_prt_model(row.model, row.detail);
        hemi::bake::PrtBakeOptions o;
        o.kind = hemi::bake::TransferKind::Unshadowed;
        m->transfer = hemi::bake::bake_prt_transfer(m->mesh, o);
        cache[row.label] = std::move(m);
        return *cache[row.label];
    }
    return *slot;
}

hemi::io::PrtAsset table1_asset(const Table1Model& model, const std::string& technique, bool cpca,
                                bool random_cpca)
{
    hemi::io::PrtAsset a;
    a.mesh = model.mesh;
    a.order = uint32_t(model.transfer.order);
    // The sample's surface: a brick normal map and base colour (what hemi-bake writes into the asset).
    static const std::vector<uint8_t> normal_png =
        hemi::io::encode_png(hemi::samples::brick_normal_map(512, 256));
    static const std::vector<uint8_t> base_png =
        hemi::io::encode_png(hemi::samples::brick_base_color(512, 256));
    a.images = {{"brick_normal.png", "image/png", normal_png},
                {"brick_base_color.png", "image/png", base_png}};
    hemi::io::Material brick;
    brick.name = "brick";
    brick.normal.image = 0;
    brick.base_color.image = 1;
    a.materials = {brick};
    a.primitives = {{0, uint32_t(a.mesh.indices.size()), 0}};
    hemi::io::PrtTechnique t;
    t.name = technique;
    t.k = uint32_t(hemi::bake::technique_size(technique));
    const uint32_t n = uint32_t(model.mesh.vertex_count()), d = t.k * a.l();
    if (!cpca)
        t.matrices = hemi::bake::fold_technique(model.transfer, model.mesh, technique);
    else if (!random_cpca)
        t.cpca = hemi::bake::compress_cpca(hemi::bake::fold_technique(model.transfer, model.mesh, technique),
                                           n, d, 1, 24);
    else
    {
        hemi::io::PrtCpca c;
        c.clusters = 1;
        c.vectors = 24;
        c.means = random_floats(d, 2);
        c.basis = random_floats(size_t(24) * d, 3);
        c.cluster.assign(n, 0);
        c.weights = random_floats(size_t(n) * 24, 4);
        t.cpca = std::move(c);
    }
    a.techniques.push_back(std::move(t));
    return a;
}

void table1(benchmark::State& state, Table1Row row, std::string technique, bool cpca, bool cpu_path)
{
    hemi::gpu::Device& device = bench_device();
    const Table1Model& model = table1_model(row);
    const hemi::io::PrtAsset asset = table1_asset(model, technique, cpca, row.random_cpca);
    const uint32_t w = 640, h = 480;
    hemi::render::PrtView view(device, asset, technique, cpca, w, h);
    hemi::render::PrtFrame frame;
    frame.world_lighting = hemi::render::environment_lighting("sky", int(asset.order));
    frame.camera = hemi::render::auto_camera(asset.mesh, frame.model, float(w) / float(h));
    hemi::gpu::CommandContext ctx(device);
    hemi::gpu::TimestampQueries queries(device, 3);
    for (int i = 0; i < 3; ++i)
        view.render(frame); // warm-up: pipeline variants compiled, memory faulted in, caches settled

    const hemi::io::PrtTechnique& t = asset.techniques[0];
    const uint32_t n = uint32_t(asset.mesh.vertex_count());
    std::unique_ptr<hemi::render::TransferMatrices> host_matrices;
    hemi::render::CpcaMatrices host_cpca;
    if (cpu_path && !cpca)
        host_matrices = std::make_unique<hemi::render::TransferMatrices>(n, t.k, asset.l(), t.matrices);
    if (cpu_path && cpca)
        host_cpca = {
            n, t.k, asset.l(), 1, 24, t.cpca->means, t.cpca->basis, t.cpca->cluster, t.cpca->weights};
    std::vector<float> coefficients(size_t(n) * t.k * 4);
    const std::vector<glm::vec3> lighting = view.object_lighting(frame);

    double transfer = 0.0, raster = 0.0, wall = 0.0, cpu = 0.0, upload = 0.0;
    for (auto _ : state)
    {
        const auto t0 = std::chrono::steady_clock::now();
        if (cpu_path)
        {
            if (cpca)
                hemi::render::cpca_multiply_host(host_cpca, lighting, coefficients);
            else
                hemi::render::transfer_multiply_host(*host_matrices, lighting, coefficients);
            const auto t1 = std::chrono::steady_clock::now();
            view.coefficients().write_coefficients(coefficients);
            const auto t2 = std::chrono::steady_clock::now();
            cpu += std::chrono::duration<double>(t1 - t0).count();
            upload += std::chrono::duration<double>(t2 - t1).count();
        }
        VkCommandBuffer cmd = ctx.begin();
        queries.reset(cmd);
        queries.write(cmd, 0, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT);
        if (cpu_path)
        {
            // Only the material's uniforms: the coefficients were uploaded.
            hemi::render::PrtFrame f = frame;
            view.record_material(cmd, f);
        }
        else
            view.record_transfer(cmd, frame);
        queries.write(cmd, 1, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
        view.record_raster(cmd);
        queries.write(cmd, 2, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
        ctx.submit_and_wait();
        const auto t3 = std::chrono::steady_clock::now();
        const std::vector<double> ns = queries.read_ns();
        const double gpu_frame = (ns[2] - ns[0]) * 1e-9;
        transfer += (ns[1] - ns[0]) * 1e-9;
        raster += (ns[2] - ns[1]) * 1e-9;
        wall += std::chrono::duration<double>(t3 - t0).count();
        state.SetIterationTime(cpu_path ? std::chrono::duration<double>(t3 - t0).count() : gpu_frame);
    }
    const double iters = double(state.iterations());
    state.counters["vertices"] = n;
    state.counters["raster_ms"] = raster / iters * 1e3;
    state.counters["wall_ms"] = wall / iters * 1e3;
    if (cpu_path)
    {
        state.counters["cpu_ms"] = cpu / iters * 1e3;
        state.counters["upload_ms"] = upload / iters * 1e3;
        state.counters["fps"] = iters / wall;
    }
    else
    {
        state.counters["transfer_ms"] = transfer / iters * 1e3;
        state.counters["fps"] = iters / (transfer + raster);
    }
}

// The frame-time ratios' loop (the material system's cost): `record(cmd, timed, measured_first)` records one
// frame holding the measured material's pass and the baseline's (the same mesh drawn by the fair baseline,
// Technique::Lambert: the same textures, one dynamic light), writing GPU timestamps 0, 1 and 2 around the
// two passes when `timed`, the measured one first when `measured_first`. The order alternates every frame,
// so neither pass always runs after the other. After three warm-up frames each iteration is one timed frame.
// Reported as medians over the frames: each pass's time and the ratio of the two within a frame, with the
// ratio's 10th and 90th percentiles (its spread on a shared machine).
struct PassTimes
{
    double measured = 0.0, baseline = 0.0; // median seconds
    double ratio = 0.0, ratio_p10 = 0.0, ratio_p90 = 0.0;
};

double quantile(std::vector<double> v, double q)
{
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    const double x = q * double(v.size() - 1);
    const size_t i = size_t(x);
    const double f = x - double(i);
    return i + 1 < v.size() ? v[i] * (1.0 - f) + v[i + 1] * f : v[i];
}

PassTimes time_against_baseline(benchmark::State& state, hemi::gpu::Device& device,
                                const std::function<void(VkCommandBuffer)>& prepare,
                                const std::function<void(VkCommandBuffer)>& measured,
                                const std::function<void(VkCommandBuffer)>& baseline)
{
    hemi::gpu::TimestampQueries queries(device, 3);
    hemi::gpu::CommandContext ctx(device);
    auto frame = [&](VkCommandBuffer cmd, bool timed, bool measured_first)
    {
        prepare(cmd);
        if (timed)
            queries.write(cmd, 0, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
        (measured_first ? measured : baseline)(cmd);
        if (timed)
            queries.write(cmd, 1, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
        (measured_first ? baseline : measured)(cmd);
        if (timed)
            queries.write(cmd, 2, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
    };
    for (int i = 0; i < 3; ++i) // warm-up
        ctx.run([&](VkCommandBuffer cmd) { frame(cmd, false, i % 2 == 0); });
    std::vector<double> measured_s, baseline_s, ratio;
    bool measured_first = true;
    for (auto _ : state)
    {
        VkCommandBuffer cmd = ctx.begin();
        queries.reset(cmd);
        frame(cmd, true, measured_first);
        ctx.submit_and_wait();
        const std::vector<double> ns = queries.read_ns();
        const double first = (ns[1] - ns[0]) * 1e-9, second = (ns[2] - ns[1]) * 1e-9;
        measured_s.push_back(measured_first ? first : second);
        baseline_s.push_back(measured_first ? second : first);
        ratio.push_back(measured_s.back() / baseline_s.back());
        state.SetIterationTime(first + second);
        measured_first = !measured_first;
    }
    PassTimes t;
    t.measured = quantile(measured_s, 0.5);
    t.baseline = quantile(baseline_s, 0.5);
    t.ratio = quantile(ratio, 0.5);
    t.ratio_p10 = quantile(ratio, 0.1);
    t.ratio_p90 = quantile(ratio, 0.9);
    return t;
}

void set_ratio_counters(benchmark::State& state, const std::string& name, const PassTimes& t)
{
    state.counters[name + "_ms"] = t.measured * 1e3;
    state.counters["lambert_ms"] = t.baseline * 1e3;
    state.counters["overhead_ratio"] = t.ratio;
    state.counters["ratio_p10"] = t.ratio_p10;
    state.counters["ratio_p90"] = t.ratio_p90;
}

// The fair baseline's one light: a directional light from above and to the side, white.
hemi::render::DynamicLight baseline_light()
{
    hemi::render::DynamicLight l;
    l.position = glm::normalize(glm::vec3(0.3f, -0.4f, 1.0f));
    l.irradiance = glm::vec3(2.0f);
    return l;
}

void material_overhead(benchmark::State& state, std::string technique)
{
    hemi::gpu::Device& device = bench_device();
    const Table1Model& model = table1_model(g_sizes.overhead);
    const hemi::io::PrtAsset asset = table1_asset(model, technique, false, false);
    const uint32_t w = 640, h = 480;
    hemi::render::PrtView view(device, asset, technique, false, w, h);
    hemi::render::PrtFrame frame;
    frame.world_lighting = hemi::render::environment_lighting("sky", int(asset.order));
    frame.camera = hemi::render::auto_camera(asset.mesh, frame.model, float(w) / float(h));

    // The fair baseline (Technique::Lambert: the same base colour and normal maps through the same material,
    // one dynamic light), drawn with the view's own material system, mesh and material instance.
    hemi::render::MaterialSystem& system = view.materials();
    hemi::gpu::UploadBatch upload(device);
    hemi::render::ProbeBuffer probe(system, 1);
    hemi::render::FrameSet baseline_frame(system);
    upload.submit_and_wait();
    hemi::render::MaterialKey key = view.model().surfaces().type(0, 0, 0).key;
    key.technique = hemi::render::Technique::Lambert;
    key.source = hemi::render::CoefficientSourceKind::Uniform;
    hemi::render::DrawBindings baseline;
    baseline.type = &system.type(key);
    baseline.frame = baseline_frame.set();
    baseline.material = view.model().surfaces().material_set(0);
    baseline.source = probe.set();
    baseline.push.model = frame.model;
    hemi::render::FrameData f;
    f.view_projection =
        hemi::render::camera_matrix(frame.camera, asset.mesh, frame.model, float(w) / float(h));
    f.lights = {baseline_light()};

    const PassTimes t = time_against_baseline(
        state, device,
        [&](VkCommandBuffer cmd)
        {
            view.record_transfer(cmd, frame);
            baseline_frame.record_update(cmd, f);
        },
        [&](VkCommandBuffer cmd) { view.record_raster(cmd); },
        [&](VkCommandBuffer cmd)
        {
            view.target().begin(cmd);
            hemi::render::bind_material(cmd, baseline);
            view.model().mesh().bind(cmd);
            view.model().mesh().draw(cmd, 0, view.model().mesh().index_count());
            view.target().end(cmd);
        });
    state.counters["vertices"] = double(asset.mesh.vertex_count());
    set_ratio_counters(state, "prt", t);
}

void prt_bake(benchmark::State& state)
{
    const hemi::io::Mesh mesh =
        hemi::samples::make_prt_model(g_sizes.overhead.model, g_sizes.overhead.detail);
    hemi::bake::PrtBakeOptions o;
    o.kind = hemi::bake::TransferKind::Shadowed;
    o.rays = 64;
    double bake_rays_per_s = 0.0, embree_rays_per_s = 0.0;
    for (auto _ : state)
    {
        const hemi::bake::PrtTransfer t = hemi::bake::bake_prt_transfer(mesh, o);
        double seconds = 0.0;
        hemi::bake::trace_bake_rays(mesh, o, seconds);
        bake_rays_per_s = double(t.rays_traced) / t.trace_seconds;
        embree_rays_per_s = double(t.rays_traced) / seconds;
        state.SetIterationTime(t.trace_seconds);
    }
    state.counters["rays_per_s"] = bake_rays_per_s;
    state.counters["embree_rays_per_s"] = embree_rays_per_s;
    state.counters["embree_ratio"] = embree_rays_per_s / bake_rays_per_s;
}

// Issue 11's speed goal: the 1024 x 1024 SSBump bake at 300 rays per texel (the paper's number), on the
// sample's deep relief (bricks, rivets, craters; scale 24 texels), tiling.
void ssbump_bake(benchmark::State& state, bool wrap)
{
    const hemi::bake::HeightField field = hemi::samples::make_relief(g_sizes.relief);
    hemi::bake::SsbumpOptions o;
    o.scale = 24.0f;
    o.rays = 300;
    o.wrap = wrap;
    hemi::bake::SsbumpMap m;
    for (auto _ : state)
    {
        m = hemi::bake::bake_ssbump(field, o);
        state.SetIterationTime(m.trace_seconds);
    }
    state.counters["seconds"] = m.trace_seconds;
    state.counters["rays_per_s"] = double(m.rays) / m.trace_seconds;
}

// The tracer choice: the same height-field rays (the bake's own, from every 8th texel of every 8th row of
// the 1024^2 relief, without wrapping, as Embree sees the relief) cast one by one by Embree (rtcOccluded1 on
// the relief's 2M triangles, on the same TBB threads) against the bake's horizon tracer, which answers the
// rays of an azimuth with one search. Also counts how often the two disagree (grazing ties only).
void ssbump_tracers(benchmark::State& state)
{
    const hemi::bake::HeightField field = hemi::samples::make_relief(g_sizes.relief);
    const float scale = 24.0f, epsilon = 1e-3f, distance = float(g_sizes.relief);
    const int rays = 300;
    const hemi::bake::HeightFieldTracer tracer(field, scale, false, epsilon, distance);
    const hemi::bake::EmbreeScene embree(hemi::bake::height_field_mesh(field, scale));
    std::vector<uint32_t> texels;
    for (uint32_t y = 4; y < field.height; y += 8)
        for (uint32_t x = 4; x < field.width; x += 8)
            texels.push_back(y * field.width + x);
    const uint64_t total = uint64_t(texels.size()) * rays;
    std::vector<uint8_t> by_embree(total), by_horizon(total);
    double embree_s = 0.0, horizon_s = 0.0;
    for (auto _ : state)
    {
        auto t0 = std::chrono::steady_clock::now();
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, texels.size(), 16),
            [&](const tbb::blocked_range<size_t>& r)
            {
                for (size_t i = r.begin(); i != r.end(); ++i)
                {
                    const uint32_t x = texels[i] % field.width, y = texels[i] / field.width;
                    const glm::vec3 origin(float(x), -float(y), tracer.height_at(x, y) + epsilon);
                    for (int k = 0; k < rays; ++k)
                    {
                        const glm::vec3 d = hemi::bake::ssbump_ray(1, texels[i], k, rays).direction;
                        const float rho = std::sqrt(d.x * d.x + d.y * d.y);
                        by_embree[i * rays + size_t(k)] = embree.occluded(origin, d, 0.0f, distance / rho);
                    }
                }
            });
        auto t1 = std::chrono::steady_clock::now();
        const int azimuths = hemi::bake::ssbump_azimuths(rays);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, texels.size(), 16),
                          [&](const tbb::blocked_range<size_t>& r)
                          {
                              for (size_t i = r.begin(); i != r.end(); ++i)
                              {
                                  const uint32_t x = texels[i] % field.width, y = texels[i] / field.width;
                                  for (int a = 0; a < azimuths; ++a)
                                  {
                                      // As the bake does: one search per azimuth from its lowest ray's slope.
                                      double k_min = 1e300, dx = 0.0, dy = 0.0;
                                      for (int k = a; k < rays; k += azimuths)
                                      {
                                          const glm::vec3 d =
                                              hemi::bake::ssbump_ray(1, texels[i], k, rays).direction;
                                          const double rho = std::sqrt(double(d.x) * d.x + double(d.y) * d.y);
                                          k_min = std::min(k_min, double(d.z) / rho);
                                          dx = d.x / rho;
                                          dy = d.y / rho;
                                      }
                                      const double h = tracer.horizon(x, y, dx, dy, k_min);
                                      for (int k = a; k < rays; k += azimuths)
                                      {
                                          const glm::vec3 d =
                                              hemi::bake::ssbump_ray(1, texels[i], k, rays).direction;
                                          const double rho = std::sqrt(double(d.x) * d.x + double(d.y) * d.y);
                                          by_horizon[i * rays + size_t(k)] = double(d.z) / rho < h;
                                      }
                                  }
                              }
                          });
        auto t2 = std::chrono::steady_clock::now();
        embree_s = std::chrono::duration<double>(t1 - t0).count();
        horizon_s = std::chrono::duration<double>(t2 - t1).count();
        state.SetIterationTime(horizon_s);
    }
    uint64_t disagree = 0, blocked = 0;
    for (uint64_t i = 0; i < total; ++i)
    {
        disagree += by_embree[i] != by_horizon[i];
        blocked += by_embree[i];
    }
    state.counters["rays"] = double(total);
    state.counters["blocked_fraction"] = double(blocked) / double(total);
    state.counters["disagreements"] = double(disagree);
    state.counters["embree_rays_per_s"] = double(total) / embree_s;
    state.counters["horizon_rays_per_s"] = double(total) / horizon_s;
    state.counters["horizon_vs_embree"] = embree_s / horizon_s;
}

// The peak resident memory of this process so far (VmHWM), in MiB; 0 where /proc is not there.
double peak_rss_mib()
{
    std::FILE* f = std::fopen("/proc/self/status", "r");
    if (!f)
        return 0.0;
    char line[256];
    double kib = 0.0;
    while (std::fgets(line, sizeof line, f))
        if (std::sscanf(line, "VmHWM: %lf kB", &kib) == 1)
            break;
    std::fclose(f);
    return kib / 1024.0;
}

// Forgets the peak resident memory so far (VmHWM), so that a benchmark's peak is its own: Linux resets it
// when "5" is written to /proc/self/clear_refs. False where that is not there.
bool reset_peak_rss()
{
    std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
    if (!f)
        return false;
    const bool ok = std::fputs("5", f) >= 0;
    return std::fclose(f) == 0 && ok;
}

// `mesh` with each triangle cut into k x k triangles (the points i/k, j/k of its barycentric grid), every
// attribute interpolated linearly, so that its surfaces, normals and lightmap UVs are the same and only the
// triangles are more: the same bake over k^2 times as many triangles. A point on an edge is the same float
// from both of its triangles (its weights are the edge's two ends; the third adds an exact 0).
hemi::io::GltfScene subdivided(const hemi::io::GltfScene& scene, uint32_t k)
{
    hemi::io::GltfScene out = scene;
    const hemi::io::Mesh& m = scene.mesh;
    hemi::io::Mesh& d = out.mesh;
    d.positions.clear();
    d.normals.clear();
    d.tangents.clear();
    d.uvs.clear();
    d.uvs1.clear();
    d.indices.clear();
    auto mix = [&](const auto& a, const auto& b, const auto& c, uint32_t i, uint32_t j)
    { return (a * float(i) + b * float(j) + c * float(k - i - j)) / float(k); };
    for (size_t t = 0; t < m.indices.size(); t += 3)
    {
        const uint32_t v0 = m.indices[t], v1 = m.indices[t + 1], v2 = m.indices[t + 2];
        const uint32_t base = uint32_t(d.positions.size());
        auto at = [&](uint32_t i, uint32_t j) // grid point (i, j), i + j <= k, row i after row i - 1
        { return base + i * (k + 1) - i * (i - 1) / 2 + j; };
        for (uint32_t i = 0; i <= k; ++i)
            for (uint32_t j = 0; i + j <= k; ++j)
            {
                d.positions.push_back(mix(m.positions[v0], m.positions[v1], m.positions[v2], i, j));
                if (!m.normals.empty())
                    d.normals.push_back(
                        glm::normalize(mix(m.normals[v0], m.normals[v1], m.normals[v2], i, j)));
                if (!m.tangents.empty())
                    d.tangents.emplace_back(
                        glm::normalize(mix(glm::vec3(m.tangents[v0]), glm::vec3(m.tangents[v1]),
                                           glm::vec3(m.tangents[v2]), i, j)),
                        m.tangents[v0].w);
                if (!m.uvs.empty())
                    d.uvs.push_back(mix(m.uvs[v0], m.uvs[v1], m.uvs[v2], i, j));
                if (!m.uvs1.empty())
                    d.uvs1.push_back(mix(m.uvs1[v0], m.uvs1[v1], m.uvs1[v2], i, j));
            }
        // The same winding as the triangle: (i, j) towards v0, v1 as i, j grow.
        for (uint32_t i = 0; i < k; ++i)
            for (uint32_t j = 0; i + j < k; ++j)
            {
                d.indices.insert(d.indices.end(), {at(i, j), at(i + 1, j), at(i, j + 1)});
                if (i + j + 1 < k)
                    d.indices.insert(d.indices.end(), {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
            }
    }
    for (hemi::io::Primitive& p : out.primitives)
    {
        p.first_index *= k * k;
        p.index_count *= k * k;
    }
    return out;
}

// What the lightmap bake benchmarks bake: `scene`'s size x size atlas, its surfaces, and a uniform sky of 1
// with a sun of 6 from (0.4, 1, 0.35) in the mesh's y-up space. Not copyable (the surfaces point at the
// mesh).
struct LightmapBench
{
    hemi::bake::LightmapAtlas atlas;
    hemi::bake::LightmapSurfaces surfaces;
    hemi::bake::LightmapLights lights;
    LightmapBench(const hemi::io::GltfScene& scene, uint32_t size)
        : surfaces(scene.mesh, scene.materials, scene.images, scene.primitives)
    {
        hemi::bake::LightmapUvReport report;
        atlas = hemi::bake::rasterize_lightmap(scene.mesh, size, size, report);
        lights.sun = true;
        lights.sun_direction = glm::normalize(glm::vec3(0.4f, 1.0f, 0.35f));
        lights.sun_irradiance = glm::vec3(6.0f);
    }
    LightmapBench(const LightmapBench&) = delete;
    LightmapBench& operator=(const LightmapBench&) = delete;
};

// A lightmap bake benchmark (issue 12's, issue 23's): `scene` baked into a size x size atlas under a uniform
// sky and a sun, 2 bounces, 64 rays per texel and pass; its time, rays/s, texels/s and peak memory. Then
// Embree's own throughput on the same rays with the same queries (below), and the ratio.
void lightmap_bake(benchmark::State& state, const hemi::io::GltfScene& scene, uint32_t size)
{
    const LightmapBench bench(scene, size);
    const hemi::bake::LightmapAtlas& atlas = bench.atlas;
    const hemi::bake::LightmapSurfaces& surfaces = bench.surfaces;
    const hemi::bake::LightmapLights& lights = bench.lights;
    hemi::bake::LightmapBakeOptions o;
    o.rays = 64;
    o.bounces = 2;
    hemi::bake::LightmapSh sh;
    reset_peak_rss(); // the level's own peak: the scene, its atlas, its ray tracer and the bake
    for (auto _ : state)
    {
        sh = hemi::bake::bake_lightmap_sh(scene.mesh, atlas, lights, o, &surfaces);
        state.SetIterationTime(sh.trace_seconds);
    }
    const double peak = peak_rss_mib();
    // Embree alone on the same rays, with the same queries, over the first 2^16 texels: each texel's
    // hemisphere rays above its own plane (closest hits, in packets of 16, as every pass traces them) and its
    // shadow rays towards the sun (occlusion, in packets of 16); rtcIntersect1 on the same hemisphere rays
    // for comparison. Origins: the texel's sample point off its plane (the bake's own also leave triangle
    // borders and move out of walls: the same rays but for a few texels).
    const hemi::bake::EmbreeScene embree(scene.mesh);
    const float offset = embree.ray_offset(o.ray_offset);
    const uint32_t n = std::min<uint32_t>(uint32_t(atlas.texels.size()), 1u << 16);
    std::vector<hemi::bake::Ray> hemisphere, sun;
    std::vector<uint32_t> hemisphere_end(n), sun_end(n); // per texel, one past its last ray
    for (uint32_t i = 0; i < n; ++i)
    {
        const hemi::bake::LightmapTexel& t = atlas.texels[i];
        const glm::vec3 origin = hemi::bake::offset_ray_origin(t.position, t.geometric_normal, offset);
        std::vector<glm::vec3> h(size_t(o.rays));
        hemi::bake::hemisphere_directions(o.seed, uint64_t(t.y) * atlas.width + t.x, h);
        for (const glm::vec3& l : h)
        {
            const glm::vec3 d = glm::normalize(l.x * t.tangent + l.y * t.bitangent + l.z * t.normal);
            if (glm::dot(d, t.geometric_normal) > 0.0f)
                hemisphere.push_back({origin, 0.0f, d, INFINITY});
        }
        hemisphere_end[i] = uint32_t(hemisphere.size());
        if (glm::dot(lights.sun_direction, t.geometric_normal) > 0.0f)
            for (int k = 0; k < o.sun_rays; ++k)
                sun.push_back({origin, 0.0f, lights.sun_direction, INFINITY});
        sun_end[i] = uint32_t(sun.size());
    }
    std::atomic<uint64_t> blocked{0};
    auto per_texel = [&](auto&& trace)
    {
        const auto t0 = std::chrono::steady_clock::now();
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n, 64),
                          [&](const tbb::blocked_range<uint32_t>& r)
                          {
                              for (uint32_t i = r.begin(); i != r.end(); ++i)
                                  trace(i);
                          });
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    const double hemisphere_s = per_texel(
        [&](uint32_t i)
        {
            const uint32_t first = i ? hemisphere_end[i - 1] : 0;
            std::vector<std::optional<hemi::bake::RayHit>> hits(hemisphere_end[i] - first);
            embree.intersect(std::span(hemisphere).subspan(first, hits.size()), hits);
            uint64_t b = 0;
            for (const auto& hit : hits)
                b += hit.has_value();
            blocked += b;
        });
    const double single_s = per_texel(
        [&](uint32_t i)
        {
            for (uint32_t k = i ? hemisphere_end[i - 1] : 0; k < hemisphere_end[i]; ++k)
                benchmark::DoNotOptimize(embree.intersect(hemisphere[k].origin, hemisphere[k].direction));
        });
    const double sun_s = per_texel(
        [&](uint32_t i)
        {
            const uint32_t first = i ? sun_end[i - 1] : 0;
            std::vector<uint8_t> b(sun_end[i] - first);
            embree.occluded(std::span(sun).subspan(first, b.size()), b);
        });
    // The bake's rays at these rates: its hemisphere rays in every pass, its sun rays in the first.
    const double covered = double(atlas.texels.size()), sampled = double(n);
    const double embree_s = (1 + o.bounces) * covered / sampled * hemisphere_s + covered / sampled * sun_s;
    const double bake_rays =
        covered / sampled * ((1 + o.bounces) * double(hemisphere.size()) + double(sun.size()));
    state.counters["triangles"] = double(scene.mesh.indices.size() / 3);
    state.counters["covered_texels"] = covered;
    state.counters["seconds"] = sh.trace_seconds;
    state.counters["rays_per_s"] = bake_rays / sh.trace_seconds;
    state.counters["texels_per_s"] = covered * (1 + o.bounces) / sh.trace_seconds;
    state.counters["peak_rss_MiB"] = peak;
    state.counters["embree_rays_per_s"] = bake_rays / embree_s;
    state.counters["embree_single_rays_per_s"] = double(hemisphere.size()) / single_s;
    state.counters["embree_ratio"] = sh.trace_seconds / embree_s;
    state.counters["blocked_fraction"] = double(blocked) / double(hemisphere.size());
}

// The sample's level (a room with openings and pillars, 1280^2 atlas, over 1M covered texels).
void lightmap_level(benchmark::State& state)
{
    lightmap_bake(state, hemi::samples::make_level(g_sizes.bake_atlas), g_sizes.bake_atlas);
}

// Issue 23's level-sized bake: samples::make_large_level (8 x 5 rooms, corridors, doors, windows, pillars,
// normal-mapped) in a 4096^2 atlas, over 10 M covered texels.
void lightmap_large(benchmark::State& state)
{
    const hemi::io::GltfScene scene =
        hemi::samples::make_large_level(g_sizes.large_rooms_x, g_sizes.large_rooms_z, g_sizes.large_atlas);
    lightmap_bake(state, scene, g_sizes.large_atlas);
}

// Issue 45's generated level of a million triangles: the many-room level (8 x 5 rooms) at 2048^2 with each
// triangle cut into 16 x 16 (990,208 triangles), the same surfaces and lightmap: against
// lightmap/bake/large's own level at the same texel density it shows what the triangles cost.
void lightmap_dense(benchmark::State& state)
{
    const hemi::io::GltfScene scene = subdivided(
        hemi::samples::make_large_level(g_sizes.large_rooms_x, g_sizes.large_rooms_z, g_sizes.dense_atlas),
        g_sizes.dense_split);
    lightmap_bake(state, scene, g_sizes.dense_atlas);
}

// A real level at a million triangles: OpenArena's oa_dm3 (Debian's openarena-081-maps, converted as the
// tests convert it, tests/tools/q3_level.h) with its 470 Bezier patches tessellated into 32 x 32 quads each
// (969,708 triangles), its own lightmap UVs (14 pages of 128^2 in a 512^2 atlas); through a .glb and
// io::read_gltf as hemi-bake reads it (which makes its tangents). Its sky is an opening: 98% of its
// bounding box is open air, and most rays leave the level.
void lightmap_q3(benchmark::State& state)
{
    const std::filesystem::path glb =
        std::filesystem::temp_directory_path() / ("hemi_bench_q3_" + std::to_string(getpid()) + ".glb");
    hemi::io::write_gltf(
        glb, hemi::test::read_q3_level(hemi::test::kOpenArenaMaps, "maps/oa_dm3.bsp", g_sizes.q3_patch_level)
                 .scene);
    const hemi::io::GltfScene scene = hemi::io::read_gltf(glb);
    std::filesystem::remove(glb);
    lightmap_bake(state, scene, 512);
}

// The denoiser (bake::denoise_lightmap, what --denoise runs) on the many-room level at 1024^2 (at most the
// large level's atlas), baked once with what it needs (32 rays, the noise estimate, a sun, a bounce); each
// iteration filters a copy of that bake. The bake's own wall time is the ratio's denominator: the share of
// a 32-ray bake with --denoise that the filter adds.
void lightmap_denoise(benchmark::State& state)
{
    const uint32_t size = std::min<uint32_t>(g_sizes.large_atlas, 1024);
    const hemi::io::GltfScene scene =
        hemi::samples::make_large_level(g_sizes.large_rooms_x, g_sizes.large_rooms_z, size);
    const LightmapBench bench(scene, size);
    hemi::bake::LightmapBakeOptions o;
    o.rays = 32;
    o.bounces = 1;
    o.keep_noise = true;
    auto t0 = std::chrono::steady_clock::now();
    const hemi::bake::LightmapSh baked =
        hemi::bake::bake_lightmap_sh(scene.mesh, bench.atlas, bench.lights, o, &bench.surfaces);
    const double bake_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double filter_s = 0.0;
    int64_t runs = 0;
    for (auto _ : state)
    {
        hemi::bake::LightmapSh sh = baked;
        t0 = std::chrono::steady_clock::now();
        hemi::bake::denoise_lightmap(scene.mesh, bench.atlas, sh);
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        state.SetIterationTime(s);
        filter_s += s;
        ++runs;
    }
    state.counters["texels"] = double(bench.atlas.texels.size());
    state.counters["bake_s"] = bake_s;
    state.counters["filter_over_bake"] = filter_s / double(std::max<int64_t>(runs, 1)) / bake_s;
}

// hemi-bake lightmap --unwrap on a curved mesh of a million triangles (issue 25's goal: under 60 s on 2
// cores): the sample's knot at a finer tessellation, unwrapped into a 4096 x 4096 atlas at the largest texel
// size that fits. Counters: the triangles, the charts, and the packing efficiency, the charts' surface in
// texels over the atlas's texels (what the texel size and the padding leave of the atlas). One thread: the
// same atlas on any machine.
void lightmap_unwrap(benchmark::State& state)
{
    const hemi::io::Mesh knot =
        hemi::samples::make_prt_model(hemi::samples::PrtModel::Complex, g_sizes.unwrap_detail);
    hemi::bake::UnwrapOptions o;
    o.width = o.height = g_sizes.smoke ? 512 : 4096;
    hemi::bake::UnwrapResult r;
    hemi::io::Mesh mesh;
    for (auto _ : state)
    {
        mesh = knot;
        const auto t0 = std::chrono::steady_clock::now();
        r = hemi::bake::unwrap_lightmap(mesh, o);
        state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    double surface = 0.0; // in texels
    for (size_t t = 0; t + 2 < knot.indices.size(); t += 3)
        surface += 0.5 * double(glm::length(glm::cross(
                             knot.positions[knot.indices[t + 1]] - knot.positions[knot.indices[t]],
                             knot.positions[knot.indices[t + 2]] - knot.positions[knot.indices[t]])));
    surface /= double(r.texel_size) * double(r.texel_size);
    state.counters["triangles"] = double(knot.indices.size() / 3);
    state.counters["charts"] = double(r.charts);
    state.counters["texel_size"] = r.texel_size;
    state.counters["packing_efficiency"] = surface / (double(r.width) * r.height);
}

// The sample's level as hemi-bake lightmap makes it and hemi-render reads it: written as a .glb with its
// textures, baked by bake::bake_lightmap_file (hemi-bake lightmap's whole job: 8 rays a texel, a sun, every
// output lightmap/material draws) and read back by io::read_lightmap_asset, so that the asset holds what a
// real one does (images, materials, primitives) whatever the format comes to hold. In a temporary folder,
// removed afterwards. `sun_mode`: how the sun is baked (mixed: its bounces and a shadowmask).
hemi::io::LightmapAsset level_lightmap_asset(uint32_t atlas,
                                             hemi::io::LightMode sun_mode = hemi::io::LightMode::Baked)
{
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("hemi-bench-" + std::to_string(::getpid()) + "-" +
                                                      hemi::io::light_mode_name(sun_mode));
    fs::create_directories(dir);
    struct Remove
    {
        fs::path dir;
        ~Remove()
        {
            std::error_code ignored;
            fs::remove_all(dir, ignored);
        }
    } remove{dir};
    hemi::io::write_gltf(dir / "level.glb", hemi::samples::make_level(atlas));
    hemi::bake::LightmapFileOptions o;
    o.width = o.height = atlas;
    o.bake.rays = 8;
    o.lights.sun = true;
    o.lights.sun_direction = glm::normalize(glm::vec3(0.4f, -0.35f, 1.0f)); // hemi's z-up world
    o.lights.sun_irradiance = glm::vec3(6.0f);
    o.lights.sun_mode = sun_mode;
    o.outputs.assign(std::begin(kLightmapTechniques), std::end(kLightmapTechniques));
    hemi::bake::bake_lightmap_file(dir / "level.glb", dir / "level.hemi", o);
    return hemi::io::read_lightmap_asset(dir / "level.hemi");
}

// The sample level's baked asset, made once per run for every frame benchmark that draws it, and the view
// they draw it from (inside the room).
const hemi::io::LightmapAsset& level_frame_asset()
{
    static const hemi::io::LightmapAsset asset = level_lightmap_asset(g_sizes.lightmap_atlas);
    return asset;
}
glm::mat4 level_frame_view(uint32_t w, uint32_t h)
{
    return hemi::render::look_at_projection(glm::vec3(-3.0f, -3.0f, 1.7f), glm::vec3(2.0f, 2.0f, 1.2f), 70.0f,
                                            float(w) / float(h));
}

// Issue 12's frame-time goal: the lightmap material against the trivial one (Technique::Constant) on the
// sample's level at 640 x 480, seen from inside the room, in the same run: GPU time of one raster pass each,
// from timestamps (the bake of the small atlas it draws is set-up, not measured).
void lightmap_material(benchmark::State& state, std::string technique)
{
    hemi::gpu::Device& device = bench_device();
    const hemi::io::LightmapAsset& asset = level_frame_asset();
    const uint32_t w = 640, h = 480;
    hemi::render::OffscreenTarget target(device, w, h);
    hemi::render::MaterialSystem system(device, target.desc());
    hemi::gpu::UploadBatch upload(device);
    hemi::render::LightmapModel model(system, asset, {technique, "lambert"}, upload);
    upload.submit_and_wait();
    // The measured technique's frame (no dynamic light: hemi's techniques light from their coefficients) and
    // the baseline's (one light).
    hemi::render::FrameSet frame(system), baseline_frame(system);
    hemi::render::FrameData f;
    f.view_projection = level_frame_view(w, h);
    hemi::render::FrameData lit = f;
    lit.lights = {baseline_light()};
    const glm::mat4 placement = hemi::render::gltf_to_world();
    const PassTimes t = time_against_baseline(
        state, device,
        [&](VkCommandBuffer cmd)
        {
            frame.record_update(cmd, f);
            baseline_frame.record_update(cmd, lit);
        },
        [&](VkCommandBuffer cmd)
        {
            target.begin(cmd);
            model.draw(cmd, frame.set(), technique, placement);
            target.end(cmd);
        },
        [&](VkCommandBuffer cmd)
        {
            target.begin(cmd);
            model.draw(cmd, baseline_frame.set(), "lambert", placement);
            target.end(cmd);
        });
    set_ratio_counters(state, "lightmap", t);
}

// A mixed sun's cost at run time (issue 43): the same level, technique and view as lightmap_material, baked
// with its sun mixed and lit by it as a frame light with its shadowmask channel (the mask fetched per pixel,
// the sun's diffuse term added), against the same level with the sun baked and no frame light, in the same
// run: what the frame pays for a sun that can light and shadow what moves.
void lightmap_mixed(benchmark::State& state, std::string technique)
{
    hemi::gpu::Device& device = bench_device();
    static const hemi::io::LightmapAsset mixed_asset =
        level_lightmap_asset(g_sizes.lightmap_atlas, hemi::io::LightMode::Mixed);
    const uint32_t w = 640, h = 480;
    hemi::render::OffscreenTarget target(device, w, h);
    hemi::render::MaterialSystem system(device, target.desc());
    hemi::gpu::UploadBatch upload(device);
    hemi::render::LightmapModel baked(system, level_frame_asset(), {technique}, upload);
    hemi::render::LightmapModel mixed(system, mixed_asset, {technique}, upload);
    upload.submit_and_wait();
    const glm::mat4 placement = hemi::render::gltf_to_world();
    hemi::render::FrameSet baked_frame(system), mixed_frame(system);
    hemi::render::FrameData f;
    f.view_projection = level_frame_view(w, h);
    hemi::render::FrameData with_sun = f;
    with_sun.lights = hemi::render::mixed_lights(mixed_asset, placement);
    auto draw = [&](const hemi::render::LightmapModel& model, const hemi::render::FrameSet& frame)
    {
        return [&](VkCommandBuffer cmd)
        {
            target.begin(cmd);
            model.draw(cmd, frame.set(), technique, placement);
            target.end(cmd);
        };
    };
    const PassTimes t = time_against_baseline(
        state, device,
        [&](VkCommandBuffer cmd)
        {
            baked_frame.record_update(cmd, f);
            mixed_frame.record_update(cmd, with_sun);
        },
        draw(mixed, mixed_frame), draw(baked, baked_frame));
    state.counters["mixed_ms"] = t.measured * 1e3;
    state.counters["baked_ms"] = t.baseline * 1e3;
    state.counters["mixed_ratio"] = t.ratio;
    state.counters["ratio_p10"] = t.ratio_p10;
    state.counters["ratio_p90"] = t.ratio_p90;
}

// The bicubic lightmap lookup's cost (issue 43): the same level, technique and view as lightmap_material,
// drawn by a model whose pipelines look the lightmap up with the cubic B-spline (four linear fetches per
// packed layer, LightmapFilter::Bicubic) against one with the linear filter, in the same run.
void lightmap_bicubic(benchmark::State& state, std::string technique)
{
    hemi::gpu::Device& device = bench_device();
    const hemi::io::LightmapAsset& asset = level_frame_asset();
    const uint32_t w = 640, h = 480;
    hemi::render::OffscreenTarget target(device, w, h);
    hemi::render::MaterialSystem system(device, target.desc());
    hemi::gpu::UploadBatch upload(device);
    hemi::render::LightmapModel linear(system, asset, {technique}, upload);
    hemi::render::LightmapModel bicubic(system, asset, {technique}, upload, {}, nullptr,
                                        hemi::render::LightmapFilter::Bicubic);
    upload.submit_and_wait();
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection = level_frame_view(w, h);
    const glm::mat4 placement = hemi::render::gltf_to_world();
    auto draw = [&](const hemi::render::LightmapModel& model)
    {
        return [&](VkCommandBuffer cmd)
        {
            target.begin(cmd);
            model.draw(cmd, frame.set(), technique, placement);
            target.end(cmd);
        };
    };
    const PassTimes t = time_against_baseline(
        state, device, [&](VkCommandBuffer cmd) { frame.record_update(cmd, f); }, draw(bicubic),
        draw(linear));
    state.counters["bicubic_ms"] = t.measured * 1e3;
    state.counters["linear_ms"] = t.baseline * 1e3;
    state.counters["bicubic_ratio"] = t.ratio;
    state.counters["ratio_p10"] = t.ratio_p10;
    state.counters["ratio_p90"] = t.ratio_p90;
}

// Issue 22's scale: 1,000 material instances and 1,000 probe-lit objects' coefficient sources made with one
// material system, as an engine loading a large scene would. Counters: the descriptor pools they take
// (before the shared allocator: one each, 2,000), the sets, and the CPU time per object made.
void scale_materials(benchmark::State& state)
{
    hemi::gpu::Device& device = bench_device();
    const uint32_t n = 1000;
    hemi::render::OffscreenTarget target(device, 8, 8);
    hemi::render::MaterialSystem system(device, target.desc());
    hemi::gpu::UploadBatch upload(device);
    const hemi::io::Material material;
    const hemi::render::TextureSet textures(device, std::span<const hemi::io::ImageRgba8>(),
                                            std::span<const hemi::io::Material>(&material, 1), upload);
    double seconds = 0.0;
    size_t pools = 0, sets = 0;
    for (auto _ : state)
    {
        std::vector<std::unique_ptr<hemi::render::MaterialInstance>> materials;
        std::vector<std::unique_ptr<hemi::render::ProbeBuffer>> probes;
        const auto t0 = std::chrono::steady_clock::now();
        for (uint32_t i = 0; i < n; ++i)
        {
            materials.push_back(
                std::make_unique<hemi::render::MaterialInstance>(system, textures, material, upload));
            probes.push_back(std::make_unique<hemi::render::ProbeBuffer>(system, 1));
        }
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        seconds += s;
        state.SetIterationTime(s);
        pools = system.descriptors().pool_count();
        sets = system.descriptors().live_sets();
        upload.submit_and_wait();
    }
    state.counters["objects"] = 2.0 * n;
    state.counters["descriptor_pools"] = double(pools);
    state.counters["descriptor_sets"] = double(sets);
    state.counters["create_us_per_object"] = seconds / double(state.iterations()) / (2.0 * n) * 1e6;
}

// Issue 22's frame at scale: 1,000 probe-lit objects whose lighting changes every frame, 2 frames in flight,
// drawn as 10,000 draws of 2 material types (each object 10 primitives alternating a single- and a
// double-sided material) through a sorted DrawQueue. hemi runs on an adopted device whose Vulkan entry
// points count their calls (tests/vulkan_calls.h), so the counters are what a capture would show:
// barriers and buffer updates in a frame's command buffer, pipeline and descriptor-set binds of the sorted
// draws (and of the same packets unsorted, for comparison), CPU recording time per draw; and the adopted
// device's own allocator: blocks per live MiB while the objects live, blocks left once they are destroyed.
// Then the same objects once as instanced draws (ProbeObject::enqueue_instances): draws, instances and
// recording time per instance-primitive.
void scale_frame(benchmark::State& state)
{
    hemi::gpu::Device& base = bench_device();
    hemi::gpu::ExternalDevice adopt{base.instance(), base.physical_device(), base.device(),
                                    base.queue(),    base.queue_family(),    {}};
    adopt.get_instance_proc_addr = hemi::test::counting_proc_addr;
    hemi::gpu::Device device(adopt);
    hemi::test::VulkanCalls& calls = hemi::test::vulkan_calls();
    const uint32_t objects = 1000, primitives = 10, frames = 2;
    double record_seconds = 0.0, allocator_blocks = 0.0, live_mib = 0.0;
    uint64_t barriers = 0, updates = 0, pipeline_binds = 0, set_binds = 0, draws = 0, unsorted_binds = 0;
    uint64_t lighting_barriers = 0, lighting_updates = 0, instanced_draw_calls = 0;
    hemi::render::DrawStats instanced_stats;
    double instanced_seconds = 0.0;
    {
        hemi::render::OffscreenTarget target(device, 64, 64);
        hemi::render::MaterialSystem system(device, target.desc());
        hemi::gpu::UploadBatch upload(device);
        const hemi::io::Mesh mesh = hemi::io::make_uv_sphere(1.0f, 20, 10);
        std::vector<hemi::io::Material> materials(2);
        materials[1].double_sided = true;
        std::vector<hemi::io::Primitive> parts;
        const uint32_t triangles = uint32_t(mesh.indices.size() / 3);
        for (uint32_t p = 0; p < primitives; ++p)
        {
            const uint32_t first = triangles * p / primitives, last = triangles * (p + 1) / primitives;
            parts.push_back({first * 3, (last - first) * 3, p % 2});
        }
        hemi::render::ProbeObject spheres(system, mesh, {}, materials, parts, objects, upload, frames);
        hemi::render::FrameSet frame_set(system, frames, objects);
        upload.submit_and_wait();
        const hemi::gpu::MemoryAllocator::Stats memory = device.allocator().stats();
        allocator_blocks = double(memory.blocks);
        live_mib = double(memory.used_bytes) / double(1 << 20);

        hemi::render::DrawQueue queue;
        std::vector<glm::vec3> sh(9, glm::vec3(0.0f));
        uint32_t frame = 0;
        for (auto _ : state)
        {
            const uint32_t slot = frame % frames;
            calls.reset();
            const auto t0 = std::chrono::steady_clock::now();
            // The frame's data through mapped memory: view, then each object's lighting.
            hemi::render::FrameData f;
            f.view_projection = glm::scale(glm::mat4(1.0f), glm::vec3(0.02f, 0.02f, 0.5f));
            frame_set.write(slot, f);
            for (uint32_t i = 0; i < objects; ++i)
            {
                sh[0] = glm::vec3(1.0f + 0.5f * std::sin(0.1f * float(frame + i)));
                spheres.write_lighting(i, sh, slot);
            }
            lighting_barriers = calls.pipeline_barriers;
            lighting_updates = calls.buffer_updates;
            queue.clear();
            for (uint32_t i = 0; i < objects; ++i)
            {
                const glm::vec3 at(float(i % 40) - 20.0f, float(i / 40) - 12.0f, 0.0f);
                spheres.enqueue(queue, frame_set.set(slot), i, glm::translate(glm::mat4(1.0f), at), slot, 0,
                                float(i) / float(objects));
            }
            queue.sort();
            const double prepare =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            double recording = 0.0;
            hemi::render::DrawStats stats;
            hemi::gpu::one_shot(
                device,
                [&](VkCommandBuffer cmd)
                {
                    const auto r0 = std::chrono::steady_clock::now();
                    target.begin(cmd);
                    stats = queue.record(cmd);
                    target.end(cmd);
                    recording = std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
                    barriers = calls.pipeline_barriers;
                    updates = calls.buffer_updates;
                });
            state.SetIterationTime(prepare + recording);
            record_seconds += prepare + recording;
            pipeline_binds = calls.pipeline_binds;
            set_binds = calls.descriptor_set_binds;
            draws = calls.draws;
            ++frame;
        }
        // The same draws in the order they were made (each object's primitives in turn), unsorted.
        hemi::render::DrawQueue made;
        for (uint32_t i = 0; i < objects; ++i)
            spheres.enqueue(made, frame_set.set(0), i, glm::mat4(1.0f), 0);
        const std::span<const hemi::render::DrawPacket> unsorted = made.packets();
        hemi::gpu::one_shot(device,
                            [&](VkCommandBuffer cmd)
                            {
                                target.begin(cmd);
                                unsorted_binds = hemi::render::record_packets(cmd, unsorted).pipeline_binds;
                                target.end(cmd);
                            });
        // The same objects as instanced draws (one asset, 1,000 instances): each primitive drawn once, every
        // object's placement and probe in its instance record.
        std::vector<hemi::shared::DrawPush> records(objects);
        for (uint32_t i = 0; i < objects; ++i)
            records[i] = spheres.instance_record(
                i, glm::translate(glm::mat4(1.0f),
                                  glm::vec3(float(i % 40) - 20.0f, float(i / 40) - 12.0f, 0.0f)));
        frame_set.write_instances(0, records);
        hemi::render::DrawQueue instanced;
        spheres.enqueue_instances(instanced, frame_set.set(0), {0, objects});
        instanced.sort();
        calls.reset();
        hemi::gpu::one_shot(
            device,
            [&](VkCommandBuffer cmd)
            {
                target.begin(cmd);
                const auto r0 = std::chrono::steady_clock::now();
                instanced_stats = instanced.record(cmd);
                instanced_seconds =
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
                target.end(cmd);
            });
        instanced_draw_calls = calls.draws;
    }
    state.counters["objects"] = objects;
    state.counters["draws"] = double(draws);
    state.counters["lighting_barriers"] = double(lighting_barriers);
    state.counters["lighting_buffer_updates"] = double(lighting_updates);
    state.counters["frame_barriers"] = double(barriers);
    state.counters["frame_buffer_updates"] = double(updates);
    state.counters["pipeline_binds"] = double(pipeline_binds);
    state.counters["unsorted_pipeline_binds"] = double(unsorted_binds);
    state.counters["descriptor_set_binds"] = double(set_binds);
    state.counters["record_us_per_draw"] =
        record_seconds / double(state.iterations()) / double(objects * primitives) * 1e6;
    state.counters["instanced_draws"] = double(instanced_draw_calls);
    state.counters["instanced_instances"] = double(instanced_stats.instances);
    state.counters["instanced_pipeline_binds"] = double(instanced_stats.pipeline_binds);
    state.counters["instanced_record_us_per_instance"] =
        instanced_seconds / double(objects * primitives) * 1e6;
    state.counters["allocator_blocks"] = allocator_blocks;
    state.counters["blocks_per_live_mib"] = allocator_blocks / std::max(live_mib, 1e-9);
    state.counters["blocks_after_destroy"] = double(device.allocator().stats().blocks);
}

} // namespace

// Heidrich & Seidel's prefiltering (math::prefilter_phong, what hemi-bake envmap runs, and
// prefilter_phong_exact, its --exact brute force): the factored sample's studio environment (2048 x 1024, a
// small sun of radiance 2000) resampled into 2 x size^2 parabolic maps, then the diffuse map (e = 1) and the
// glossy maps for e = 10, 100 and 1000, each at glossy_size(e). The time is the fast path's; the counters:
// seconds per map of each path, their ratio, and the fast maps' RMSE against the exact ones at the envmap
// report's 1024 directions, relative to the exact maps' RMS there. The resampling and mipmaps are not timed.
void prefilter(benchmark::State& state)
{
    const hemi::io::ImageRgba env = hemi::samples::studio_environment(2048, 1024);
    const std::vector<hemi::math::ParabolicImage> chain = hemi::math::parabolic_mip_chain(
        hemi::math::parabolic_from_equirect(g_sizes.prefilter, env.width, env.height, env.pixels));
    const double exponents[] = {1.0, 10.0, 100.0, 1000.0};
    const char* names[] = {"diffuse", "e10", "e100", "e1000"};
    double seconds[4] = {0, 0, 0, 0};
    std::vector<hemi::math::ParabolicImage> fast(4);
    for (auto _ : state)
    {
        double total = 0.0;
        for (int i = 0; i < 4; ++i)
        {
            hemi::math::PrefilterStats stats;
            fast[size_t(i)] = hemi::math::prefilter_phong(chain, exponents[i], &stats);
            seconds[i] = stats.seconds;
            state.counters[std::string(names[i]) + "_pairs"] = double(stats.texel_pairs);
            total += stats.seconds;
        }
        state.SetIterationTime(total);
    }
    const uint32_t directions = 1024;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    double exact_glossy = 0.0;
    for (int i = 0; i < 4; ++i)
    {
        hemi::math::PrefilterStats stats;
        const hemi::math::ParabolicImage exact =
            hemi::math::prefilter_phong_exact(chain, exponents[i], &stats);
        if (i > 0)
            exact_glossy += stats.seconds;
        double diff = 0.0, rms = 0.0;
        for (uint32_t k = 0; k < directions; ++k)
        {
            const double z = 1.0 - (k + 0.5) * 2.0 / directions, r = std::sqrt(1.0 - z * z);
            const glm::dvec3 d(r * std::cos(golden * k), r * std::sin(golden * k), z);
            const glm::dvec3 x = exact.sample(d), f = fast[size_t(i)].sample(d);
            diff += glm::dot(f - x, f - x);
            rms += glm::dot(x, x);
        }
        state.counters[std::string(names[i]) + "_s"] = seconds[i];
        state.counters[std::string(names[i]) + "_exact_s"] = stats.seconds;
        state.counters[std::string(names[i]) + "_rmse_pct"] = 100.0 * std::sqrt(diff / rms);
    }
    state.counters["glossy_s"] = seconds[1] + seconds[2] + seconds[3]; // the goal: <= 1 s
    state.counters["glossy_exact_s"] = exact_glossy;
}

int main(int argc, char** argv)
{
    // --smoke (or HEMI_BENCH_SMOKE=1, not 0): every benchmark once at its smallest size, validation on.
    bool smoke = false;
    if (const char* env = std::getenv("HEMI_BENCH_SMOKE"))
        smoke = *env != '\0' && std::strcmp(env, "0") != 0;
    int kept = 1;
    const char* write_level = nullptr;
    for (int i = 1; i < argc; ++i)
        if (std::strcmp(argv[i], "--smoke") == 0)
            smoke = true;
        else if (std::strncmp(argv[i], "--write-large-level=", 20) == 0)
            write_level = argv[i] + 20;
        else
            argv[kept++] = argv[i];
    argc = kept;
    argv[argc] = nullptr;
    if (smoke)
        g_sizes = smoke_sizes();
    if (write_level)
    {
        // The level of lightmap/bake/large as a .glb, for bakes with hemi-bake (bench/level_scaling.sh).
        try
        {
            hemi::io::write_gltf(write_level,
                                 hemi::samples::make_large_level(g_sizes.large_rooms_x, g_sizes.large_rooms_z,
                                                                 g_sizes.large_atlas));
        }
        catch (const std::exception& e)
        {
            std::fprintf(stderr, "hemi-bench: %s\n", e.what());
            return 1;
        }
        std::printf("wrote %s (%u x %u rooms, lightmap UVs for %u^2)\n", write_level, g_sizes.large_rooms_x,
                    g_sizes.large_rooms_z, g_sizes.large_atlas);
        return 0;
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    g_triad_gbps = measure_triad_gbps();
    std::printf("memory bandwidth (STREAM triad, best of 5): %.1f GB/s\n", g_triad_gbps);
    if (smoke)
        std::printf("smoke run: every benchmark once at its smallest size, validation on; the times mean "
                    "nothing\n");
    add("stream/triad", stream_triad)->Unit(benchmark::kMillisecond)->UseRealTime();

    for (const TransferCase& c : g_sizes.transfer)
    {
        std::string suffix =
            "/N:" + std::to_string(c.n) + "/K:" + std::to_string(c.k) + "/L:" + std::to_string(c.l);
        add("transfer/gpu" + suffix, transfer_gpu, c)->Unit(benchmark::kMillisecond)->UseManualTime();
        add("transfer/cpu" + suffix, transfer_cpu, c)->Unit(benchmark::kMillisecond)->UseRealTime();
    }
    add("sh/rotate/order:6/rgb", sh_rotate_order6_rgb)->Unit(benchmark::kMicrosecond);

    for (const Table1Row& row : g_sizes.table1)
        for (const char* tech : {"gs", "sep4", "sal4", "hl2", "h4", "h6", "gs+cpca", "sep4+cpca"})
            for (bool cpu_path : {false, true})
            {
                std::string t = tech;
                const bool cpca = t.size() > 5 && t.substr(t.size() - 5) == "+cpca";
                if (cpca)
                    t = t.substr(0, t.size() - 5);
                if (g_sizes.smoke && row.random_cpca && !cpca)
                    continue; // the same path as the row before
                const std::string name = "table1/" + row.label + "/" + tech + (cpu_path ? "/cpu" : "");
                full_min_time(
                    add(name, table1, row, t, cpca, cpu_path)->Unit(benchmark::kMillisecond)->UseManualTime(),
                    0.2);
            }
    for (const char* technique : {"gs", "sep4", "sal4", "hl2", "h4", "h6", "prt"})
        full_min_time(add("material/overhead/" + g_sizes.overhead.label + "/640x480/" + technique,
                          material_overhead, std::string(technique))
                          ->Unit(benchmark::kMillisecond)
                          ->UseManualTime(),
                      3.0); // medians of ~100 interleaved frames
    full_iterations(
        add("bake/" + g_sizes.overhead.label, prt_bake)->Unit(benchmark::kMillisecond)->UseManualTime(), 2);
    const std::string relief = std::to_string(g_sizes.relief) + "x" + std::to_string(g_sizes.relief);
    full_iterations(add("ssbump/bake/" + relief + "/rays:300", ssbump_bake, true)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    full_iterations(add("ssbump/bake/" + relief + "/rays:300/no-wrap", ssbump_bake, false)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    full_iterations(
        add("ssbump/tracers/" + relief, ssbump_tracers)->Unit(benchmark::kMillisecond)->UseManualTime(), 1);
    for (const char* technique : kLightmapTechniques)
        full_min_time(add(std::string("lightmap/material/level/640x480/") + technique, lightmap_material,
                          std::string(technique))
                          ->Unit(benchmark::kMillisecond)
                          ->UseManualTime(),
                      3.0);
    for (const char* technique : {"h6", "plain"})
        full_min_time(add(std::string("lightmap/bicubic/level/640x480/") + technique, lightmap_bicubic,
                          std::string(technique))
                          ->Unit(benchmark::kMillisecond)
                          ->UseManualTime(),
                      3.0);
    for (const char* technique : {"h6", "plain"})
        full_min_time(add(std::string("lightmap/mixed/level/640x480/") + technique, lightmap_mixed,
                          std::string(technique))
                          ->Unit(benchmark::kMillisecond)
                          ->UseManualTime(),
                      3.0);
    const std::string atlas = std::to_string(g_sizes.bake_atlas) + "x" + std::to_string(g_sizes.bake_atlas);
    full_iterations(add("lightmap/bake/level/" + atlas + "/bounces:2/rays:64", lightmap_level)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    const std::string large = std::to_string(g_sizes.large_rooms_x) + "x" +
                              std::to_string(g_sizes.large_rooms_z) + "/" +
                              std::to_string(g_sizes.large_atlas) + "x" + std::to_string(g_sizes.large_atlas);
    full_iterations(add("lightmap/bake/large/" + large + "/bounces:2/rays:64", lightmap_large)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    full_iterations(add("lightmap/bake/dense/" + std::to_string(g_sizes.large_rooms_x) + "x" +
                            std::to_string(g_sizes.large_rooms_z) + "/" +
                            std::to_string(g_sizes.dense_atlas) + "x" + std::to_string(g_sizes.dense_atlas) +
                            "/split:" + std::to_string(g_sizes.dense_split) + "/bounces:2/rays:64",
                        lightmap_dense)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    full_iterations(add("lightmap/bake/q3/oa_dm3/patches:" + std::to_string(g_sizes.q3_patch_level) +
                            "/512x512/bounces:2/rays:64",
                        lightmap_q3)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    full_iterations(add("lightmap/denoise/large/" + std::to_string(g_sizes.large_rooms_x) + "x" +
                            std::to_string(g_sizes.large_rooms_z) + "/" +
                            std::to_string(std::min<uint32_t>(g_sizes.large_atlas, 1024)) + "x" +
                            std::to_string(std::min<uint32_t>(g_sizes.large_atlas, 1024)) + "/rays:32",
                        lightmap_denoise)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    3);
    full_iterations(
        add("lightmap/unwrap/knot", lightmap_unwrap)->Unit(benchmark::kMillisecond)->UseManualTime(), 1);
    const std::string parabolic = std::to_string(g_sizes.prefilter);
    full_iterations(add("prefilter/parabolic/2x" + parabolic + "^2/studio/e:1,10,100,1000", prefilter)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    1);
    full_iterations(add("scale/frame/probe_objects:1000/draws:10000", scale_frame)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    10);
    full_iterations(add("scale/materials:1000/probes:1000", scale_materials)
                        ->Unit(benchmark::kMillisecond)
                        ->UseManualTime(),
                    3);
    const size_t run = benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    g_device.reset(); // its messages at destruction (leaks) count too
    const int failures = g_failures.load();
    const uint64_t messages = g_validation_messages.load();
    if (failures > 0 || messages > 0)
    {
        std::fprintf(stderr, "hemi-bench: %d of %zu benchmark(s) threw, %llu validation message(s)\n",
                     failures, run, (unsigned long long)messages);
        return 1;
    }
    if (smoke)
        std::printf("smoke run: %zu benchmarks ran to the end\n", run);
    return 0;
}
