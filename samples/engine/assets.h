#pragma once
// The engine sample's content, baked with hemi's baker the way a studio's asset pipeline would and kept in a
// folder (re-used when present): the sample level with an SSBump wall (lightmap outputs h6, h4 and rnm, light
// probes), a torus for PRT (technique h4), and a sky with its parabolic maps for Heidrich & Seidel's glossy
// object. Each file is what hemi-bake writes, so hemi-render draws the same level from the same file.
#include <hemi/io/envmap_asset.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>

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

// Loads the assets from `dir`, baking (and writing) each one that is missing; `log` hears what is baked.
// Throws what the bakes and readers throw (io::FormatError names a corrupt file).
EngineAssets prepare_engine_assets(const std::filesystem::path& dir,
                                   const std::function<void(const std::string&)>& log);

} // namespace hemi::samples
