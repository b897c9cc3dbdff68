#include "assets.h"

#include "level.h"
#include "models.h"

#include <hemi/bake/factored.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/io/gltf.h>
#include <hemi/math/sh_environment.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

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
    const glm::vec3 sun = kSunDirection;
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

// The level as a studio's pipeline bakes it: its glTF (what an artist exports) through hemi-bake's own job
// (bake::bake_lightmap_file: stitched seams, probes, the light table), outputs h6 and h4 for the floor, walls
// and pillars and rnm for the SSBump wall. The lights are the irradiance_normalmap sample's: a blue sky and a
// sun low in the west through the opening, the sun mixed (its bounces in the lightmap, its visibility in the
// shadowmask; the engine lights it with its shadow map) or baked (all of its light in the lightmap).
void bake_level(const fs::path& gltf, const fs::path& path, bool mixed_sun,
                const std::function<void(const std::string&)>& log)
{
    const auto t0 = std::chrono::steady_clock::now();
    const uint32_t atlas = 256;
    log("baking the level (" + std::to_string(atlas) +
        "^2 lightmap: h6, h4, rnm; light and reflection probes; the sun " + (mixed_sun ? "mixed" : "baked") +
        ") into " + path.string());
    if (!fs::exists(gltf))
        io::write_gltf(gltf, make_level(atlas, LevelMaps::SsbumpWall));
    bake::LightmapFileOptions o;
    o.width = o.height = atlas;
    o.outputs = {"h6", "h4", "rnm"};
    o.probes = glm::uvec3(6, 3, 6);
    o.probe_rays = 1024;
    // A reflection probe at the room's centre, half a unit up (the level's own frame: glTF's, y up), over the
    // whole level, for the glossy ball (box-projected from wherever it stands), glossy enough (Phong 400) to
    // show the room.
    o.reflection_probes = {{glm::vec3(0.0f, 0.5f, 0.0f)}};
    o.reflection.size = 128;
    o.reflection.exponents = {400.0};
    o.bake.rays = 128;
    o.bake.bounces = 1;
    o.lights.uniform = glm::vec3(0.35f, 0.45f, 0.65f);
    o.lights.sun = true;
    o.lights.sun_direction = kSunDirection;
    o.lights.sun_irradiance = glm::vec3(5.0f, 4.6f, 4.0f);
    o.lights.sun_mode = mixed_sun ? io::LightMode::Mixed : io::LightMode::Baked;
    bake::bake_lightmap_file(gltf, path, o);
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

// Whether `level` is this sample's: its sun baked as asked, its floor polished, its probes' depth maps there
// (what keeps the spheres' light from leaking through the walls) and its reflection probe.
bool current_level(const io::LightmapAsset& level, bool mixed_sun)
{
    const bool sun =
        std::any_of(level.lights.begin(), level.lights.end(),
                    [&](const io::LightmapLight& l)
                    {
                        return l.light.type == io::PunctualLight::Type::Directional &&
                               l.light.mode == (mixed_sun ? io::LightMode::Mixed : io::LightMode::Baked);
                    });
    const bool floor = std::any_of(level.materials.begin(), level.materials.end(),
                                   [](const io::Material& m) { return m.name == "polished floor"; });
    return sun && floor && !level.probes.depth.empty() && !level.reflections.empty();
}

} // namespace

EngineAssets prepare_engine_assets(const fs::path& dir, bool mixed_sun,
                                   const std::function<void(const std::string&)>& log)
{
    fs::create_directories(dir);
    EngineAssets a;
    a.level_path = dir / (mixed_sun ? "engine_level.hemi" : "engine_level_baked_sun.hemi");
    const fs::path torus = dir / "engine_torus.hemi", sky = dir / "engine_sky.hemi";
    if (!fs::exists(a.level_path))
        bake_level(dir / "engine_level.glb", a.level_path, mixed_sun, log);
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
    if (!current_level(a.level, mixed_sun))
    {
        // A folder from before the sample had its mixed sun and polished floor: bake the level again.
        log(a.level_path.string() + " is an older sample's level (no " + (mixed_sun ? "mixed" : "baked") +
            " sun, no polished floor, no probe depth maps or no reflection probe): baking it again");
        fs::remove(dir / "engine_level.glb");
        bake_level(dir / "engine_level.glb", a.level_path, mixed_sun, log);
        a.level = io::read_lightmap_asset(a.level_path);
    }
    a.torus = io::read_prt_asset(torus);
    a.sky = io::read_envmap_asset(sky);
    a.sky_sh = math::project_equirect(3, sky_equirect.width, sky_equirect.height, sky_equirect.pixels);
    return a;
}

} // namespace hemi::samples
