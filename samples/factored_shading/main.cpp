// factored_shading: Heidrich & Seidel 1999's figures re-made with hemi's materials, per pixel on lavapipe.
//   Fig. 2  a torus with the factored Torrance-Sparrow model at two roughness values (a directional light)
//   Fig. 3  a sphere and a disk with Banks' anisotropic model (tangents around z)
//   Fig. 6  the two parabolic images of the studio environment, and a torus reflecting it from two views
//   Fig. 7  Fresnel at n = 1.5 and n = 200, F L_m + L_d (top) and the coating's F L_m + (1 - F) L_d (bottom)
//   Fig. 8  the prefiltered glossy map (exponent 20), and a glossy torus
//   Fig. 10 the normal map with the environment alone and with local illumination added, from four views
// One comparison image (-o) and each figure on its own (--dir). The environment is baked with hemi-bake
// envmap's code (bake::bake_envmap), the tables with hemi-bake brdf's (math/brdf.h).
//   factored_shading [-o FIGURE.png] [--dir DIR] [--size N] [--environment STUDIO.exr]
#include "factored_scene.h"
#include "figure.h"

#include <hemi/bake/factored.h>
#include <hemi/bake/normal_map.h>
#include <hemi/gpu/device.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace
{
using hemi::render::Technique;

// One half of a parabolic map as a tile of size x size (nearest resampling), opaque.
hemi::io::ImageRgba half_tile(const hemi::math::ParabolicImage& map, int half, uint32_t size)
{
    const hemi::io::ImageRgba h = hemi::bake::parabolic_half_image(map, half);
    hemi::io::ImageRgba t;
    t.width = t.height = size;
    t.pixels.resize(size_t(size) * size * 4);
    for (uint32_t y = 0; y < size; ++y)
        for (uint32_t x = 0; x < size; ++x)
        {
            const float* p = h.at(x * h.width / size, y * h.height / size);
            float* q = t.pixels.data() + (size_t(y) * size + x) * 4;
            q[0] = p[0], q[1] = p[1], q[2] = p[2], q[3] = 1.0f;
        }
    return t;
}

// Brick normal map from the sh_normalmap sample's height field recipe (bevelled running bond).
hemi::io::ImageRgba8 bricks(uint32_t w, uint32_t h)
{
    std::vector<float> height(size_t(w) * h);
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const float rows = 8.0f, cols = 8.0f;
            const float v = (y + 0.5f) / h * rows;
            const int row = int(std::floor(v));
            const float u = (x + 0.5f) / w * cols + (row % 2 ? 0.5f : 0.0f);
            const float fu = u - std::floor(u), fv = v - std::floor(v);
            const float edge = std::min(std::min(fu, 1.0f - fu) * 2.0f, std::min(fv, 1.0f - fv));
            height[size_t(y) * w + x] = std::clamp(edge / 0.12f, 0.0f, 1.0f);
        }
    return {w, h, hemi::bake::normal_map_from_height(height, w, h, 3.0f)};
}
} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"factored_shading: Heidrich & Seidel 1999's figures with hemi's environment materials"};
    std::string out = "factored_shading.png", dir = "factored_shading";
    uint32_t size = 256;
    app.add_option("-o,--output", out, "the comparison image (PNG)")->capture_default_str();
    app.add_option("--dir", dir, "where each figure is written on its own")->capture_default_str();
    app.add_option("--size", size, "pixels per side of each tile")->capture_default_str();
    std::string environment_out;
    app.add_option("--environment", environment_out,
                   "also write the studio environment as an equirectangular EXR (hemi-bake envmap's input)");
    CLI11_PARSE(app, argc, argv);
    try
    {
        const auto t0 = std::chrono::steady_clock::now();
        std::filesystem::create_directories(dir);
        hemi::gpu::Device device(hemi::gpu::DeviceDesc{});
        const hemi::io::ImageRgba studio = hemi::samples::studio_environment(1024, 512);
        if (!environment_out.empty())
            hemi::io::write_exr(environment_out, studio);
        hemi::bake::EnvmapBakeOptions options;
        options.size = 256;
        options.exponents = {20.0};
        options.iors = {1.5, 200.0};
        const hemi::io::EnvmapAsset env = hemi::bake::bake_envmap(studio, options);
        std::printf("environment baked (%.1f s)\n",
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());

        const hemi::io::Mesh torus = hemi::samples::make_torus(1.0f, 0.42f, 160, 80);
        const hemi::io::Mesh sphere = hemi::io::make_uv_sphere(1.2f, 128, 64);
        const hemi::io::Mesh disk = hemi::samples::make_disk(1.5f, 160, 40);
        const hemi::io::ImageRgba8 brick_map = bricks(512, 256);
        const glm::vec3 sun = hemi::samples::studio_sun_direction();
        const hemi::render::DynamicLight light{false, sun, glm::vec3(3.0f)};
        const glm::mat4 tilt = glm::rotate(glm::mat4(1.0f), glm::radians(50.0f), glm::vec3(1, 0, 0));

        auto base = [&](const hemi::io::Mesh& mesh, Technique technique)
        {
            hemi::samples::FactoredView v;
            v.mesh = &mesh;
            v.environment = &env;
            v.technique = technique;
            v.model = tilt;
            v.eye = glm::vec3(0.0f, -4.2f, 1.6f);
            return v;
        };
        auto render = [&](const hemi::samples::FactoredView& v)
        { return hemi::samples::render_factored(device, v, size, size); };
        auto write = [&](const std::string& name, const std::vector<hemi::io::ImageRgba>& tiles,
                         const std::vector<std::string>& columns, const std::vector<std::string>& rows)
        {
            hemi::samples::write_labeled_grid((std::filesystem::path(dir) / name).string(), tiles, size, size,
                                              columns, rows, 0.8f);
        };

        // Fig. 2: Torrance-Sparrow at two roughness values.
        std::vector<hemi::io::ImageRgba> fig2;
        for (double m : {0.15, 0.4})
        {
            auto v = base(torus, Technique::Factored);
            v.brdf = hemi::math::torrance_sparrow_tables(
                hemi::math::TorranceSparrow(hemi::math::FacetDistribution::Beckmann, m, 1.5), 256);
            v.albedo = glm::vec3(0.55f, 0.12f, 0.08f);
            v.material.kd = 0.6f;
            v.material.ks = 1.0f;
            v.lights = {light};
            fig2.push_back(render(v));
        }
        write("fig2_torrance_sparrow.png", fig2, {"m = 0.15", "m = 0.4"}, {"Fig. 2"});

        // Fig. 3: Banks on a sphere and a disk.
        std::vector<hemi::io::ImageRgba> fig3;
        for (const hemi::io::Mesh* mesh : {&sphere, &disk})
        {
            auto v = base(*mesh, Technique::Banks);
            v.brdf = {hemi::math::banks_table(40.0, 256)};
            v.albedo = glm::vec3(0.35f, 0.3f, 0.25f);
            v.material.kd = 0.5f;
            v.material.ks = 0.8f;
            // A light from the viewer's side, so that the disk's brushed rings catch it.
            v.lights = {{false, glm::normalize(glm::vec3(-0.6f, -0.7f, 0.6f)), glm::vec3(3.0f)}};
            v.model =
                mesh == &disk ? glm::rotate(glm::mat4(1.0f), glm::radians(60.0f), glm::vec3(1, 0, 0)) : tilt;
            fig3.push_back(render(v));
        }
        write("fig3_banks.png", fig3, {"sphere", "disk"}, {"Fig. 3"});

        // Fig. 6: the two parabolic images and a mirror torus from two views.
        std::vector<hemi::io::ImageRgba> fig6;
        for (int half : {0, 1})
            fig6.push_back(half_tile(env.mirror[0], half, size));
        for (const glm::vec3 eye : {glm::vec3(0.0f, -4.2f, 1.6f), glm::vec3(3.2f, 2.0f, 2.6f)})
        {
            auto v = base(torus, Technique::EnvMirror);
            v.material.fresnel = 1; // n = 200: a metal, the mirror everywhere
            v.material.kd = 0.0f;
            v.eye = eye;
            fig6.push_back(render(v));
        }
        write("fig6_parabolic.png", fig6,
              {"front half (z >= 0)", "back half", "mirror torus", "another view"}, {"Fig. 6"});

        // Fig. 7: Fresnel, n = 1.5 and 200, both blends.
        std::vector<hemi::io::ImageRgba> fig7;
        for (bool coating : {false, true})
            for (uint32_t ior : {0u, 1u})
            {
                auto v = base(torus, Technique::EnvMirror);
                v.albedo = glm::vec3(0.7f, 0.45f, 0.2f);
                v.material.fresnel = ior;
                v.material.kd = 1.0f;
                v.material.coating = coating;
                fig7.push_back(render(v));
            }
        write("fig7_fresnel.png", fig7, {"n = 1.5", "n = 200"}, {"F Lm + Ld", "F Lm + (1-F) Ld"});

        // Fig. 8: the prefiltered map and a glossy torus.
        std::vector<hemi::io::ImageRgba> fig8;
        {
            fig8.push_back(half_tile(env.glossy[0], 0, size));
            auto v = base(torus, Technique::EnvGlossy);
            v.albedo = glm::vec3(0.2f);
            v.material.kd = 0.3f;
            v.material.ks = 0.9f;
            fig8.push_back(render(v));
        }
        write("fig8_glossy.png", fig8, {"glossy map, e = 20 (front)", "glossy torus"}, {"Fig. 8"});

        // Fig. 10: normal map; environment only (top), plus local illumination (bottom), from four views.
        std::vector<hemi::io::ImageRgba> fig10;
        for (bool local : {false, true})
            for (int k = 0; k < 4; ++k)
            {
                auto v = base(torus, Technique::EnvMirror);
                v.normal_map = brick_map;
                v.albedo = glm::vec3(0.6f, 0.35f, 0.25f);
                v.material.kd = 0.7f;
                const float a = glm::radians(-90.0f + 35.0f * k);
                v.eye = glm::vec3(4.2f * std::cos(a), 4.2f * std::sin(a), 1.8f);
                if (local)
                {
                    v.lights = {light};
                    v.specular_exponent = 40.0f;
                    v.specular_strength = 0.5f;
                }
                fig10.push_back(render(v));
            }
        write("fig10_normal_map.png", fig10, {"view 1", "view 2", "view 3", "view 4"},
              {"environment", "+ local light"});

        // The rendered glossy reflection against the reference: a glossy sphere (ks = 1, no diffuse, no
        // normal map) on the GPU, and at each covered pixel Eq. 9 integrated over the environment's pixels in
        // the reflection direction of the analytic sphere at the UV the GPU reports.
        {
            // A finely tessellated sphere, so that the GPU's interpolated normals are the analytic ones.
            const hemi::io::Mesh fine_sphere = hemi::io::make_uv_sphere(1.2f, 512, 256);
            hemi::samples::FactoredView v;
            v.mesh = &fine_sphere;
            v.environment = &env;
            v.technique = Technique::EnvGlossy;
            v.material.kd = 0.0f;
            v.material.ks = 1.0f;
            v.eye = glm::vec3(0.0f, -4.2f, 1.6f);
            hemi::io::ImageRgba aux;
            const hemi::io::ImageRgba img = hemi::samples::render_factored(device, v, size, size, &aux);
            std::vector<glm::dvec3> dirs;
            std::vector<glm::dvec3> got;
            for (uint32_t y = 0; y < size; ++y)
                for (uint32_t x = 0; x < size; ++x)
                    if (aux.at(x, y)[3] == 1.0f)
                    {
                        const double phi = 2.0 * M_PI * aux.at(x, y)[0], theta = M_PI * aux.at(x, y)[1];
                        const glm::dvec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                           std::cos(theta));
                        const glm::dvec3 view_dir = glm::normalize(glm::dvec3(v.eye) - 1.2 * n);
                        dirs.push_back(2.0 * glm::dot(n, view_dir) * n - view_dir);
                        got.emplace_back(img.at(x, y)[0], img.at(x, y)[1], img.at(x, y)[2]);
                    }
            const std::vector<glm::dvec3> ref = hemi::bake::phong_reference(studio, env.exponents[0], dirs);
            double se = 0.0, sr = 0.0;
            for (size_t i = 0; i < dirs.size(); ++i)
            {
                const glm::dvec3 e = got[i] - ref[i];
                se += glm::dot(e, e) / 3.0;
                sr += glm::dot(ref[i], ref[i]) / 3.0;
            }
            std::printf("rendered glossy sphere (exponent %g, %zu pixels) against the reference: RMSE %.4f, "
                        "%.3f%% of "
                        "the reference's RMS\n",
                        double(env.exponents[0]), dirs.size(), std::sqrt(se / dirs.size()),
                        100.0 * std::sqrt(se / sr));
        }

        // The comparison: one row of each figure's first images.
        std::vector<hemi::io::ImageRgba> all = {fig2[0], fig2[1], fig3[0], fig3[1], fig6[0], fig6[2],
                                                fig7[0], fig7[1], fig7[2], fig7[3], fig8[1], fig10[5]};
        hemi::samples::write_labeled_grid(out, all, size, size,
                                          {"TS m = 0.15", "TS m = 0.4", "Banks", "Banks disk",
                                           "parabolic front", "mirror", "n = 1.5", "n = 200", "coat 1.5",
                                           "coat 200", "glossy e = 20", "normal map + light"},
                                          {""}, 0.8f);
        std::printf("wrote %s and the figures in %s (%.1f s)\n", out.c_str(), dir.c_str(),
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "factored_shading: %s\n", e.what());
        return 1;
    }
    return 0;
}
