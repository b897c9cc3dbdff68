#pragma once
// The irradiance_normalmap sample's level, made in code (shared with the tests and hemi-bench): a room with
// window openings in two walls, four pillars, coloured walls, with normal-map UVs (TEXCOORD_0, one unit of
// world space per UV unit) and lightmap UVs (TEXCOORD_1: every quad its own chart, packed into the unit
// square at a uniform texel density with a gap between charts). glTF's y-up space, like a scene from a file.
// With normal maps (PNG, embedded like a Blender export's), the floor, ceiling and pillars are bevelled tiles
// of 0.5 units and the walls bricks of 0.5 x 0.25 with deep mortar joints: slopes of up to 50 degrees, which
// is where the directional lightmap bases differ. With SSBump maps (Green 2007) the same reliefs are baked
// into self-shadowed bump maps (hemi-bake ssbump's bake, normalised convention) held in the normal slot, for
// the ssbump technique.

#include <hemi/io/gltf.h>

#include <cstdint>

namespace hemi::samples
{

// `atlas` is the lightmap size the charts are packed for (their gaps are 2 texels of it).
enum class LevelMaps
{
    None,
    Normal, // tangent-space normal maps
    Ssbump, // SSBump maps with directional occlusion (300 rays a texel)
    // Normal maps, but the blue wall (material 3) holds the bricks' SSBump map and asks for the "ssbump"
    // technique (io::Material::technique): an SSBump wall inside a level drawn with a basis; and the floor
    // has its own material, kPolishedFloor, "polished floor" (samples/engine: a glossy floor).
    SsbumpWall,
};
inline constexpr uint32_t kPolishedFloor = 4;

io::GltfScene make_level(uint32_t atlas = 512, LevelMaps maps = LevelMaps::Normal);

// A level of many rooms, for bakes at a real level's scale (hemi-bench's lightmap/bake/large): rooms_x x
// rooms_z rooms of 8 x 8 x 3 units in rows along x, walls 0.3 thick, a corridor 3 wide between two rows;
// doors between neighbouring rooms and from every room to the corridors beside it (with reveals: the faces
// of the wall's thickness), windows in the outer walls and at the corridors' ends, four pillars a room; the
// materials and maps of make_level (the walls' colour alternating from room to room). Every quad is its own
// lightmap chart, packed into `atlas` at one texel density. Throws std::invalid_argument for no rooms, more
// than 64 a side or an atlas under 64.
io::GltfScene make_large_level(uint32_t rooms_x, uint32_t rooms_z, uint32_t atlas,
                               LevelMaps maps = LevelMaps::Normal);

} // namespace hemi::samples
