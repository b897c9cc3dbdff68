// Block-sparse per-texel maps (block_maps.h).
#include <hemi/io/block_maps.h>

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>

namespace hemi::io
{

BlockGrid::BlockGrid(uint32_t width, uint32_t height, std::vector<uint32_t> blocks)
    : width_(width), height_(height), blocks_(std::move(blocks))
{
    if (width == 0 || height == 0 || width > (1u << 18) || height > (1u << 18))
        throw std::invalid_argument("a block grid of " + std::to_string(width) + "x" +
                                    std::to_string(height) + " texels is not in [1, 2^18] per side");
    const size_t grid = size_t(blocks_x()) * blocks_y();
    row_begin_.assign(size_t(blocks_y()) + 1, 0);
    for (size_t i = 0; i < blocks_.size(); ++i)
    {
        if (blocks_[i] >= grid || (i > 0 && blocks_[i] <= blocks_[i - 1]))
            throw std::invalid_argument("block " + std::to_string(blocks_[i]) + " (kept block " +
                                        std::to_string(i) + ") is out of the " + std::to_string(grid) +
                                        "-block grid or not in ascending order");
        ++row_begin_[blocks_[i] / blocks_x() + 1];
    }
    for (size_t r = 1; r < row_begin_.size(); ++r)
        row_begin_[r] += row_begin_[r - 1];
    if (grid > kMaxRankedBlocks)
        return; // slot() searches
    kept_.assign((grid + 63) / 64, 0);
    for (const uint32_t b : blocks_)
        kept_[b / 64] |= uint64_t(1) << (b % 64);
    rank_.assign(kept_.size(), 0);
    for (size_t w = 1; w < kept_.size(); ++w)
        rank_[w] = rank_[w - 1] + uint32_t(std::popcount(kept_[w - 1]));
}

BlockMaps::BlockMaps(BlockGrid g, uint32_t maps)
    : grid(std::move(g)), k(maps), values(grid.slots() * maps * 3, 0.0f)
{
}

BlockMaps BlockMaps::from_dense(uint32_t width, uint32_t height, uint32_t k, std::span<const float> dense)
{
    const size_t plane = size_t(width) * height;
    if (dense.size() != plane * k * 3)
        throw std::invalid_argument("a dense map of " + std::to_string(dense.size()) + " values for " +
                                    std::to_string(k) + " maps of " + std::to_string(width) + "x" +
                                    std::to_string(height) + " RGB texels");
    const BlockGrid all(width, height, {});
    const uint32_t bx = all.blocks_x(), by = all.blocks_y();
    std::vector<uint32_t> kept;
    for (uint32_t b = 0; b < bx * by; ++b)
    {
        bool any = false;
        const uint32_t x0 = (b % bx) * BlockGrid::kSize, y0 = (b / bx) * BlockGrid::kSize;
        for (uint32_t m = 0; m < k && !any; ++m)
            for (uint32_t y = y0; y < std::min(y0 + BlockGrid::kSize, height) && !any; ++y)
                for (uint32_t x = x0; x < std::min(x0 + BlockGrid::kSize, width) && !any; ++x)
                    for (uint32_t c = 0; c < 3; ++c)
                        any = any || dense[((m * plane) + size_t(y) * width + x) * 3 + c] != 0.0f;
        if (any)
            kept.push_back(b);
    }
    BlockMaps out(BlockGrid(width, height, std::move(kept)), k);
    for (size_t s = 0; s < out.grid.slots(); ++s)
    {
        const glm::uvec2 t = out.grid.texel(s);
        if (t.x >= width || t.y >= height)
            continue;
        for (uint32_t m = 0; m < k; ++m)
            for (uint32_t c = 0; c < 3; ++c)
                out.values[out.index(m, s) + c] = dense[((m * plane) + size_t(t.y) * width + t.x) * 3 + c];
    }
    return out;
}

std::vector<float> BlockMaps::dense() const
{
    const uint32_t w = grid.width(), h = grid.height();
    const size_t plane = size_t(w) * h;
    std::vector<float> out(plane * k * 3, 0.0f);
    for (size_t s = 0; s < grid.slots(); ++s)
    {
        const glm::uvec2 t = grid.texel(s);
        if (t.x >= w || t.y >= h)
            continue;
        for (uint32_t m = 0; m < k; ++m)
            for (uint32_t c = 0; c < 3; ++c)
                out[((m * plane) + size_t(t.y) * w + t.x) * 3 + c] = values[index(m, s) + c];
    }
    return out;
}

} // namespace hemi::io
