#pragma once
// Per-texel data over a W x H atlas, stored only where there is some: the atlas is cut into 8 x 8 blocks and
// only the blocks that hold a texel are kept. A lightmap bake and its asset use it, so that their memory and
// size follow the texels a scene covers, not the atlas it is laid out in (a one-texel chart in a 4096^2 atlas
// costs a few blocks, not 16 M texels).
//
// Block b of the grid covers texels [bx * 8, bx * 8 + 8) x [by * 8, by * 8 + 8), b = by * blocks_x + bx; the
// blocks of the last column and row may reach past the atlas (their outside texels exist and stay unused).
// A kept block's slot is its rank among the kept blocks, and a texel's slot is block slot * 64 + (y % 8) * 8
// + x % 8: row-major inside the block, blocks in ascending order.

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace hemi::io
{

// The largest side of a lightmap atlas hemi bakes, stores and draws: beyond the device's largest image
// (16384 on most), since the runtime stores only the pages that hold texels (render::TexelCoefficients).
inline constexpr uint32_t kMaxAtlasSide = 65536;

class BlockGrid
{
  public:
    static constexpr uint32_t kSize = 8;    // texels along a block's side
    static constexpr uint32_t kTexels = 64; // texels of a block

    BlockGrid() = default;
    // `blocks`: the kept blocks' indices, strictly ascending. Throws std::invalid_argument for a side of 0 or
    // over 2^18 (so that every block index fits 32 bits), or for blocks out of the grid or out of order.
    BlockGrid(uint32_t width, uint32_t height, std::vector<uint32_t> blocks);

    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }
    uint32_t blocks_x() const { return (width_ + kSize - 1) / kSize; }
    uint32_t blocks_y() const { return (height_ + kSize - 1) / kSize; }
    const std::vector<uint32_t>& blocks() const { return blocks_; }
    size_t slots() const { return blocks_.size() * kTexels; } // texels of the kept blocks
    bool empty() const { return blocks_.empty(); }

    // The slot of texel (x, y), or -1 when the texel is outside the atlas or its block is not kept: the
    // block's rank in a bitmap of the kept blocks (a word and a population count), or for a grid of more than
    // kMaxRankedBlocks blocks a binary search among the kept blocks of the texel's block row.
    int64_t slot(int64_t x, int64_t y) const
    {
        if (x < 0 || y < 0 || x >= int64_t(width_) || y >= int64_t(height_))
            return -1;
        const uint32_t row = uint32_t(y / kSize), block = row * blocks_x() + uint32_t(x / kSize);
        const int64_t first = block_slot(block);
        return first < 0 ? -1 : first + (y % kSize) * kSize + x % kSize;
    }
    // The first slot of block `block` (< blocks_x() * blocks_y()), or -1 when it is not kept.
    int64_t block_slot(uint32_t block) const
    {
        if (!kept_.empty())
        {
            const uint64_t word = kept_[block / 64], bit = uint64_t(1) << (block % 64);
            if (!(word & bit))
                return -1;
            return int64_t(rank_[block / 64] + ones(word & (bit - 1))) * kTexels;
        }
        const uint32_t row = block / blocks_x();
        const auto first = blocks_.begin() + row_begin_[row], last = blocks_.begin() + row_begin_[row + 1];
        const auto it = std::lower_bound(first, last, block);
        if (it == last || *it != block)
            return -1;
        return int64_t(it - blocks_.begin()) * kTexels;
    }
    // The texel of a slot (it may lie past the atlas in a block of the last column or row).
    glm::uvec2 texel(size_t slot) const
    {
        const uint32_t b = blocks_[slot / kTexels], local = uint32_t(slot % kTexels);
        return {(b % blocks_x()) * kSize + local % kSize, (b / blocks_x()) * kSize + local / kSize};
    }

  private:
    // The bits set in w: std::popcount without the POPCNT instruction (a build for any x86-64) is a call into
    // libgcc, which cost a bake 2% of its time; this is a handful of inline operations.
    static uint32_t ones(uint64_t w)
    {
        w = w - ((w >> 1) & 0x5555555555555555ull);
        w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
        w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
        return uint32_t((w * 0x0101010101010101ull) >> 56);
    }

    uint32_t width_ = 0, height_ = 0;
    std::vector<uint32_t> blocks_;
    std::vector<uint32_t> row_begin_; // per block row, and one past the last: its first kept block's slot
    // Per 64 blocks of the grid, a bit per kept block and the kept blocks before them: 12 bytes per 64 blocks
    // (1.2 MiB for a 20000^2 atlas), kept for grids of up to kMaxRankedBlocks blocks (48 MiB).
    static constexpr size_t kMaxRankedBlocks = size_t(1) << 28;
    std::vector<uint64_t> kept_;
    std::vector<uint32_t> rank_;
};

// What a bilinear lookup at `uv` ([0, 1]^2 over a width x height atlas, v down) reads, as the runtime's
// sampler reads it: texels (x0 or x1, y0 or y1), clamped to the atlas's edge, weighted by (1 - tx or tx)
// times (1 - ty or ty). BlockMaps::bilinear and the seam stitch (bake/lightmap_seams.h) both use it.
struct BilinearFootprint
{
    int64_t x0, x1, y0, y1;
    float tx, ty;
};
inline BilinearFootprint bilinear_footprint(glm::vec2 uv, uint32_t width, uint32_t height)
{
    const double fx = std::clamp(double(uv.x), 0.0, 1.0) * width - 0.5;
    const double fy = std::clamp(double(uv.y), 0.0, 1.0) * height - 0.5;
    // fx, fy >= -0.5: floor(f) as the truncation of f + 1 (exact in double), less 1, which is
    // std::floor's value without its call (the bake makes a lookup for every bounce ray).
    const double x0 = double(int64_t(fx + 1.0)) - 1.0, y0 = double(int64_t(fy + 1.0)) - 1.0;
    const int64_t ix = int64_t(x0), iy = int64_t(y0), w = int64_t(width) - 1, h = int64_t(height) - 1;
    return {std::clamp<int64_t>(ix, 0, w),
            std::clamp<int64_t>(ix + 1, 0, w),
            std::clamp<int64_t>(iy, 0, h),
            std::clamp<int64_t>(iy + 1, 0, h),
            float(fx - x0),
            float(fy - y0)};
}

// The slots of a bilinear lookup's four texels at `uv` (bilinear_footprint's, in its order: (x0, y0),
// (x1, y0), (x0, y1), (x1, y1)), -1 where no block is kept, and its weights. The texels lie in one, two or
// four blocks: each block is found once. Every per-texel map over a grid (BlockMaps, the bake's packed
// irradiance) reads through it.
struct BilinearSlots
{
    int64_t slot[4];
    float tx, ty;
};
// `block_slot(block)` finds a block's first slot, or -1 (BlockGrid::block_slot's answer; a caller with a
// faster table of its own passes that).
template <class BlockSlot>
BilinearSlots bilinear_slots(const BlockGrid& grid, glm::vec2 uv, BlockSlot&& block_slot)
{
    const BilinearFootprint f = bilinear_footprint(uv, grid.width(), grid.height());
    BilinearSlots t{{-1, -1, -1, -1}, f.tx, f.ty};
    // Inside the atlas (the footprint is clamped to it): unsigned, so that / and % are shifts and masks.
    const uint32_t B = BlockGrid::kSize, xs[2] = {uint32_t(f.x0), uint32_t(f.x1)},
                   ys[2] = {uint32_t(f.y0), uint32_t(f.y1)};
    int64_t first[2][2]; // each tap's block's first slot
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
        {
            if (i == 1 && xs[1] / B == xs[0] / B)
                first[j][1] = first[j][0];
            else if (j == 1 && ys[1] / B == ys[0] / B)
                first[1][i] = first[0][i];
            else
                first[j][i] = block_slot((ys[j] / B) * grid.blocks_x() + xs[i] / B);
            if (first[j][i] >= 0)
                t.slot[j * 2 + i] = first[j][i] + int64_t((ys[j] % B) * B + xs[i] % B);
        }
    return t;
}
inline BilinearSlots bilinear_slots(const BlockGrid& grid, glm::vec2 uv)
{
    return bilinear_slots(grid, uv, [&](uint32_t block) { return grid.block_slot(block); });
}

// A bilinear lookup's four texels (bilinear_slots' order) blended by its weights.
inline glm::vec3 bilinear_blend(const glm::vec3& v00, const glm::vec3& v10, const glm::vec3& v01,
                                const glm::vec3& v11, float tx, float ty)
{
    return (v00 * (1.0f - tx) + v10 * tx) * (1.0f - ty) + (v01 * (1.0f - tx) + v11 * tx) * ty;
}

// K RGB maps over a BlockGrid: coefficient k of the texel at slot s, channel c, at
// ((s / 64 * K + k) * 64 + s % 64) * 3 + c (block after block; in a block, map after map). Texels of blocks
// that are not kept read as 0.
struct BlockMaps
{
    BlockGrid grid;
    uint32_t k = 0;
    std::vector<float> values;

    BlockMaps() = default;
    BlockMaps(BlockGrid grid, uint32_t k); // every value 0

    // The blocks of a dense K x H x W x 3 array (map after map, rows from the top) that hold a value other
    // than 0. Throws std::invalid_argument when the array's size is not K * W * H * 3.
    static BlockMaps from_dense(uint32_t width, uint32_t height, uint32_t k, std::span<const float> dense);
    // The dense K x H x W x 3 array (what a GPU image of the whole atlas holds).
    std::vector<float> dense() const;

    uint32_t width() const { return grid.width(); }
    uint32_t height() const { return grid.height(); }
    size_t index(uint32_t map, size_t slot) const
    {
        return ((slot / BlockGrid::kTexels * k + map) * BlockGrid::kTexels + slot % BlockGrid::kTexels) * 3;
    }
    // Coefficient `map` of texel (x, y); 0 where no block is kept (and outside the atlas).
    glm::vec3 at(uint32_t map, int64_t x, int64_t y) const
    {
        const int64_t s = grid.slot(x, y);
        if (s < 0)
            return glm::vec3(0.0f);
        const float* v = &values[index(map, size_t(s))];
        return {v[0], v[1], v[2]};
    }
    // Coefficient `map` at `uv` ([0, 1]^2 over the atlas, v down) as the runtime's sampler reads it: bilinear
    // between texel centres, clamped to the atlas's edge.
    glm::vec3 bilinear(uint32_t map, glm::vec2 uv) const { return read(taps(map, uv)); }

    // bilinear() in two steps, for a caller with many lookups to make (the bounce rays of a texel): taps()
    // finds the four texels, which the caller may prefetch for every lookup before read() reads any, so that
    // the lookups' cache misses overlap instead of following one another.
    struct Taps
    {
        const float* texel[4]; // (x0, y0), (x1, y0), (x0, y1), (x1, y1); nullptr where no block is kept
        float tx, ty;
    };
    Taps taps(uint32_t map, glm::vec2 uv) const
    {
        const BilinearSlots b = bilinear_slots(grid, uv);
        Taps t{{nullptr, nullptr, nullptr, nullptr}, b.tx, b.ty};
        for (int i = 0; i < 4; ++i)
            if (b.slot[i] >= 0)
                t.texel[i] = &values[index(map, size_t(b.slot[i]))];
        return t;
    }
    static glm::vec3 read(const Taps& t)
    {
        auto at = [&](int i)
        { return t.texel[i] ? glm::vec3(t.texel[i][0], t.texel[i][1], t.texel[i][2]) : glm::vec3(0.0f); };
        return bilinear_blend(at(0), at(1), at(2), at(3), t.tx, t.ty);
    }
};

} // namespace hemi::io
