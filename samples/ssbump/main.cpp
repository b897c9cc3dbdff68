// ssbump: Green 2007's Fig. 2 re-made from the procedural relief: the height map, its tangent-space normal
// map, the bump map stored in the radiosity-normal-mapping basis, and the same with directional ambient
// occlusion, side by side; each also on its own. Headless, writes PNGs.
//   ssbump [--size N] [--scale S] [--rays R] [--dir DIR] [-o FIG2.png]
#include "relief.h"

#include <hemi/bake/ssbump.h>
#include <hemi/io/image.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>

namespace
{

hemi::io::ImageRgba8 panel(uint32_t w, uint32_t h, std::vector<uint8_t> rgba)
{
    return {w, h, std::move(rgba)};
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"ssbump: Green 2007 Fig. 2 from a procedural relief (bricks, rivets, craters)"};
    uint32_t size = 512;
    float scale = 12.0f;
    int rays = 300;
    std::string dir = "ssbump", figure = "ssbump_fig2.png";
    app.add_option("--size", size, "map size in texels (a multiple of 64)")->capture_default_str();
    app.add_option("--scale", scale, "height of white above black, in texel widths")->capture_default_str();
    app.add_option("--rays", rays, "rays per texel")->capture_default_str();
    app.add_option("--dir", dir, "folder for the single panels (and the height map, for hemi-bake ssbump)")
        ->capture_default_str();
    app.add_option("-o,--output", figure, "the side-by-side figure")->capture_default_str();
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
        std::printf("wrote %s (height, normal map, bump map in the basis, with directional occlusion) and the panels "
                    "in %s/; %llu rays in %.2f s\n",
                    figure.c_str(), dir.c_str(), (unsigned long long)shadowed.rays, shadowed.trace_seconds);
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "ssbump: %s\n", e.what());
        return 1;
    }
    return 0;
}
