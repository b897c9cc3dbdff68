#include <hemi/render/transfer.h>

#include <hemi/gpu/vk_check.h>

#include "hemi/shared/transfer.h"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hemi::render
{

static_assert(TransferMatrices::kBlockVertices == HEMI_TRANSFER_BLOCK_VERTICES);
static_assert(sizeof(TransferPush) == 4);

void validate_transfer_shape(uint32_t vertex_count, uint32_t k, uint32_t l)
{
    if (vertex_count == 0)
        throw std::invalid_argument("hemi: transfer matrices for zero vertices");
    if (k == 0 || k > HEMI_TRANSFER_MAX_K)
        throw std::invalid_argument("hemi: transfer output size K = " + std::to_string(k) + " is not in [1, " +
                                    std::to_string(HEMI_TRANSFER_MAX_K) + "]");
    uint32_t order = uint32_t(std::lround(std::sqrt(double(l))));
    if (l == 0 || l > HEMI_TRANSFER_MAX_L || order * order != l)
        throw std::invalid_argument("hemi: transfer lighting size L = " + std::to_string(l) +
                                    " is not an SH coefficient count (1, 4, 9, 16, 25 or 36)");
}

TransferMatrices::TransferMatrices(uint32_t vertex_count, uint32_t k, uint32_t l, std::span<const float> row_major)
    : n_(vertex_count), k_(k), l_(l)
{
    validate_transfer_shape(vertex_count, k, l);
    const size_t kl = size_t(k) * l;
    if (row_major.size() != size_t(vertex_count) * kl)
        throw std::invalid_argument("hemi: transfer matrices: expected " + std::to_string(size_t(vertex_count) * kl) +
                                    " floats (" + std::to_string(vertex_count) + " vertices x " + std::to_string(k) +
                                    " x " + std::to_string(l) + "), got " + std::to_string(row_major.size()));
    blocks_ = (vertex_count + kBlockVertices - 1) / kBlockVertices;
    data_.assign(size_t(blocks_) * block_floats(), 0.0f);

    std::atomic<size_t> bad{SIZE_MAX};
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, blocks_), [&](const tbb::blocked_range<uint32_t>& r) {
        for (uint32_t b = r.begin(); b != r.end(); ++b)
        {
            float* dst = data_.data() + size_t(b) * block_floats();
            uint32_t v_end = std::min(vertex_count, (b + 1) * kBlockVertices);
            for (uint32_t v = b * kBlockVertices; v < v_end; ++v)
            {
                const float* src = row_major.data() + size_t(v) * kl;
                uint32_t lane = v % kBlockVertices;
                for (size_t f = 0; f < kl; ++f)
                {
                    if (!std::isfinite(src[f]))
                    {
                        // Report the first bad value whatever the thread schedule: keep the minimum index.
                        size_t i = size_t(v) * kl + f, cur = bad.load();
                        while (i < cur && !bad.compare_exchange_weak(cur, i))
                        {
                        }
                    }
                    dst[f * kBlockVertices + lane] = src[f];
                }
            }
        }
    });
    if (size_t i = bad.load(); i != SIZE_MAX)
        throw std::invalid_argument("hemi: transfer matrices: non-finite value at vertex " + std::to_string(i / kl) +
                                    ", element " + std::to_string(i % kl));
}

float TransferMatrices::at(uint32_t v, uint32_t k, uint32_t j) const
{
    size_t f = size_t(k) * l_ + j;
    return data_[size_t(v / kBlockVertices) * block_floats() + f * kBlockVertices + v % kBlockVertices];
}

// ---------------------------------------------------------------------------------------------------------
// Host path

namespace
{

constexpr uint32_t kB = TransferMatrices::kBlockVertices;

// One block: for each output row k and each half (16 vertices) of the block, accumulate r/g/b over j.
// Six 8-wide accumulators, two row loads and three broadcasts fit the 16 vector registers of x86-64, so
// nothing spills; the second half re-reads the block from L1/L2, not memory. With AVX2+FMA (chosen at
// load time, see multiply_block) each matrix element costs 3 FMAs per 8 vertices.
typedef float v8f __attribute__((vector_size(32)));

__attribute__((always_inline)) inline void multiply_block_body(const float* __restrict m, const float* __restrict light /* L x 3 */, uint32_t K, uint32_t L,
                    float* __restrict acc /* K x 3 x 32 */)
{
    for (uint32_t k = 0; k < K; ++k)
    {
        for (uint32_t h = 0; h < kB; h += 16)
        {
            v8f r0 = {}, r1 = {}, g0 = {}, g1 = {}, b0 = {}, b1 = {};
            const float* row = m + size_t(k) * L * kB + h;
            for (uint32_t j = 0; j < L; ++j, row += kB)
            {
                v8f m0, m1; // unaligned loads (memcpy keeps it inside this target clone)
                std::memcpy(&m0, row, sizeof m0);
                std::memcpy(&m1, row + 8, sizeof m1);
                const float lr = light[j * 3 + 0], lg = light[j * 3 + 1], lb = light[j * 3 + 2];
                r0 += m0 * lr;
                r1 += m1 * lr;
                g0 += m0 * lg;
                g1 += m1 * lg;
                b0 += m0 * lb;
                b1 += m1 * lb;
            }
            float* a = acc + size_t(k) * 3 * kB + h;
            std::memcpy(a, &r0, 32);
            std::memcpy(a + 8, &r1, 32);
            std::memcpy(a + kB, &g0, 32);
            std::memcpy(a + kB + 8, &g1, 32);
            std::memcpy(a + 2 * kB, &b0, 32);
            std::memcpy(a + 2 * kB + 8, &b1, 32);
        }
    }
}

void multiply_block_default(const float* m, const float* light, uint32_t K, uint32_t L, float* acc)
{
    multiply_block_body(m, light, K, L, acc);
}

#if defined(__GNUC__) && defined(__x86_64__)
// target_clones("arch=haswell") would dispatch on the CPU *model*, not its features, so AMD CPUs with
// AVX2 would get the SSE2 clone: dispatch on the features ourselves.
__attribute__((target("avx2,fma"))) void multiply_block_avx2(const float* m, const float* light, uint32_t K,
                                                              uint32_t L, float* acc)
{
    multiply_block_body(m, light, K, L, acc);
}
using MultiplyBlockFn = void (*)(const float*, const float*, uint32_t, uint32_t, float*);
MultiplyBlockFn select_multiply_block()
{
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") ? multiply_block_avx2
                                                                           : multiply_block_default;
}
#else
using MultiplyBlockFn = void (*)(const float*, const float*, uint32_t, uint32_t, float*);
MultiplyBlockFn select_multiply_block()
{
    return multiply_block_default;
}
#endif

void check_lighting(std::span<const glm::vec3> lighting, uint32_t l)
{
    if (lighting.size() != l)
        throw std::invalid_argument("hemi: transfer lighting has " + std::to_string(lighting.size()) +
                                    " coefficients, the matrices expect L = " + std::to_string(l));
    for (const glm::vec3& c : lighting)
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
            throw std::invalid_argument("hemi: transfer lighting contains a non-finite value");
}

} // namespace

void transfer_multiply_host(const TransferMatrices& matrices, std::span<const glm::vec3> lighting,
                            std::span<float> out)
{
    const uint32_t N = matrices.vertex_count(), K = matrices.k(), L = matrices.l();
    check_lighting(lighting, L);
    if (out.size() != size_t(N) * K * 4)
        throw std::invalid_argument("hemi: transfer output has " + std::to_string(out.size()) + " floats, expected " +
                                    std::to_string(size_t(N) * K * 4) + " (N*K*4)");
    float light[HEMI_TRANSFER_MAX_L * 3];
    for (uint32_t j = 0; j < L; ++j)
    {
        light[j * 3 + 0] = lighting[j].x;
        light[j * 3 + 1] = lighting[j].y;
        light[j * 3 + 2] = lighting[j].z;
    }
    static const MultiplyBlockFn multiply_block = select_multiply_block(); // immutable after first use
    const float* data = matrices.data().data();
    const size_t block_floats = matrices.block_floats();
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, matrices.block_count(), 64),
                      [&](const tbb::blocked_range<uint32_t>& range) {
                          float acc[HEMI_TRANSFER_MAX_K * 3 * kB];
                          for (uint32_t blk = range.begin(); blk != range.end(); ++blk)
                          {
                              multiply_block(data + size_t(blk) * block_floats, light, K, L, acc);
                              uint32_t v0 = blk * kB, count = std::min(kB, N - v0);
                              for (uint32_t i = 0; i < count; ++i)
                              {
                                  float* o = out.data() + (size_t(v0 + i) * K) * 4;
                                  for (uint32_t k = 0; k < K; ++k)
                                  {
                                      const float* a = acc + size_t(k) * 3 * kB;
                                      o[k * 4 + 0] = a[i];
                                      o[k * 4 + 1] = a[kB + i];
                                      o[k * 4 + 2] = a[2 * kB + i];
                                      o[k * 4 + 3] = 0.0f;
                                  }
                              }
                          }
                      });
}

// ---------------------------------------------------------------------------------------------------------
// Device path

namespace
{
uint64_t align_up(uint64_t value, uint64_t alignment)
{
    alignment = std::max<uint64_t>(1, alignment);
    return (value + alignment - 1) / alignment * alignment;
}

// Instances of one source: instance i's lighting at i * stride bytes of the lighting buffer (a dynamic
// uniform offset), its coefficients at i * stride texels of the output (views at aligned offsets).
struct InstanceLayout
{
    uint32_t count = 1;
    VkDeviceSize lighting_stride = 0; // bytes
    uint64_t coefficient_stride = 0;  // texels
};

InstanceLayout instance_layout(const gpu::Device& device, uint32_t instances, uint32_t n, uint32_t k)
{
    if (instances == 0)
        throw std::invalid_argument("hemi: a coefficient source needs at least one instance");
    const VkPhysicalDeviceLimits& limits = device.limits();
    InstanceLayout layout;
    layout.count = instances;
    layout.lighting_stride = align_up(HEMI_TRANSFER_MAX_L * 16, limits.minUniformBufferOffsetAlignment);
    layout.coefficient_stride = align_up(uint64_t(n) * k * 16, std::lcm<uint64_t>(16, std::max<uint64_t>(1, limits.minTexelBufferOffsetAlignment))) / 16;
    if (layout.coefficient_stride * instances > limits.maxTexelBufferElements)
        throw std::invalid_argument("hemi: " + std::to_string(instances) + " instances of " + std::to_string(n) +
                                    " vertices' coefficients exceed the device's maxTexelBufferElements");
    return layout;
}
} // namespace

struct TransferPass::Impl
{
    const gpu::Device* device;
    uint32_t n, k, l;
    InstanceLayout instances;
    gpu::Buffer matrices;
    gpu::Buffer lighting;
    gpu::Buffer coefficients;
    gpu::Program program;
    gpu::DescriptorPool pool;
    struct Segment
    {
        gpu::BufferView matrix_view;
        gpu::BufferView coefficient_view;
        VkDescriptorSet set;
        uint32_t vertex_count;
    };
    std::vector<Segment> segments; // instance i's segment s at i * segment_count + s
    uint32_t segment_count = 0;
};

static std::vector<gpu::Binding> transfer_bindings()
{
    return {
        {HEMI_TRANSFER_BINDING_MATRICES, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
        {HEMI_TRANSFER_BINDING_LIGHTING, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, VK_SHADER_STAGE_COMPUTE_BIT},
        {HEMI_TRANSFER_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
    };
}

TransferPass::TransferPass(const gpu::Device& device, const TransferMatrices& m, uint64_t max_view_texels,
                           uint32_t instances)
    : impl_(std::make_unique<Impl>())
{
    Impl& s = *impl_;
    s.device = &device;
    s.n = m.vertex_count();
    s.k = m.k();
    s.l = m.l();
    s.instances = instance_layout(device, instances, s.n, s.k);

    const VkDeviceSize matrix_bytes = m.data().size_bytes();
    s.matrices = gpu::create_buffer(device, {matrix_bytes, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
    gpu::write_buffer(device, s.matrices, m.data().data(), matrix_bytes);
    s.lighting = gpu::create_buffer(device, {s.instances.lighting_stride * instances, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    const VkDeviceSize coefficient_bytes = s.instances.coefficient_stride * 16 * instances;
    s.coefficients = gpu::create_buffer(
        device, {coefficient_bytes, VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});

    std::vector<gpu::Binding> bindings = transfer_bindings();
    s.program = gpu::create_compute_program(
        device, {gpu::embedded_spirv("prt_transfer.comp"), bindings, sizeof(TransferPush), {s.k, s.l}});

    // Segments: whole blocks, at most maxTexelBufferElements texels of matrices (and of coefficients) per
    // view, with view offsets that respect minTexelBufferOffsetAlignment.
    const VkPhysicalDeviceLimits& limits = device.limits();
    const uint64_t block_texels = uint64_t(s.k) * s.l * HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    const uint64_t block_bytes = block_texels * 16;
    const uint64_t out_block_bytes = uint64_t(HEMI_TRANSFER_BLOCK_VERTICES) * s.k * 16;
    uint64_t max_texels = limits.maxTexelBufferElements;
    if (max_view_texels != 0)
        max_texels = std::min<uint64_t>(max_texels, max_view_texels);
    uint64_t blocks_per_segment = max_texels / block_texels;
    blocks_per_segment = std::min<uint64_t>(blocks_per_segment, max_texels / (HEMI_TRANSFER_BLOCK_VERTICES * s.k));
    // One dispatch per segment: its workgroup count must stay within maxComputeWorkGroupCount[0] (65,535 on
    // many drivers, reached by K = 3, L = 9 sets of ~17M vertices before the texel limit is).
    blocks_per_segment = std::min<uint64_t>(blocks_per_segment, uint64_t(limits.maxComputeWorkGroupCount[0]) *
                                                                    HEMI_TRANSFER_WORKGROUP_SIZE /
                                                                    HEMI_TRANSFER_INVOCATIONS_PER_BLOCK);
    const uint64_t align = std::max<uint64_t>(1, limits.minTexelBufferOffsetAlignment);
    const uint64_t step = std::lcm(align / std::gcd(align, block_bytes), align / std::gcd(align, out_block_bytes));
    blocks_per_segment -= blocks_per_segment % step;
    if (blocks_per_segment == 0)
        throw std::runtime_error("hemi: device " + std::string(device.name()) +
                                 " cannot hold one block of transfer matrices in a texel buffer");

    const uint32_t total_blocks = m.block_count();
    const uint32_t segment_count = uint32_t((total_blocks + blocks_per_segment - 1) / blocks_per_segment);
    s.segment_count = segment_count;
    s.pool = gpu::create_descriptor_pool(device, bindings, segment_count * instances);
    for (uint32_t instance = 0; instance < instances; ++instance)
    for (uint32_t i = 0; i < segment_count; ++i)
    {
        const VkDeviceSize instance_base = instance * s.instances.coefficient_stride * 16;
        uint64_t first_block = i * blocks_per_segment;
        uint64_t blocks = std::min<uint64_t>(blocks_per_segment, total_blocks - first_block);
        uint64_t first_vertex = first_block * HEMI_TRANSFER_BLOCK_VERTICES;
        Impl::Segment seg;
        seg.vertex_count = uint32_t(std::min<uint64_t>(blocks * HEMI_TRANSFER_BLOCK_VERTICES, s.n - first_vertex));
        seg.matrix_view = gpu::create_buffer_view(device, s.matrices, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                  first_block * block_bytes, blocks * block_bytes);
        seg.coefficient_view = gpu::create_buffer_view(device, s.coefficients, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                       instance_base + first_vertex * s.k * 16,
                                                       uint64_t(seg.vertex_count) * s.k * 16);
        seg.set = gpu::allocate_descriptor_set(device, s.pool, s.program.set_layout);
        gpu::DescriptorWrite writes[3];
        writes[0].binding = HEMI_TRANSFER_BINDING_MATRICES;
        writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
        writes[0].texel_view = seg.matrix_view;
        writes[1].binding = HEMI_TRANSFER_BINDING_LIGHTING;
        writes[1].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC;
        writes[1].buffer = {s.lighting, 0, HEMI_TRANSFER_MAX_L * 16};
        writes[2].binding = HEMI_TRANSFER_BINDING_COEFFICIENTS;
        writes[2].type = VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
        writes[2].texel_view = seg.coefficient_view;
        gpu::write_descriptors(device, seg.set, writes);
        s.segments.push_back(std::move(seg));
    }
}

TransferPass::~TransferPass() = default;

namespace
{
// How many instances `lighting` holds (L coefficients each); throws when it is not a whole number of them
// within the capacity.
uint32_t lighting_instances(std::span<const glm::vec3> lighting, uint32_t l, uint32_t capacity)
{
    if (lighting.empty() || lighting.size() % l != 0 || lighting.size() / l > capacity)
        throw std::invalid_argument("hemi: lighting has " + std::to_string(lighting.size()) +
                                    " SH coefficients: expected L = " + std::to_string(l) + " per instance for 1 to " +
                                    std::to_string(capacity) + " instances");
    for (size_t i = 0; i < lighting.size(); i += l)
        check_lighting(lighting.subspan(i, l), l);
    return uint32_t(lighting.size() / l);
}

// The per-frame lighting update both passes start with: instance i's L coefficients at i * stride bytes.
void record_lighting_update(VkCommandBuffer cmd, const gpu::Buffer& buffer, std::span<const glm::vec3> lighting,
                            uint32_t l, VkDeviceSize stride)
{
    const size_t instances = lighting.size() / l;
    std::vector<float> packed(instances * stride / 4, 0.0f);
    for (size_t i = 0; i < instances; ++i)
        for (uint32_t j = 0; j < l; ++j)
        {
            float* p = &packed[i * stride / 4 + j * 4];
            p[0] = lighting[i * l + j].x;
            p[1] = lighting[i * l + j].y;
            p[2] = lighting[i * l + j].z;
        }
    // Earlier reads of the lighting (a previous frame's dispatch) finish before the update; the update
    // finishes before this frame's dispatch reads it. Earlier reads of the coefficients (vertex shaders)
    // finish before this dispatch overwrites them.
    // ALL_COMMANDS as the source: valid on compute-only queues, and covers readers in any shader stage.
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_UNIFORM_READ_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                        VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    // vkCmdUpdateBuffer takes at most 65,536 bytes per call.
    const VkDeviceSize bytes = packed.size() * 4;
    for (VkDeviceSize offset = 0; offset < bytes; offset += 65536)
        vkCmdUpdateBuffer(cmd, buffer, offset, std::min<VkDeviceSize>(65536, bytes - offset),
                          reinterpret_cast<const std::byte*>(packed.data()) + offset);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_UNIFORM_READ_BIT);
}
} // namespace

void TransferPass::record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting)
{
    Impl& s = *impl_;
    const uint32_t instances = lighting_instances(lighting, s.l, s.instances.count);
    record_lighting_update(cmd, s.lighting, lighting, s.l, s.instances.lighting_stride);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.program.pipeline);
    for (uint32_t i = 0; i < instances * s.segment_count; ++i)
    {
        const Impl::Segment& seg = s.segments[i];
        const uint32_t offset = uint32_t((i / s.segment_count) * s.instances.lighting_stride);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.program.layout, 0, 1, &seg.set, 1, &offset);
        TransferPush push{seg.vertex_count};
        vkCmdPushConstants(cmd, s.program.layout, VK_SHADER_STAGE_ALL, 0, sizeof push, &push);
        uint32_t invocations = (seg.vertex_count + HEMI_TRANSFER_VERTICES_PER_INVOCATION - 1) /
                               HEMI_TRANSFER_VERTICES_PER_INVOCATION;
        vkCmdDispatch(cmd, (invocations + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE, 1, 1);
    }
}

void CoefficientSource::run(std::span<const glm::vec3> lighting)
{
    gpu::one_shot(device(), [&](VkCommandBuffer cmd) {
        record(cmd, lighting);
        // A fence wait alone does not make device writes visible to the host.
        gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                            VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                            VK_ACCESS_HOST_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT);
    });
}

const gpu::Buffer& TransferPass::coefficients() const
{
    return impl_->coefficients;
}

std::vector<float> CoefficientSource::read_coefficients() const
{
    std::vector<float> out(size_t(vertex_count()) * k() * 4);
    gpu::read_buffer(device(), coefficients(), out.data(), out.size() * sizeof(float));
    return out;
}

uint32_t TransferPass::vertex_count() const { return impl_->n; }
uint32_t TransferPass::k() const { return impl_->k; }
uint32_t TransferPass::l() const { return impl_->l; }
uint32_t TransferPass::segment_count() const { return impl_->segment_count; }
uint32_t TransferPass::instances() const { return impl_->instances.count; }
uint64_t TransferPass::instance_stride() const { return impl_->instances.coefficient_stride; }
const gpu::Device& TransferPass::device() const { return *impl_->device; }

namespace
{
// Sizes and cluster ids always (memory safety); the values' finiteness when `values` (once, when data are
// loaded onto the device; read_prt_asset has checked them too).
void validate_cpca(const CpcaMatrices& c, bool values = true)
{
    validate_transfer_shape(c.vertex_count, c.k, c.l);
    const size_t d = size_t(c.k) * c.l;
    if (c.clusters == 0 || c.vectors == 0)
        throw std::invalid_argument("hemi: CPCA needs at least one cluster and one vector");
    if (c.means.size() != c.clusters * d || c.basis.size() != size_t(c.clusters) * c.vectors * d ||
        c.cluster.size() != c.vertex_count || c.weights.size() != size_t(c.vertex_count) * c.vectors)
        throw std::invalid_argument("hemi: CPCA array sizes do not match " + std::to_string(c.clusters) + "x" +
                                    std::to_string(c.vectors) + " clusters x vectors over " +
                                    std::to_string(c.vertex_count) + " vertices");
    for (uint32_t id : c.cluster)
        if (id >= c.clusters)
            throw std::invalid_argument("hemi: CPCA cluster id " + std::to_string(id) + " out of range");
    if (values)
        for (std::span<const float> array : {c.means, c.basis, c.weights})
            for (float v : array)
                if (!std::isfinite(v))
                    throw std::invalid_argument("hemi: CPCA data contain a non-finite value");
}
} // namespace

void cpca_multiply_host(const CpcaMatrices& c, std::span<const glm::vec3> lighting, std::span<float> out)
{
    validate_cpca(c, false);
    check_lighting(lighting, c.l);
    if (out.size() != size_t(c.vertex_count) * c.k * 4)
        throw std::invalid_argument("hemi: CPCA output has " + std::to_string(out.size()) + " floats, expected " +
                                    std::to_string(size_t(c.vertex_count) * c.k * 4));
    const size_t d = size_t(c.k) * c.l;
    const Eigen::Index rows = Eigen::Index(c.k) * 4, V = c.vectors;
    // Step 1: per cluster, a (4K) x (V + 1) matrix: column j is row j (the mean, then the V vectors) times
    // the lighting, RGB plus a zero alpha, already in the output's texel layout.
    std::vector<Eigen::MatrixXf> projected(c.clusters, Eigen::MatrixXf::Zero(rows, V + 1));
    for (uint32_t cl = 0; cl < c.clusters; ++cl)
        for (uint32_t j = 0; j <= c.vectors; ++j)
        {
            const float* m = j == 0 ? &c.means[cl * d] : &c.basis[(size_t(cl) * c.vectors + j - 1) * d];
            for (uint32_t k = 0; k < c.k; ++k)
            {
                glm::vec3 sum(0.0f);
                for (uint32_t i = 0; i < c.l; ++i)
                    sum += m[k * c.l + i] * lighting[i];
                for (int ch = 0; ch < 3; ++ch)
                    projected[cl](Eigen::Index(k) * 4 + ch, j) = sum[ch];
            }
        }
    // Step 2: out_v = P_c [1; w_v]. With one cluster a block of vertices is one matrix product (Eigen's
    // vectorised GEMM: the weights, N x V row-major, are a V x N column-major matrix); otherwise one
    // matrix-vector product per vertex.
    using ConstMap = Eigen::Map<const Eigen::MatrixXf>;
    using Map = Eigen::Map<Eigen::MatrixXf>;
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, c.vertex_count, 2048), [&](const tbb::blocked_range<uint32_t>& r) {
        const Eigen::Index count = Eigen::Index(r.end() - r.begin());
        Map o(out.data() + size_t(r.begin()) * rows, rows, count);
        ConstMap w(c.weights.data() + size_t(r.begin()) * V, V, count);
        if (c.clusters == 1)
        {
            o = projected[0].col(0).replicate(1, count);
            o.noalias() += projected[0].rightCols(V) * w;
        }
        else
            for (Eigen::Index i = 0; i < count; ++i)
            {
                const Eigen::MatrixXf& p = projected[c.cluster[r.begin() + uint32_t(i)]];
                o.col(i) = p.col(0);
                o.col(i).noalias() += p.rightCols(V) * w.col(i);
            }
    });
}

struct CpcaTransferPass::Impl
{
    const gpu::Device* device;
    uint32_t n, k, l, rows, per_cluster;
    InstanceLayout instances;
    VkDeviceSize projected_instance_bytes = 0; // one instance's projections, aligned
    VkDeviceSize projected_stride; // bytes between clusters' projections (aligned for dynamic offsets)
    struct Run
    {
        uint32_t cluster, first_invocation, invocations;
    };
    std::vector<Run> runs; // one dispatch per non-empty cluster
    gpu::Buffer rows_buffer, lighting, projected, weights, slots, coefficients;
    gpu::BufferView coefficient_view, weight_view;
    gpu::Program project, reconstruct;
    gpu::DescriptorPool pool;
    std::vector<gpu::BufferView> instance_views;
    std::vector<VkDescriptorSet> project_sets, reconstruct_sets; // one each per instance
};

CpcaTransferPass::CpcaTransferPass(const gpu::Device& device, const CpcaMatrices& c, uint32_t instances)
    : impl_(std::make_unique<Impl>())
{
    validate_cpca(c);
    Impl& s = *impl_;
    s.device = &device;
    s.n = c.vertex_count;
    s.k = c.k;
    s.l = c.l;
    s.instances = instance_layout(device, instances, s.n, s.k);
    const size_t d = size_t(c.k) * c.l;
    s.rows = c.clusters * (c.vectors + 1) * c.k;
    s.per_cluster = (c.vectors + 1) * c.k;
    const VkPhysicalDeviceLimits& limits = device.limits();
    auto storage = [&](VkDeviceSize bytes, const char* what) {
        if (bytes > limits.maxStorageBufferRange)
            throw std::runtime_error("hemi: CPCA " + std::string(what) + " (" + std::to_string(bytes) +
                                     " bytes) exceed the device's maxStorageBufferRange");
        return gpu::create_buffer(device, {bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    };
    if (c.vectors > HEMI_CPCA_MAX_VECTORS)
        throw std::invalid_argument("hemi: the CPCA pass supports up to " + std::to_string(HEMI_CPCA_MAX_VECTORS) +
                                    " vectors per cluster, got " + std::to_string(c.vectors));
    // Rows: per cluster, the mean then the V vectors, each K x L.
    std::vector<float> rows(size_t(s.rows) * c.l);
    for (uint32_t cl = 0; cl < c.clusters; ++cl)
    {
        std::copy_n(&c.means[cl * d], d, &rows[size_t(cl) * (c.vectors + 1) * d]);
        std::copy_n(&c.basis[size_t(cl) * c.vectors * d], size_t(c.vectors) * d,
                    &rows[(size_t(cl) * (c.vectors + 1) + 1) * d]);
    }
    // Slots: vertices grouped by cluster, each cluster's run padded to whole 32-slot blocks (one dispatch per
    // cluster); weights element-interleaved in blocks of 32 slots, as the dense matrices are.
    constexpr uint32_t kNone = 0xffffffffu, kBlock = HEMI_TRANSFER_BLOCK_VERTICES;
    std::vector<std::vector<uint32_t>> members(c.clusters);
    for (uint32_t v = 0; v < c.vertex_count; ++v)
        members[c.cluster[v]].push_back(v);
    std::vector<uint32_t> slot_vertex;
    uint32_t largest_run = 0;
    for (uint32_t cl = 0; cl < c.clusters; ++cl)
    {
        if (members[cl].empty())
            continue;
        const uint32_t first = uint32_t(slot_vertex.size() / HEMI_TRANSFER_VERTICES_PER_INVOCATION);
        slot_vertex.insert(slot_vertex.end(), members[cl].begin(), members[cl].end());
        slot_vertex.resize((slot_vertex.size() + kBlock - 1) / kBlock * kBlock, kNone);
        const uint32_t count = uint32_t(slot_vertex.size() / HEMI_TRANSFER_VERTICES_PER_INVOCATION) - first;
        s.runs.push_back({cl, first, count});
        largest_run = std::max(largest_run, count);
    }
    const VkDeviceSize align = std::max<VkDeviceSize>(1, limits.minUniformBufferOffsetAlignment);
    s.projected_stride = (VkDeviceSize(c.vectors + 1) * c.k * 16 + align - 1) / align * align;
    if (HEMI_CPCA_PROJECTED_BYTES > limits.maxUniformBufferRange)
        throw std::runtime_error("hemi: the device's maxUniformBufferRange is below the CPCA pass's uniform block");
    const uint32_t V = c.vectors, per_block = HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    std::vector<float> interleaved(slot_vertex.size() * V, 0.0f);
    for (size_t slot = 0; slot < slot_vertex.size(); ++slot)
    {
        if (slot_vertex[slot] == kNone)
            continue;
        const size_t invocation = slot / 4, block = invocation / per_block, lane = invocation % per_block;
        for (uint32_t j = 0; j < V; ++j)
            interleaved[((block * V + j) * per_block + lane) * 4 + slot % 4] =
                c.weights[size_t(slot_vertex[slot]) * V + j];
    }
    if ((uint64_t(largest_run) + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE >
            limits.maxComputeWorkGroupCount[0] ||
        (uint64_t(s.rows) + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE >
            limits.maxComputeWorkGroupCount[0])
        throw std::runtime_error("hemi: CPCA pass over " + std::to_string(s.n) +
                                 " vertices exceeds the device's maxComputeWorkGroupCount");
    if (uint64_t(s.n) * s.k > limits.maxTexelBufferElements ||
        interleaved.size() / 4 > limits.maxTexelBufferElements)
        throw std::runtime_error("hemi: CPCA data of " + std::to_string(s.n) +
                                 " vertices exceed the device's maxTexelBufferElements");
    s.rows_buffer = storage(rows.size() * 4, "cluster matrices");
    gpu::write_buffer(device, s.rows_buffer, rows.data(), rows.size() * 4);
    s.weights = gpu::create_buffer(device, {interleaved.size() * 4, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
    gpu::write_buffer(device, s.weights, interleaved.data(), interleaved.size() * 4);
    s.weight_view = gpu::create_buffer_view(device, s.weights, VK_FORMAT_R32G32B32A32_SFLOAT, 0,
                                            interleaved.size() * 4);
    s.slots = storage(slot_vertex.size() * 4, "vertex slots");
    gpu::write_buffer(device, s.slots, slot_vertex.data(), slot_vertex.size() * 4);
    // Written by step 1 as a storage buffer, read by step 2 as a uniform block at a dynamic offset: cluster
    // c's projections start at c * stride.
    if (s.projected_stride * (c.clusters - 1) + HEMI_CPCA_PROJECTED_BYTES > limits.maxStorageBufferRange)
        throw std::runtime_error("hemi: CPCA projections of " + std::to_string(c.clusters) +
                                 " clusters exceed the device's maxStorageBufferRange");
    const VkDeviceSize projected_bytes = s.projected_stride * (c.clusters - 1) + HEMI_CPCA_PROJECTED_BYTES;
    s.projected_instance_bytes =
        align_up(projected_bytes, std::max(limits.minUniformBufferOffsetAlignment, limits.minStorageBufferOffsetAlignment));
    s.projected = gpu::create_buffer(device, {s.projected_instance_bytes * instances,
                                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    s.lighting = gpu::create_buffer(device, {s.instances.lighting_stride * instances, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    const VkDeviceSize coefficient_bytes = s.instances.coefficient_stride * 16 * instances;
    s.coefficients = gpu::create_buffer(
        device, {coefficient_bytes, VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});

    const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
    const std::vector<gpu::Binding> project_bindings = {
        {HEMI_CPCA_BINDING_ROWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
        {HEMI_CPCA_BINDING_LIGHTING, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, cs},
        {HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
    };
    const std::vector<gpu::Binding> reconstruct_bindings = {
        {HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, cs},
        {HEMI_CPCA_BINDING_WEIGHTS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, cs},
        {HEMI_CPCA_BINDING_SLOTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
        {HEMI_CPCA_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, cs},
    };
    s.project = gpu::create_compute_program(
        device, {gpu::embedded_spirv("cpca_project.comp"), project_bindings, sizeof(CpcaPush), {s.l}});
    s.reconstruct = gpu::create_compute_program(
        device, {gpu::embedded_spirv("cpca_reconstruct.comp"), reconstruct_bindings, sizeof(CpcaPush),
                 {s.k, c.vectors}});
    std::vector<gpu::Binding> all = project_bindings;
    all.insert(all.end(), reconstruct_bindings.begin(), reconstruct_bindings.end());
    s.pool = gpu::create_descriptor_pool(device, all, 2 * instances);
    auto buffer_write = [](uint32_t binding, VkDescriptorType type, VkBuffer buffer, VkDeviceSize offset,
                           VkDeviceSize range) {
        gpu::DescriptorWrite w;
        w.binding = binding;
        w.type = type;
        w.buffer = {buffer, offset, range};
        return w;
    };
    for (uint32_t i = 0; i < instances; ++i)
    {
        const VkDeviceSize projected_base = i * s.projected_instance_bytes;
        const VkDeviceSize coefficient_base = i * s.instances.coefficient_stride * 16;
        s.instance_views.push_back(gpu::create_buffer_view(device, s.coefficients, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                           coefficient_base, VkDeviceSize(s.n) * s.k * 16));
        const VkDescriptorSet project_set = gpu::allocate_descriptor_set(device, s.pool, s.project.set_layout);
        const VkDescriptorSet reconstruct_set = gpu::allocate_descriptor_set(device, s.pool, s.reconstruct.set_layout);
        gpu::DescriptorWrite project_writes[3] = {
            buffer_write(HEMI_CPCA_BINDING_ROWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, s.rows_buffer, 0, VK_WHOLE_SIZE),
            buffer_write(HEMI_CPCA_BINDING_LIGHTING, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, s.lighting, 0,
                         HEMI_TRANSFER_MAX_L * 16),
            buffer_write(HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, s.projected, projected_base,
                         projected_bytes),
        };
        gpu::write_descriptors(device, project_set, project_writes);
        gpu::DescriptorWrite reconstruct_writes[4] = {
            buffer_write(HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, s.projected,
                         projected_base, HEMI_CPCA_PROJECTED_BYTES),
            {},
            buffer_write(HEMI_CPCA_BINDING_SLOTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, s.slots, 0, VK_WHOLE_SIZE),
            {},
        };
        reconstruct_writes[1].binding = HEMI_CPCA_BINDING_WEIGHTS;
        reconstruct_writes[1].type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
        reconstruct_writes[1].texel_view = s.weight_view;
        reconstruct_writes[3].binding = HEMI_CPCA_BINDING_COEFFICIENTS;
        reconstruct_writes[3].type = VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
        reconstruct_writes[3].texel_view = s.instance_views.back();
        gpu::write_descriptors(device, reconstruct_set, reconstruct_writes);
        s.project_sets.push_back(project_set);
        s.reconstruct_sets.push_back(reconstruct_set);
    }
}

CpcaTransferPass::~CpcaTransferPass() = default;

void CpcaTransferPass::record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting)
{
    Impl& s = *impl_;
    const uint32_t instances = lighting_instances(lighting, s.l, s.instances.count);
    record_lighting_update(cmd, s.lighting, lighting, s.l, s.instances.lighting_stride);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.project.pipeline);
    const CpcaPush push{s.rows, 0, s.per_cluster, uint32_t(s.projected_stride / 16)};
    vkCmdPushConstants(cmd, s.project.layout, VK_SHADER_STAGE_ALL, 0, sizeof push, &push);
    for (uint32_t i = 0; i < instances; ++i)
    {
        const uint32_t lighting_offset = uint32_t(i * s.instances.lighting_stride);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.project.layout, 0, 1, &s.project_sets[i], 1,
                                &lighting_offset);
        vkCmdDispatch(cmd, (s.rows + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE, 1, 1);
    }
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_UNIFORM_READ_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.reconstruct.pipeline);
    for (uint32_t i = 0; i < instances; ++i)
    for (const Impl::Run& run : s.runs)
    {
        const uint32_t offset = uint32_t(run.cluster * s.projected_stride);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.reconstruct.layout, 0, 1, &s.reconstruct_sets[i], 1,
                                &offset);
        const CpcaPush run_push{run.invocations, run.first_invocation, 0, 0};
        vkCmdPushConstants(cmd, s.reconstruct.layout, VK_SHADER_STAGE_ALL, 0, sizeof run_push, &run_push);
        vkCmdDispatch(cmd, (run.invocations + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE, 1, 1);
    }
}

const gpu::Buffer& CpcaTransferPass::coefficients() const { return impl_->coefficients; }
uint32_t CpcaTransferPass::instances() const { return impl_->instances.count; }
uint64_t CpcaTransferPass::instance_stride() const { return impl_->instances.coefficient_stride; }
uint32_t CpcaTransferPass::vertex_count() const { return impl_->n; }
uint32_t CpcaTransferPass::k() const { return impl_->k; }
uint32_t CpcaTransferPass::l() const { return impl_->l; }
const gpu::Device& CpcaTransferPass::device() const { return *impl_->device; }

} // namespace hemi::render
