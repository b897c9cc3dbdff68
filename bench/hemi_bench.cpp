// hemi-bench: performance of hemi's kernels, reported as ratios measured in the same run.
//
//   stream/triad                      a[i] = b[i] + s*c[i] over 3 x 256 MiB, all cores (TBB): the memory
//                                     bandwidth every other ratio is measured against (STREAM counts 3 arrays).
//   transfer/{gpu,cpu}/N:n/K:k/L:l    the PRT transfer multiply. Counters:
//                                       GBps     = matrix bytes (N*K*L*4) / time
//                                       bw_ratio = time / (matrix bytes / triad bandwidth); 1.0 is the limit.
//                                     gpu: the reported time is the GPU timestamp difference around the
//                                     dispatches (UseManualTime); the counter wall_ms is submit + wait on the host.
//                                     cpu: wall clock of transfer_multiply_host.
//   sh/rotate/order:6/rgb             building an order-6 SH rotation and applying it to RGB lighting.
//
// Run with --benchmark_filter=... to pick; HEMI_DEVICE chooses the Vulkan device.

#include <hemi/gpu/commands.h>
#include <hemi/gpu/device.h>
#include <hemi/math/sh.h>
#include <hemi/render/transfer.h>

#include <glm/gtc/matrix_transform.hpp>

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace
{

double g_triad_gbps = 0.0; // measured by stream/triad, which runs first

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
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 20), [&](const tbb::blocked_range<size_t>& r) {
        Rng rng{seed ^ (r.begin() * 0x9E3779B97F4A7C15ull)};
        for (size_t i = r.begin(); i != r.end(); ++i)
            v[i] = rng.next();
    });
    return v;
}

void stream_triad(benchmark::State& state)
{
    const size_t n = size_t(64) << 20; // 64 Mi floats = 256 MiB per array
    std::vector<float> a(n), b(n, 1.0f), c(n, 2.0f);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i)
            a[i] = 0.0f; // first touch in parallel
    });
    const float s = 3.0f;
    for (auto _ : state)
    {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
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
    state.counters["GBps"] = benchmark::Counter(bytes * 1e-9 * double(state.iterations()), benchmark::Counter::kIsRate);
}

// Derived after the run (the rate counter needs the loop's time): we time the triad once more here.
double measure_triad_gbps()
{
    const size_t n = size_t(64) << 20;
    std::vector<float> a(n, 0.0f), b(n, 1.0f), c(n, 2.0f);
    double best = 1e30;
    for (int rep = 0; rep < 5; ++rep)
    {
        auto t0 = std::chrono::steady_clock::now();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
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

struct TransferCase
{
    uint32_t n, k, l;
};

hemi::gpu::Device& bench_device()
{
    static std::unique_ptr<hemi::gpu::Device> device = std::make_unique<hemi::gpu::Device>(hemi::gpu::DeviceDesc{});
    return *device;
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

} // namespace

int main(int argc, char** argv)
{
    benchmark::Initialize(&argc, argv);
    g_triad_gbps = measure_triad_gbps();
    std::printf("memory bandwidth (STREAM triad, best of 5): %.1f GB/s\n", g_triad_gbps);
    benchmark::RegisterBenchmark("stream/triad", stream_triad)->Unit(benchmark::kMillisecond)->UseRealTime();

    const TransferCase cases[] = {{31726, 9, 25}, {1000000, 9, 25}};
    for (const TransferCase& c : cases)
    {
        std::string suffix = "/N:" + std::to_string(c.n) + "/K:" + std::to_string(c.k) + "/L:" + std::to_string(c.l);
        benchmark::RegisterBenchmark(("transfer/gpu" + suffix).c_str(), transfer_gpu, c)
            ->Unit(benchmark::kMillisecond)
            ->UseManualTime();
        benchmark::RegisterBenchmark(("transfer/cpu" + suffix).c_str(), transfer_cpu, c)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    }
    benchmark::RegisterBenchmark("sh/rotate/order:6/rgb", sh_rotate_order6_rgb)->Unit(benchmark::kMicrosecond);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
