#pragma once
// Transfer matrices as the per-frame passes read them: dense, in hemi's block layout, or compressed with
// CPCA.
//
// The per-frame PRT transfer multiply, c_v = T_v * l (Sloan 2006, Sec. 2): on the Vulkan device
// (TransferPass) and on the host (transfer_multiply_host), over one shared data layout.
//
// T_v is a K x L matrix per vertex (K output coefficients of the pixel basis: 3 HL2, 4 SAL/H4/separable,
// 6 H6, 9 SH; L lighting SH coefficients: 9, 16, 25 or 36), l is the RGB lighting in SH (L vec3), and
// c_v is K RGB coefficients. Output layout on both paths: coefficient k of vertex v is the 4 floats at
// (v*K + k)*4 (r, g, b, 0) -- one RGBA32F texel, what a vertex shader reads with texelFetch.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace hemi::render
{

// Per-vertex transfer matrices in hemi's element-interleaved block layout (hemi/shared/transfer.h):
// blocks of 32 vertices; inside a block, element f = k*L + j of all 32 vertices is 32 consecutive floats.
// The last block is padded with zero matrices.
class TransferMatrices
{
  public:
    // `row_major` holds N matrices one after another, each K x L row-major (element (k, j) at k*L + j).
    // Throws std::invalid_argument when N is 0, K is not in [1, 9], L is not a square in [1, 36], the
    // span's size is not N*K*L, or a value is not finite.
    TransferMatrices(uint32_t vertex_count, uint32_t k, uint32_t l, std::span<const float> row_major);

    uint32_t vertex_count() const { return n_; }
    uint32_t k() const { return k_; }
    uint32_t l() const { return l_; }
    uint32_t block_count() const { return blocks_; }
    // Floats of one 32-vertex block: K * L * 32.
    size_t block_floats() const { return size_t(k_) * l_ * kBlockVertices; }
    std::span<const float> data() const { return data_; }
    // Bytes of the matrices proper, N*K*L*4: what the bandwidth ratios of hemi-bench are measured against.
    size_t matrix_bytes() const { return size_t(n_) * k_ * l_ * sizeof(float); }
    // Element (k, j) of vertex v (for tests and tools; not for hot loops).
    float at(uint32_t v, uint32_t k, uint32_t j) const;

    static constexpr uint32_t kBlockVertices = 32;

  private:
    uint32_t n_, k_, l_, blocks_;
    std::vector<float> data_;
};

// Throws std::invalid_argument with a message naming the mismatch.
void validate_transfer_shape(uint32_t vertex_count, uint32_t k, uint32_t l);

// Matrices compressed with CPCA (Sloan et al. 2003): C clusters, each a mean and V PCA matrices (K x L, the
// same row-major form as TransferMatrices' input), and per vertex a cluster and V weights.
struct CpcaMatrices
{
    uint32_t vertex_count = 0, k = 0, l = 0, clusters = 0, vectors = 0;
    std::span<const float> means;      // C x K*L
    std::span<const float> basis;      // C x V x K*L
    std::span<const uint32_t> cluster; // N
    std::span<const float> weights;    // N x V
};

} // namespace hemi::render
