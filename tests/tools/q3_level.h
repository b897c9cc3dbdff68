#pragma once
// A real game level for the tests: a Quake III Arena map (IBSP version 46, as OpenArena ships them in its
// .pk3 zip archives) turned into the glTF scene hemi-bake lightmap reads, with the level's own lightmap UVs
// as TEXCOORD_1. Test-only code: it reads Debian's openarena-081-maps package, which cmake/install_deps.sh
// installs.
//
// What the converter keeps: polygon (type 1) and mesh (type 3) faces as their triangles, and Bezier patches
// (type 2) tessellated; billboards (type 4) and every face without a lightmap (lm_index < 0: the sky,
// decals, vertex-lit effects) are left out, so that the sky is an opening the environment's light enters
// through. Quake's z-up world in inches becomes glTF's y-up one: (x, y, z) -> (x, z, -y) / 64.
#include <hemi/io/gltf.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hemi::test
{

// Where Debian's openarena-081-maps package (a dependency of openarena-data) puts OpenArena 0.8.1's maps.
inline const std::filesystem::path kOpenArenaMaps = "/usr/share/games/openarena/baseoa/pak1-maps.pk3";
// Where Debian's openarena-oacmp1 package puts the OpenArena Community Map Pack's first volume (its
// maps/oacmpdm1.bsp is a sealed indoor level: no sky, pillars and walls that touch, faces left inside them).
inline const std::filesystem::path kOpenArenaCommunityMaps =
    "/usr/share/games/openarena/baseoa/z_oacmp-volume1-v3.pk3";

// The bytes of the entry `name` (e.g. "maps/oa_dm3.bsp") of the zip archive `zip`: stored or deflated,
// checked against the CRC-32 of the central directory. Throws std::runtime_error naming the archive (and the
// entry) when the file is missing or unreadable, the archive is malformed, the entry is absent, or it uses
// another compression method, ZIP64 or encryption.
std::vector<uint8_t> read_zip_entry(const std::filesystem::path& zip, const std::string& name);

struct Q3Level
{
    io::GltfScene scene;         // one grey material (albedo 0.5), one primitive; no tangents
    std::vector<uint32_t> faces; // the BSP face each triangle comes from
    uint32_t lightmap_pages = 0; // 128 x 128 lightmaps of the BSP, laid out on a grid in TEXCOORD_1
    uint32_t atlas_columns = 0, atlas_rows = 0;
    size_t polygon_faces = 0, mesh_faces = 0, patch_faces = 0; // the faces kept, by type
    size_t patches = 0;                                        // 3 x 3 Bezier patches tessellated
    size_t faces_without_lightmap = 0, billboards = 0;         // faces left out
};

// Converts the BSP file `bsp` (its bytes; `name` for messages). Each 3 x 3 patch becomes
// `patch_level` x `patch_level` quads. Throws std::runtime_error naming `name` for anything that is not a
// well-formed IBSP 46 file: a bad header, a lump outside the file, a face whose vertices, mesh vertices,
// lightmap or patch grid are out of range, non-finite values, or no face with a lightmap.
Q3Level convert_q3_level(const std::vector<uint8_t>& bsp, const std::string& name, int patch_level = 4);

// read_zip_entry, then convert_q3_level; messages name "PK3:ENTRY".
Q3Level read_q3_level(const std::filesystem::path& pk3, const std::string& entry, int patch_level = 4);

} // namespace hemi::test
