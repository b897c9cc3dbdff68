#include <hemi/bake/normal_map.h>
#include <hemi/bake/ssbump.h>

#include <stdexcept>
#include <string>

namespace hemi::bake
{

std::vector<uint8_t> normal_map_from_height(std::span<const float> heights, uint32_t width, uint32_t height,
                                            float scale)
{
    if (width == 0 || height == 0 || heights.size() != size_t(width) * height)
        throw std::invalid_argument("hemi: normal_map_from_height: " + std::to_string(heights.size()) +
                                    " heights for a " + std::to_string(width) + "x" + std::to_string(height) +
                                    " map");
    // The SSBump bake's normals (central differences, wrapping), encoded as n * 0.5 + 0.5.
    const HeightField field{width, height, std::vector<float>(heights.begin(), heights.end())};
    return ssbump_rgba8(height_normals(field, scale, true), {}, true);
}

} // namespace hemi::bake
