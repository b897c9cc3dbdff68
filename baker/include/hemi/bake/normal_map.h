#pragma once
// Tangent-space normal maps from height fields (the bump maps that Green 2007 and Sloan 2006 light).

#include <cstdint>
#include <span>
#include <vector>

namespace hemi::bake
{

// Converts a height field (row-major, `width` x `height`, row 0 at v = 0, wrapping at the edges) into an
// RGBA8 tangent-space normal map in glTF convention (+X toward +u, +Y toward -v, i.e. "up" in the image,
// encoded as n * 0.5 + 0.5). `scale` is the height difference, in texel widths, of one height unit:
// n = normalize(-scale * dh/dx, scale * dh/dy, 1) with central differences over texels (dh/dy along +v).
// Throws std::invalid_argument when the size does not match or a height is not finite.
std::vector<uint8_t> normal_map_from_height(std::span<const float> heights, uint32_t width, uint32_t height,
                                            float scale);

} // namespace hemi::bake
