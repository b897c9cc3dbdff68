#pragma once
// The engine sample's content, baked with hemi's baker the way a studio's asset pipeline would and kept in a
// folder (re-used when present): the sample level with an SSBump wall and a polished floor (lightmap outputs
// h6, h4 and rnm, light probes, the sun mixed with a shadowmask or baked), a torus for PRT (technique h4),
// and a sky with its parabolic maps for Heidrich & Seidel's glossy object. Each file is what hemi-bake
// writes, so hemi-render draws the same level from the same file.
#include <hemi/io/envmap_asset.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace hemi::samples
{

struct EngineAssets
{
    std::filesystem::path level_path; // DIR/engine_level.hemi
    io::LightmapAsset level;
    io::PrtAsset torus;
    io::EnvmapAsset sky;
    std::vector<glm::vec3>
        sky_sh; // the same sky as world-space SH (order 3), what the torus's PRT multiplies
};

// Towards the sun (hemi's world, z up): low in the west, where the sky image has its sun and the level's
// bake puts it.
inline const glm::vec3 kSunDirection = glm::normalize(glm::vec3(-0.75f, -0.3f, 0.55f));

// Loads the assets from `dir`, baking (and writing) each one that is missing; `log` hears what is baked. The
// level: DIR/engine_level.hemi with the sun mixed, DIR/engine_level_baked_sun.hemi with it baked (both baked
// from DIR/engine_level.glb, written first). Throws what the bakes and readers throw (io::FormatError names a
// corrupt file).
EngineAssets prepare_engine_assets(const std::filesystem::path& dir, bool mixed_sun,
                                   const std::function<void(const std::string&)>& log);

} // namespace hemi::samples
