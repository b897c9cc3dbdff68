// ssbump: Green 2007's Figures 1 and 2 re-made from the procedural relief. Fig. 2: the height map, its
// tangent-space normal map, the bump map stored in the radiosity-normal-mapping basis, and the same with
// directional ambient occlusion, side by side; each also on its own. Fig. 1: the relief on a lightmapped
// floor (a dim sky baked into its rnm lightmap colours) under a dynamic light at three elevations, in the
// paper's three modes: normal mapped (Listing 1, technique rnm), normal mapped with ambient occlusion
// (rnm_ao, the occlusion texture), self-shadowed (the SSBump map, technique ssbump). Headless, writes PNGs.
//   ssbump [--size N] [--scale S] [--rays R] [--dir DIR] [-o FIG2.png] [--fig1 FIG1.png]
#include "figure.h"
#include "relief.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/ssbump.h>
#include <hemi/gpu/device.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/render/view/lightmap_view.h>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <cmath>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>

namespace
{

hemi::io::ImageRgba8 panel(uint32_t w, uint32_t h, std::vector<uint8_t> rgba)
{
    return {w, h, std::move(rgba)};
}

// A floor z = 0 over [-1, 1]^2 (tangent +x, bitangent +y), the relief once across it (TEXCOORD_0),
// its lightmap (TEXCOORD_1 over the floor) the rnm colours of a dim uniform sky, with the material's normal
// slot holding `normal_slot` and, when given, an occlusion texture.
hemi::io::LightmapAsset relief_floor(const hemi::io::ImageRgba8& normal_slot,
                                     const hemi::io::ImageRgba8* occlusion)
{
    hemi::io::LightmapAsset a;
    hemi::io::Mesh& m = a.mesh;
    const glm::vec2 c[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    for (const glm::vec2& uv : c)
    {
        m.positions.emplace_back(2.0f * uv.x - 1.0f, 1.0f - 2.0f * uv.y, 0.0f);
        m.normals.emplace_back(0, 0, 1);
        m.tangents.emplace_back(1, 0, 0, 1);
        m.uvs.push_back(uv);
        m.uvs1.push_back(uv);
    }
    m.indices = {0, 1, 2, 0, 2, 3};
    a.images.push_back({"relief normal slot.png", "image/png", hemi::io::encode_png(normal_slot)});
    hemi::io::Material mat;
    mat.name = "relief";
    mat.base_color_factor = glm::vec4(0.75f, 0.7f, 0.65f, 1.0f);
    mat.normal.image = 0;
    if (occlusion)
    {
        a.images.push_back({"relief occlusion.png", "image/png", hemi::io::encode_png(*occlusion)});
        mat.occlusion.image = 1;
    }
    a.materials.push_back(mat);
    a.primitives.push_back({0, 6, 0});
    const uint32_t atlas = 16;
    hemi::bake::LightmapUvReport report;
    const hemi::bake::LightmapAtlas lightmap = hemi::bake::rasterize_lightmap(m, atlas, atlas, report);
    hemi::bake::LightmapLights sky;
    sky.uniform = glm::vec3(0.12f, 0.14f, 0.18f);
    const hemi::bake::LightmapSh sh =
        hemi::bake::bake_lightmap_sh(m, lightmap, sky, hemi::bake::LightmapBakeOptions{});
    a.width = a.height = atlas;
    a.covered_texels = uint32_t(lightmap.texels.size());
    a.outputs.push_back({"rnm", 3, hemi::bake::lightmap_maps("rnm", lightmap, sh)});
    return a;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"ssbump: Green 2007 Fig. 2 from a procedural relief (bricks, rivets, craters)"};
    uint32_t size = 512;
    float scale = 12.0f;
    int rays = 300;
    std::string dir = "ssbump", figure = "ssbump_fig2.png", fig1 = "ssbump_fig1.png";
    app.add_option("--size", size, "map size in texels (a multiple of 64)")->capture_default_str();
    app.add_option("--scale", scale, "height of white above black, in texel widths")->capture_default_str();
    app.add_option("--rays", rays, "rays per texel")->capture_default_str();
    app.add_option("--dir", dir, "folder for the single panels (and the height map, for hemi-bake ssbump)")
        ->capture_default_str();
    app.add_option("-o,--output", figure, "Fig. 2: the maps side by side")->capture_default_str();
    app.add_option("--fig1", fig1, "Fig. 1: the three modes under a dynamic light (empty: none)")
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    try
    {
        std::filesystem::create_directories(dir);
        const hemi::bake::HeightField field = hemi::samples::make_relief(size);
        hemi::bake::SsbumpOptions o;
        o.scale = scale;
        o.rays = rays;
        const hemi::bake::SsbumpMap shadowed = hemi::bake::bake_ssbump(field, o);
        const hemi::bake::SsbumpMap plain =
            hemi::bake::ssbump_from_normals(size, size, shadowed.normals, o.convention);
        std::vector<uint8_t> height(size_t(size) * size * 4);
        for (size_t i = 0; i < field.heights.size(); ++i)
        {
            const uint8_t v = uint8_t(std::lround(field.heights[i] * 255.0f));
            height[i * 4 + 0] = height[i * 4 + 1] = height[i * 4 + 2] = v;
            height[i * 4 + 3] = 255;
        }
        const hemi::io::ImageRgba8 panels[4] = {
            panel(size, size, height),
            panel(size, size, hemi::bake::ssbump_rgba8(shadowed.normals, {}, true)),
            panel(size, size, hemi::bake::ssbump_rgba8(plain.weights, {}, false)),
            panel(size, size, hemi::bake::ssbump_rgba8(shadowed.weights, {}, false)),
        };
        const char* names[4] = {"height.png", "normal.png", "basis.png", "ssbump.png"};
        for (int i = 0; i < 4; ++i)
            hemi::io::write_png(std::filesystem::path(dir) / names[i], panels[i]);
        // Side by side with an 8-texel gap: the top-left 256 x 256 texels of each, at full resolution.
        const uint32_t p = std::min(size, 256u), gap = 8;
        hemi::io::ImageRgba8 fig{4 * p + 3 * gap, p, {}};
        fig.pixels.assign(size_t(fig.width) * fig.height * 4, 255);
        for (int i = 0; i < 4; ++i)
            for (uint32_t y = 0; y < p; ++y)
                for (uint32_t x = 0; x < p; ++x)
                    for (int c = 0; c < 4; ++c)
                        fig.pixels[(size_t(y) * fig.width + uint32_t(i) * (p + gap) + x) * 4 + size_t(c)] =
                            panels[i].pixels[(size_t(y) * size + x) * 4 + size_t(c)];
        hemi::io::write_png(figure, fig);
        std::printf(
            "wrote %s (height, normal map, bump map in the basis, with directional occlusion) and the panels "
            "in %s/; %llu rays in %.2f s\n",
            figure.c_str(), dir.c_str(), (unsigned long long)shadowed.rays, shadowed.trace_seconds);

        if (!fig1.empty())
        {
            // The plain ambient occlusion of the baseline: the mean of the three directional occlusions.
            hemi::io::ImageRgba8 ao{size, size, std::vector<uint8_t>(size_t(size) * size * 4, 255)};
            for (size_t i = 0; i < shadowed.occlusion.size(); ++i)
            {
                const glm::vec3& occ = shadowed.occlusion[i];
                const uint8_t v =
                    uint8_t(std::lround(std::clamp((occ.x + occ.y + occ.z) / 3.0f, 0.0f, 1.0f) * 255.0f));
                ao.pixels[i * 4] = ao.pixels[i * 4 + 1] = ao.pixels[i * 4 + 2] = v;
            }
            const hemi::io::ImageRgba8& normal_map = panels[1];
            const hemi::io::ImageRgba8& ssbump_map = panels[3];
            const hemi::io::LightmapAsset assets[3] = {relief_floor(normal_map, nullptr),
                                                       relief_floor(normal_map, &ao),
                                                       relief_floor(ssbump_map, nullptr)};
            const char* techniques[3] = {"rnm", "rnm_ao", "ssbump"};
            const float elevations[3] = {60.0f, 35.0f, 15.0f};
            hemi::gpu::Device device(hemi::gpu::DeviceDesc{});
            const uint32_t t = 256;
            std::vector<hemi::io::ImageRgba> tiles(9);
            for (int mode = 0; mode < 3; ++mode)
            {
                hemi::render::LightmapView view(device, assets[mode], {techniques[mode]}, t, t);
                for (int row = 0; row < 3; ++row)
                {
                    hemi::render::LightmapFrame frame;
                    frame.technique = techniques[mode];
                    frame.model = glm::mat4(1.0f);
                    frame.camera.eye = glm::vec3(0.1f, -0.75f, 0.95f);
                    frame.camera.target = glm::vec3(0.1f, 0.15f, 0.0f);
                    const float e = glm::radians(elevations[row]), azimuth = glm::radians(20.0f);
                    hemi::render::DynamicLight sun;
                    sun.position = glm::vec3(std::cos(e) * std::cos(azimuth), std::cos(e) * std::sin(azimuth),
                                             std::sin(e));
                    sun.irradiance = glm::vec3(2.6f, 2.45f, 2.2f);
                    frame.lights = {sun};
                    tiles[size_t(row) * 3 + size_t(mode)] = view.render(frame);
                    char name[64];
                    std::snprintf(name, sizeof name, "fig1_%s_%02d.png", techniques[mode],
                                  int(elevations[row]));
                    hemi::io::write_png(std::filesystem::path(dir) / name,
                                        tiles[size_t(row) * 3 + size_t(mode)]);
                }
            }
            hemi::samples::write_labeled_grid(
                fig1, tiles, t, t,
                {"normal mapped (Listing 1)", "with ambient occlusion", "self-shadowed (SSBump)"},
                {"light 60 deg above the horizon", "35 deg", "15 deg"}, 1.0f);
            std::printf("wrote %s (the three modes under a dynamic light at 60, 35 and 15 degrees)\n",
                        fig1.c_str());
        }
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "ssbump: %s\n", e.what());
        return 1;
    }
    return 0;
}
