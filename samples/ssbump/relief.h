#pragma once
// The ssbump sample's procedural height field, made in code (shared with the tests and hemi-bench): bricks
// in running bond with deep mortar joints and bevelled edges, rivets, and craters with raised rims, plus a
// little value noise. It tiles: the pattern repeats exactly across the borders.

#include <hemi/bake/ssbump.h>

#include <cstdint>

namespace hemi::samples
{

// Heights in [0, 1] (mortar 0, brick faces about 0.75, rivet tops and crater rims higher). `size` is the
// width and the height, a multiple of 64 (bricks are size/8 x size/16 texels).
bake::HeightField make_relief(uint32_t size);

} // namespace hemi::samples
