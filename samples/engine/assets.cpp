#include "assets.h"

#include "level.h"
#include "models.h"

#include <hemi/bake/factored.h>
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/math/camera.h>
#include <hemi/math/sh_environment.h>

#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace hemi::samples
{
namespace
{
namespace fs = std::filesystem;

double since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string seconds(double s)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.1f s", s);
    return text;
}

// A clear sky, z up in hemi's world: blue overhead, pale at the horizon, a warm sun low in the west (where
// the level's bake puts its sun) and a dim brown ground. Equirectangular in Blender's mapping
// (math/sh_environment.h), 2:1.
io::ImageRgba sky_image(uint32_t width)
{
    io::ImageRgba img;
    img.width = width;
    img.height = width / 2;
    img.pixels.resize(size_t(img.width) * img.height * 4);
    const glm::vec3 sun = glm::normalize(glm::vec3(-0.75f, -0.3f, 0.55f));
    for (uint32_t y = 0; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width; ++x)
        {
            const float phi = float(M_PI) - 2.0f * float(M_PI) * (float(x) + 0.5f) / float(img.width);
            const float theta = float(M_PI) * (float(y) + 0.5f) / float(img.height);
            const glm::vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
            glm::vec3 c;
            if (d.z >= 0.0f)
            {
                const float t = std::pow(1.0f - d.z, 3.0f);
                c = glm::mix(glm::vec3(0.25f, 0.45f, 0.9f), glm::vec3(0.85f, 0.9f, 1.0f), t);
            }
            else
                c = glm::vec3(0.22f, 0.18f, 0.14f) * (1.0f + 0.5f * d.z);
            const float s = glm::dot(d, sun);
            c += glm::vec3(40.0f, 34.0f, 26.0f) * std::pow(std::max(s, 0.0f), 400.0f);
            float* p = &img.pixels[(size_t(y) * img.width + x) * 4];
            p[0] = c.r;
            p[1] = c.g;
            p[2] = c.b;
            p[3] = 1.0f;
        }
    return img;
}

void bake_level(const fs::path& path, const std::function<void(const std::string&)>& log)
{
    const auto t0 = std::chrono::steady_clock::now();
    const uint32_t atlas = 256;
    log("baking the level (" + std::to_string(atlas) + "^2 lightmap: h6, h4, rnm; light probes) into " +
        path.string());
    const io::GltfScene level = make_level(atlas, LevelMaps::SsbumpWall);
    const bake::LightmapSurfaces surfaces(level.mesh, level.materials, level.images, level.primitives);
    bake::LightmapUvReport report;
    const bake::LightmapAtlas lightmap_atlas = bake::rasterize_lightmap(level.mesh, atlas, atlas, report);
    if (!report.ok())
        throw std::runtime_error("the level's lightmap UVs: " + report.problems.front());
    // The irradiance_normalmap sample's lights: a blue sky, and a sun low in the west through the opening.
    bake::LightmapLights lights;
    lights.uniform = glm::vec3(0.35f, 0.45f, 0.65f);
    lights.sun = true;
    lights.sun_direction = glm::normalize(glm::vec3(-0.75f, -0.3f, 0.55f));
    lights.sun_irradiance = glm::vec3(5.0f, 4.6f, 4.0f);
    lights.scene_to_world = glm::mat3(math::gltf_to_world());
    bake::LightmapBakeOptions options;
    options.rays = 128;
    options.bounces = 1;
    const bake::LightmapSh sh =
        bake::bake_lightmap_sh(level.mesh, lightmap_atlas, lights, options, &surfaces);
    io::LightmapAsset asset;
    asset.mesh = level.mesh;
    asset.materials = level.materials;
    asset.images = level.images;
    asset.primitives = level.primitives;
    asset.width = asset.height = atlas;
    asset.rays = uint32_t(options.rays);
    asset.bounces = uint32_t(options.bounces);
    asset.seed = options.seed;
    asset.covered_texels = uint32_t(lightmap_atlas.texels.size());
    for (const char* output : {"h6", "h4", "rnm"})
        asset.outputs.push_back({output, uint32_t(bake::lightmap_output_size(output)),
                                 bake::lightmap_maps(output, lightmap_atlas, sh)});
    asset.probes = bake::probe_grid(level.mesh, glm::uvec3(6, 3, 6));
    bake::LightmapBakeOptions probe_options = options;
    probe_options.rays = 1024;
    bake::bake_light_probes(asset.probes, level.mesh, lightmap_atlas, sh, lights, probe_options, &surfaces);
    io::write_lightmap_asset(path, asset);
    log("  level baked in " + seconds(since(t0)));
}

void bake_torus(const fs::path& dir, const fs::path& path, const std::function<void(const std::string&)>& log)
{
    const auto t0 = std::chrono::steady_clock::now();
    log("baking the torus's PRT (h4, interreflected) into " + path.string());
    const fs::path gltf = write_prt_model(dir, "engine_torus", PrtModel::Simple);
    bake::PrtAssetOptions options;
    options.techniques = {"h4"};
    options.bake.order = 3;
    options.bake.rays = 256;
    options.bake.bounces = 1;
    bake::bake_prt_file(gltf, path, options);
    log("  torus baked in " + seconds(since(t0)));
}

} // namespace

EngineAssets prepare_engine_assets(const fs::path& dir, const std::function<void(const std::string&)>& log)
{
    fs::create_directories(dir);
    EngineAssets a;
    a.level_path = dir / "engine_level.hemi";
    const fs::path torus = dir / "engine_torus.hemi", sky = dir / "engine_sky.hemi";
    if (!fs::exists(a.level_path))
        bake_level(a.level_path, log);
    if (!fs::exists(torus))
        bake_torus(dir, torus, log);
    const io::ImageRgba sky_equirect = sky_image(256);
    if (!fs::exists(sky))
    {
        const auto t0 = std::chrono::steady_clock::now();
        log("baking the sky's parabolic maps into " + sky.string());
        bake::EnvmapBakeOptions options;
        options.size = 64;
        options.exponents = {60.0};
        io::write_envmap_asset(sky, bake::bake_envmap(sky_equirect, options));
        log("  sky baked in " + seconds(since(t0)));
    }
    a.level = io::read_lightmap_asset(a.level_path);
    a.torus = io::read_prt_asset(torus);
    a.sky = io::read_envmap_asset(sky);
    a.sky_sh = math::project_equirect(3, sky_equirect.width, sky_equirect.height, sky_equirect.pixels);
    return a;
}

} // namespace hemi::samples
