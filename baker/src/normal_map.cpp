#include <hemi/bake/normal_map.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

std::vector<uint8_t> normal_map_from_height(std::span<const float> heights, uint32_t width, uint32_t height,
                                            float scale)
{
    if (width == 0 || height == 0 || heights.size() != size_t(width) * height)
        throw std::invalid_argument("hemi: normal_map_from_height: " + std::to_string(heights.size()) +
                                    " heights for a " + std::to_string(width) + "x" + std::to_string(height) + " map");
    for (float h : heights)
        if (!std::isfinite(h))
            throw std::invalid_argument("hemi: normal_map_from_height: height is not finite");
    auto h = [&](uint32_t x, uint32_t y) { return heights[size_t(y % height) * width + x % width]; };
    std::vector<uint8_t> out(size_t(width) * height * 4);
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x)
        {
            float dx = 0.5f * (h(x + 1, y) - h(x + width - 1, y));
            float dy = 0.5f * (h(x, y + 1) - h(x, y + height - 1));
            float nx = -scale * dx, ny = scale * dy, nz = 1.0f;
            float inv = 1.0f / std::sqrt(nx * nx + ny * ny + nz * nz);
            uint8_t* o = &out[(size_t(y) * width + x) * 4];
            o[0] = uint8_t(std::lround((nx * inv * 0.5f + 0.5f) * 255.0f));
            o[1] = uint8_t(std::lround((ny * inv * 0.5f + 0.5f) * 255.0f));
            o[2] = uint8_t(std::lround((nz * inv * 0.5f + 0.5f) * 255.0f));
            o[3] = 255;
        }
    return out;
}

} // namespace hemi::bake
