// The host paths of the per-frame transfer: the dense multiply (AVX2 + FMA or SSE2, TBB over blocks) and the
// CPCA multiply (Eigen). Same output layout as the device passes.
#include <hemi/render/passes/host_transfer.h>

#include "pass_detail.h"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hemi::render
{
using detail::check_lighting;
using detail::validate_cpca;

namespace
{

constexpr uint32_t kB = TransferMatrices::kBlockVertices;

// One block: for each output row k and each half (16 vertices) of the block, accumulate r/g/b over j.
// Six 8-wide accumulators, two row loads and three broadcasts fit the 16 vector registers of x86-64, so
// nothing spills; the second half re-reads the block from L1/L2, not memory. With AVX2+FMA (chosen at
// load time, see multiply_block) each matrix element costs 3 FMAs per 8 vertices.
typedef float v8f __attribute__((vector_size(32)));

__attribute__((always_inline)) inline void multiply_block_body(const float* __restrict m,
                                                               const float* __restrict light /* L x 3 */,
                                                               uint32_t K, uint32_t L,
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

} // namespace

void transfer_multiply_host(const TransferMatrices& matrices, std::span<const glm::vec3> lighting,
                            std::span<float> out)
{
    const uint32_t N = matrices.vertex_count(), K = matrices.k(), L = matrices.l();
    check_lighting(lighting, L);
    if (out.size() != size_t(N) * K * 4)
        throw std::invalid_argument("hemi: transfer output has " + std::to_string(out.size()) +
                                    " floats, expected " + std::to_string(size_t(N) * K * 4) + " (N*K*4)");
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
                      [&](const tbb::blocked_range<uint32_t>& range)
                      {
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

void cpca_multiply_host(const CpcaMatrices& c, std::span<const glm::vec3> lighting, std::span<float> out)
{
    validate_cpca(c, false);
    check_lighting(lighting, c.l);
    if (out.size() != size_t(c.vertex_count) * c.k * 4)
        throw std::invalid_argument("hemi: CPCA output has " + std::to_string(out.size()) +
                                    " floats, expected " + std::to_string(size_t(c.vertex_count) * c.k * 4));
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
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, c.vertex_count, 2048),
                      [&](const tbb::blocked_range<uint32_t>& r)
                      {
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

} // namespace hemi::render
