// hemi-denoise-quality: how close hemi-bake lightmap --denoise comes to a converged bake (issue 25's bar:
// 32 rays denoised against 128 rays undenoised, both against 4096 rays).
// docs/lightmaps.md#denoising---denoise quotes its table. For each scene and seed s it bakes 4096 rays (seed
// 3), 128 rays (seed s + 1) and 32 rays (seed s, with the halves the denoiser needs), denoises the 32-ray
// bake and prints the RMSE of plain and of SH9's nine coefficients over every texel and colour channel, and
// the mean of plain against the 4096-ray bake's. The scenes:
//   - the sample level (samples::make_level) unwrapped at 0.1 units per texel, with one bounce and without;
//   - the same level in a 96 x 96 atlas (a texel per 30 cm), one bounce;
//   - a floor with a wall standing on it under a sky of 1 and a sun of 10 at 45 degrees (the scene of
//     LightmapDenoise.ThirtyTwoRaysDenoisedComeCloserWithTheShadowEdgeKept).
// The level is lit by Blender's courtyard HDRI (Debian's blender-data) and a sun of (8, 7.5, 7) from
// (0.3, -0.5, 0.4), world z up, through its window.
//
//   hemi-denoise-quality [SEEDS [SCENE]]   SEEDS: 1 to 100 (default 3: seeds 1, 11, 21, ...); SCENE: only
//                                          the scenes whose name contains it ("wall", "96x96", "no bounce")
//
// Under each scene it also prints how the noise the bake estimates for the denoiser (LightmapSh::noise, of
// plain's luminance) compares with the 32-ray bake's actual error, as root mean squares over the texels.
//
// About 4 minutes on 2 cores at 3 seeds. Not a benchmark of speed: it times nothing but the sample level's
// 32-ray bake and filter against its 128-ray bake, which the documentation quotes beside the table.
#include "../samples/irradiance_normalmap/level.h"
#include "../tests/bake/quads.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/lightmap_denoise.h>
#include <hemi/bake/lightmap_unwrap.h>
#include <hemi/io/image.h>
#include <hemi/math/camera.h>
#include <hemi/math/luminance.h>

#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <string>

namespace
{
using namespace hemi;
using namespace hemi::bake;

struct Scene
{
    std::string name;
    io::Mesh mesh;
    LightmapAtlas atlas;
    LightmapLights lights;
    std::optional<LightmapSurfaces> surfaces;
    int bounces = 0;
};

double seconds_since(std::chrono::steady_clock::time_point start)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

const char* g_only = nullptr; // SCENE

bool selected(const std::string& name)
{
    return !g_only || name.find(g_only) != std::string::npos;
}

void measure(const Scene& s, int seeds)
{
    if (!selected(s.name))
        return;
    const auto bake = [&](int rays, uint64_t seed)
    {
        LightmapBakeOptions o;
        o.rays = rays;
        o.seed = seed;
        o.bounces = s.bounces;
        o.keep_noise = rays == 32;
        return bake_lightmap_sh(s.mesh, s.atlas, s.lights, o, s.surfaces ? &*s.surfaces : nullptr);
    };
    const LightmapSh reference = bake(4096, 3);
    const size_t n = s.atlas.texels.size();
    const auto rmse = [&](const LightmapSh& sh, bool plain)
    {
        double sum = 0.0;
        for (size_t i = 0; i < n; ++i)
            for (size_t k = 0; k < (plain ? 1u : 9u); ++k)
            {
                const glm::vec3 d = plain ? sh.direct[i][0] - reference.direct[i][0]
                                          : sh.irradiance[i][k] - reference.irradiance[i][k];
                sum += double(glm::dot(d, d));
            }
        return std::sqrt(sum / double(n * (plain ? 3 : 27)));
    };
    const auto mean = [&](const LightmapSh& sh)
    {
        double sum = 0.0, ref = 0.0;
        for (size_t i = 0; i < n; ++i)
        {
            sum += double(sh.direct[i][0].x + sh.direct[i][0].y + sh.direct[i][0].z);
            ref += double(reference.direct[i][0].x + reference.direct[i][0].y + reference.direct[i][0].z);
        }
        return 100.0 * (sum / ref - 1.0);
    };
    double ratio[2] = {}, estimated = 0.0, actual = 0.0;
    for (int k = 0; k < seeds; ++k)
    {
        const uint64_t seed = 1 + 10 * uint64_t(k);
        const LightmapSh more = bake(128, seed + 1), noisy = bake(32, seed);
        for (size_t i = 0; i < n; ++i)
        {
            // The estimated variance of plain's luminance, and its actual error.
            const double e = math::luminance(noisy.direct[i][0] - reference.direct[i][0]);
            estimated += double(noisy.noise[i][0]) / double(n * size_t(seeds));
            actual += e * e / double(n * size_t(seeds));
        }
        LightmapSh denoised = noisy;
        denoise_lightmap(s.mesh, s.atlas, denoised);
        for (const bool plain : {true, false})
        {
            ratio[plain ? 0 : 1] += rmse(denoised, plain) / rmse(more, plain) / seeds;
            std::printf(
                "| %s (%zu texels), seed %d | %s | %.4f (mean %+.2f%%) | %.4f (%+.2f%%) | %.4f (%+.2f%%) "
                "| %.2f |\n",
                s.name.c_str(), n, int(seed), plain ? "plain" : "sh9", rmse(noisy, plain), mean(noisy),
                rmse(denoised, plain), mean(denoised), rmse(more, plain), mean(more),
                rmse(denoised, plain) / rmse(more, plain));
        }
    }
    std::printf("| %s: mean over %d seeds of denoised / 128 rays | | | | | plain %.2f, sh9 %.2f |\n",
                s.name.c_str(), seeds, ratio[0], ratio[1]);
    std::printf("| %s: the bake's estimate of plain's noise at 32 rays %.4f, its actual error %.4f (%.1fx) "
                "| | | | | |\n",
                s.name.c_str(), std::sqrt(estimated), std::sqrt(actual), std::sqrt(estimated / actual));
    std::fflush(stdout);
}

Scene level_scene(const char* name, bool coarse, int bounces)
{
    io::GltfScene level = samples::make_level(128);
    UnwrapOptions u;
    if (coarse)
        u.width = u.height = 96;
    else
        u.texel_size = 0.1f;
    const UnwrapResult r = unwrap_lightmap(level.mesh, u);
    Scene s;
    s.name = name;
    LightmapUvReport report;
    s.atlas = rasterize_lightmap(level.mesh, r.width, r.height, report);
    const std::string hdri = "/usr/share/blender/datafiles/studiolights/world/courtyard.exr";
    s.lights.environment = io::read_exr(hdri);
    io::clamp_negative_radiance(s.lights.environment, hdri);
    s.lights.sun = true;
    s.lights.sun_direction = glm::normalize(glm::vec3(0.3f, -0.5f, 0.4f));
    s.lights.sun_irradiance = glm::vec3(8.0f, 7.5f, 7.0f);
    s.lights.scene_to_world = glm::mat3(math::gltf_to_world());
    s.lights.punctual = level.lights;
    s.surfaces.emplace(level.mesh, level.materials, level.images, level.primitives);
    s.mesh = std::move(level.mesh);
    s.bounces = bounces;
    return s;
}

Scene floor_and_wall()
{
    Scene s;
    s.name = "floor, wall and sun";
    test::add_floor_and_wall(s.mesh);
    LightmapUvReport report;
    s.atlas = rasterize_lightmap(s.mesh, 64, 64, report);
    s.lights.uniform = glm::vec3(1.0f);
    s.lights.sun = true;
    s.lights.sun_direction = glm::normalize(glm::vec3(-1.0f, 0.0f, 1.0f));
    s.lights.sun_irradiance = glm::vec3(10.0f);
    return s;
}

} // namespace

int main(int argc, char** argv)
{
    try
    {
        const int seeds = argc > 1 ? std::atoi(argv[1]) : 3;
        if (seeds < 1 || seeds > 100)
            throw std::invalid_argument("SEEDS must be 1 to 100");
        g_only = argc > 2 ? argv[2] : nullptr;
        std::printf("| scene | output | 32 rays | 32 rays, --denoise | 128 rays | denoised / 128 |\n"
                    "| --- | --- | ---: | ---: | ---: | ---: |\n");
        if (selected("sample level, 1 bounce"))
        {
            // The time a 32-ray bake and its filter take against a 128-ray bake, on the first scene.
            const Scene s = level_scene("sample level, 1 bounce", false, 1);
            LightmapBakeOptions o;
            o.bounces = 1;
            o.rays = 32;
            o.keep_noise = true;
            auto start = std::chrono::steady_clock::now();
            LightmapSh sh = bake_lightmap_sh(s.mesh, s.atlas, s.lights, o, &*s.surfaces);
            const double bake32 = seconds_since(start);
            start = std::chrono::steady_clock::now();
            denoise_lightmap(s.mesh, s.atlas, sh);
            const double filter = seconds_since(start);
            o.rays = 128;
            o.keep_noise = false;
            start = std::chrono::steady_clock::now();
            bake_lightmap_sh(s.mesh, s.atlas, s.lights, o, &*s.surfaces);
            std::fprintf(stderr, "sample level, 1 bounce: 32 rays %.2f s + filter %.2f s; 128 rays %.2f s\n",
                         bake32, filter, seconds_since(start));
            measure(s, seeds);
        }
        measure(level_scene("sample level, no bounce", false, 0), seeds);
        measure(level_scene("sample level at 96x96, 1 bounce", true, 1), seeds);
        measure(floor_and_wall(), seeds);
        return 0;
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "hemi-denoise-quality: %s\n", e.what());
        return 1;
    }
}
