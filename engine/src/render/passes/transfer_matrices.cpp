#include <hemi/render/passes/transfer_matrices.h>

#include "hemi/shared/transfer.h"

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
        throw std::invalid_argument("hemi: transfer output size K = " + std::to_string(k) +
                                    " is not in [1, " + std::to_string(HEMI_TRANSFER_MAX_K) + "]");
    uint32_t order = uint32_t(std::lround(std::sqrt(double(l))));
    if (l == 0 || l > HEMI_TRANSFER_MAX_L || order * order != l)
        throw std::invalid_argument("hemi: transfer lighting size L = " + std::to_string(l) +
                                    " is not an SH coefficient count (1, 4, 9, 16, 25 or 36)");
}

TransferMatrices::TransferMatrices(uint32_t vertex_count, uint32_t k, uint32_t l,
                                   std::span<const float> row_major)
    : n_(vertex_count), k_(k), l_(l)
{
    validate_transfer_shape(vertex_count, k, l);
    const size_t kl = size_t(k) * l;
    if (row_major.size() != size_t(vertex_count) * kl)
        throw std::invalid_argument("hemi: transfer matrices: expected " +
                                    std::to_string(size_t(vertex_count) * kl) + " floats (" +
                                    std::to_string(vertex_count) + " vertices x " + std::to_string(k) +
                                    " x " + std::to_string(l) + "), got " + std::to_string(row_major.size()));
    blocks_ = (vertex_count + kBlockVertices - 1) / kBlockVertices;
    data_.assign(size_t(blocks_) * block_floats(), 0.0f);

    std::atomic<size_t> bad{SIZE_MAX};
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, blocks_),
                      [&](const tbb::blocked_range<uint32_t>& r)
                      {
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
                                          // Report the first bad value whatever the thread schedule: keep the
                                          // minimum index.
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
        throw std::invalid_argument("hemi: transfer matrices: non-finite value at vertex " +
                                    std::to_string(i / kl) + ", element " + std::to_string(i % kl));
}

float TransferMatrices::at(uint32_t v, uint32_t k, uint32_t j) const
{
    size_t f = size_t(k) * l_ + j;
    return data_[size_t(v / kBlockVertices) * block_floats() + f * kBlockVertices + v % kBlockVertices];
}

} // namespace hemi::render
