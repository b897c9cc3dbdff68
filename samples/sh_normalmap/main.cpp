// sh_normalmap: a brick-mapped sphere lit per pixel by SH9 irradiance, rendered headless on Vulkan and
// written to PNG (tone-mapped sRGB) and optionally EXR (linear).
//
//   sh_normalmap [-o out.png] [--exr out.exr] [--size WxH] [--env sky|uniform]

#include "scene.h"

#include <hemi/gpu/device.h>
#include <hemi/io/image.h>

#include <CLI/CLI.hpp>

#include <cstdio>

int main(int argc, char** argv)
{
    CLI::App app{"hemi sample: a normal-mapped sphere lit by SH9 irradiance (Vulkan, headless)"};
    std::string png = "sh_normalmap.png", exr, size = "640x480", env = "sky";
    app.add_option("-o,--output", png, "PNG to write (tone-mapped sRGB)")->capture_default_str();
    app.add_option("--exr", exr, "also write the linear image as EXR (RGBA float, alpha = coverage)");
    app.add_option("--size", size, "image size WxH")->capture_default_str();
    app.add_option("--env", env, "environment: sky (analytic sky) or uniform (radiance 1)")
        ->check(CLI::IsMember({"sky", "uniform"}))
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    unsigned w = 0, h = 0;
    if (std::sscanf(size.c_str(), "%ux%u", &w, &h) != 2 || w == 0 || h == 0 || w > 16384 || h > 16384)
    {
        std::fprintf(stderr, "sh_normalmap: --size must be WxH with 1..16384, got '%s'\n", size.c_str());
        return 2;
    }
    try
    {
        hemi::gpu::DeviceDesc desc;
        desc.log = [](hemi::gpu::LogLevel level, bool, std::string_view m)
        {
            if (level >= hemi::gpu::LogLevel::Info)
                std::fprintf(stderr, "%.*s\n", int(m.size()), m.data());
        };
        hemi::gpu::Device device(desc);
        auto scene = hemi::samples::make_sh_normalmap_scene(
            env == "uniform" ? hemi::samples::Environment::Uniform : hemi::samples::Environment::Sky);
        hemi::io::ImageRgba image = hemi::samples::render_sh_normalmap(device, scene, w, h);
        hemi::io::write_png(png, image);
        std::printf("wrote %s (%ux%u)\n", png.c_str(), w, h);
        if (!exr.empty())
        {
            hemi::io::write_exr(exr, image);
            std::printf("wrote %s\n", exr.c_str());
        }
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "sh_normalmap: %s\n", e.what());
        return 1;
    }
    return 0;
}
