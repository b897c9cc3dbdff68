// hemi-render: renders a baked asset headlessly (Vulkan, lavapipe included) to PNG or EXR: the preview a
// pipeline takes of a bake, and the samples' building block. The asset's kind is read from the file.
//
//   hemi-render PRT.hemi --technique gs|hl2|sal4|h4|h6|sep4|prt [--cpca] --env uniform|sky|FILE.exr
//               [--rotate DEG] [--white] [--size WxH] [--camera auto|EYE,TARGET] [--exposure E]
//               -o OUT.png|OUT.exr
//   hemi-render LEVEL.hemi --technique sh9|hl2|h4|h6|sal4|plain|rnm|ssbump [--white] [--size WxH]
//               [--camera auto|EYE,TARGET] [--exposure E] [--sphere X,Y,Z,R ...] -o OUT.png|OUT.exr
//               (a lightmap asset: the lighting is baked in; each --sphere is a dynamic object lit by the
//               asset's light probes)
// Environment assets (hemi-bake envmap) are drawn by the material system's environment materials, not here.
// HEMI_DEVICE picks the Vulkan device; HEMI_VALIDATION=1 turns the Khronos validation layer on, and then any
// message from it makes the exit status 2.
#include <hemi/gpu/device.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/ggx.h>
#include <hemi/render/view/lightmap_view.h>
#include <hemi/render/view/prt_view.h>

#include "tool_options.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

int main(int argc, char** argv)
{
    CLI::App app{"hemi-render: render a baked PRT (hemi-bake prt) or lightmap (hemi-bake lightmap) asset to "
                 "PNG or EXR"};
    std::string asset_path, technique = "gs", env = "sky", size = "800x600", camera = "auto", output;
    bool cpca = false, white = false, bicubic = false;
    std::vector<std::string> spheres;
    float rotate = 0.0f, exposure = 1.0f, roughness = 0.0f, f0 = 0.04f;
    app.add_option("asset", asset_path, "baked asset (.hemi)")->required()->check(CLI::ExistingFile);
    app.add_option("--technique", technique,
                   "PRT: gs (SH9 gold standard), hl2, sal4, h4, h6, sep4, prt (classic PRT), "
                   "also sh4ls, zernike3, zernike6 when baked; lightmaps: sh9 (gs is the "
                   "same), hl2, h4, h6, sal4, plain (non-directional), rnm (radiosity "
                   "normal mapping), ssbump (an SSBump map in the normal slot)")
        ->capture_default_str();
    app.add_flag("--cpca", cpca, "use the technique's CPCA data (bake with --cpca)");
    CLI::Option* env_option =
        app.add_option("--env", env,
                       "PRT: uniform (radiance 1 everywhere), sky (analytic) or an "
                       "equirectangular FILE.exr, z up, in Blender's world mapping (the image centre looks "
                       "along +x); lightmaps carry their lighting")
            ->capture_default_str();
    app.add_option("--rotate", rotate, "turn the environment about the up axis by DEG degrees")
        ->check(hemi::tool::finite(-1e6, 1e6))
        ->capture_default_str();
    app.add_flag("--white", white, "albedo 1: the lighting-only view");
    app.add_flag("--bicubic", bicubic,
                 "lightmaps: look the lightmap up with the cubic B-spline instead of the linear filter (no "
                 "creases at texel centres in gradients)");
    app.add_option("--roughness", roughness,
                   "lightmaps: a GGX coat of this roughness (glTF's, 0.03 to 1) over every surface, its "
                   "specular from the lightmap's coefficients and exact for mixed lights (0: none; "
                   "docs/specular.md)")
        ->check(CLI::Range(0.0f, 1.0f))
        ->capture_default_str();
    app.add_option("--f0", f0, "lightmaps: the GGX coat's reflectance at normal incidence (0 to 1)")
        ->check(CLI::Range(0.0f, 1.0f))
        ->capture_default_str();
    app.add_option("--size", size, "WIDTHxHEIGHT in pixels")->capture_default_str();
    app.add_option("--camera", camera,
                   "auto (frames the model) or EYE,TARGET as x,y,z,x,y,z in world space (z up; "
                   "glTF +y is world +z)")
        ->capture_default_str();
    app.add_option("--sphere", spheres,
                   "lightmap assets baked with --probes: a grey sphere at X,Y,Z (world space) of "
                   "radius R, lit by the probes (repeatable, up to 16)");
    app.add_option("--exposure", exposure, "PNG only: multiplies radiance before the sRGB clamp (> 0)")
        ->check(hemi::tool::finite(1e-30, 1e30))
        ->capture_default_str();
    app.add_option("-o,--output", output,
                   "OUT.png (tone-mapped sRGB) or OUT.exr (linear RGBA, alpha = coverage)")
        ->required();
    return hemi::tool::run(
        app, argc, argv, "hemi-render",
        [&]() -> int
        {
            const auto t0 = std::chrono::steady_clock::now();
            const auto [w, h] = hemi::tool::parse_size(size, "--size", 16384, false);
            const std::string ext = std::filesystem::path(output).extension().string();
            if (ext != ".png" && ext != ".exr")
                throw std::invalid_argument("-o must end in .png or .exr, got '" + output + "'");
            // The output before any work: writable, a regular file or none, not the asset itself.
            hemi::tool::Files files;
            files.input("ASSET", asset_path);
            if (env != "uniform" && env != "sky")
                files.input("--env", env);
            files.output("-o", output);
            files.check();
            std::vector<glm::vec4> sphere_list;
            for (const std::string& text : spheres)
            {
                const std::vector<double> v =
                    hemi::tool::parse_numbers(text, "--sphere", "X,Y,Z,RADIUS (RADIUS > 0)", {4});
                if (!(v[3] > 0.0))
                    throw std::invalid_argument("--sphere " + text + ": the radius must be > 0");
                sphere_list.push_back(glm::vec4(float(v[0]), float(v[1]), float(v[2]), float(v[3])));
            }
            const std::string kind = hemi::io::asset_kind(asset_path);
            if (kind != "lightmap" && kind != "prt")
                throw std::invalid_argument(
                    asset_path + " is an asset of kind '" + kind +
                    "': hemi-render draws PRT assets (hemi-bake prt) and lightmap assets "
                    "(hemi-bake lightmap); an environment asset (hemi-bake envmap) is "
                    "drawn by the environment materials (docs/factored.md)");
            const bool lightmap = kind == "lightmap";
            if (!lightmap && !spheres.empty())
                throw std::invalid_argument("--sphere is for lightmap assets baked with --probes");
            if (roughness > 0.0f && roughness < float(hemi::math::kGgxMinRoughness))
                throw std::invalid_argument("--roughness must be 0 (no coat) or in [0.03, 1]");
            if (roughness > 0.0f && (technique == "rnm" || technique == "ssbump" || technique == "rnm_ao"))
                throw std::invalid_argument(
                    "--roughness needs a basis's coefficients (sh9, h6, ..., plain), not "
                    "--technique " +
                    technique);
            if (!lightmap && roughness > 0.0f)
                throw std::invalid_argument(asset_path +
                                            " is not a lightmap asset: --roughness is for lightmaps");
            if (!lightmap && bicubic)
                throw std::invalid_argument(asset_path +
                                            " is not a lightmap asset: --bicubic is for lightmaps");
            if (lightmap && (cpca || rotate != 0.0f || env_option->count() > 0))
                throw std::invalid_argument(asset_path +
                                            " is a lightmap asset: its lighting is baked in (--env, --rotate "
                                            "and --cpca are for PRT assets)");
            // Vulkan's warnings and errors (the validation layer's too, with HEMI_VALIDATION=1) go to stderr.
            hemi::gpu::DeviceDesc desc;
            desc.log = [](hemi::gpu::LogLevel level, bool validation, std::string_view message)
            {
                if (level >= hemi::gpu::LogLevel::Warning)
                    std::fprintf(stderr, "hemi-render: %s%.*s\n", validation ? "validation: " : "",
                                 int(message.size()), message.data());
            };
            const float aspect = float(w) / float(h);
            const std::optional<hemi::math::Camera> chosen = hemi::math::parse_camera(camera);
            const bool auto_camera = !chosen;
            const hemi::render::PrtCamera view_camera = chosen.value_or(hemi::render::PrtCamera{});
            hemi::io::ImageRgba image;
            std::unique_ptr<hemi::gpu::Device> device;
            // The camera and the depth range square lengths in float: positions past 1e18 cannot be framed
            // (issue 41: an asset at 3e38 got "the camera's eye or target is not finite", no file named).
            const auto check_extent = [&](const hemi::io::Mesh& mesh)
            {
                float largest = 0.0f;
                for (const glm::vec3& p : mesh.positions)
                    largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
                if (largest > 1e18f)
                {
                    char text[160];
                    std::snprintf(
                        text, sizeof text,
                        ": its positions reach %.3g units, beyond the 1e18 that the camera and depth "
                        "range hold (squared lengths overflow a float)",
                        double(largest));
                    throw std::invalid_argument(asset_path + text);
                }
            };
            // Whatever the asset holds that cannot be drawn (a corrupt embedded image: "tiles normal map:
            // corrupt PNG") is named with the asset that holds it.
            try
            {
                if (lightmap)
                {
                    const hemi::io::LightmapAsset asset = hemi::io::read_lightmap_asset(asset_path);
                    check_extent(asset.mesh);
                    if (technique == "gs")
                        technique = "sh9";
                    try
                    {
                        asset.output(technique == "ssbump" || technique == "rnm_ao" ? "rnm" : technique);
                    }
                    catch (const std::invalid_argument& e)
                    {
                        throw std::invalid_argument(asset_path + ": " + e.what());
                    }
                    device = std::make_unique<hemi::gpu::Device>(desc);
                    // The GGX coat: the output drawn by the ggx technique ("<output>+ggx").
                    if (roughness > 0.0f)
                        technique += "+ggx";
                    hemi::render::LightmapView view(*device, asset, {technique}, w, h,
                                                    bicubic ? hemi::render::LightmapFilter::Bicubic
                                                            : hemi::render::LightmapFilter::Linear);
                    hemi::render::LightmapFrame frame;
                    frame.technique = technique;
                    frame.white = white;
                    frame.camera = auto_camera ? hemi::render::auto_camera(asset.mesh, frame.model, aspect)
                                               : view_camera;
                    frame.spheres = sphere_list;
                    frame.glossy_roughness = roughness;
                    frame.glossy_f0 = f0;
                    // The asset's mixed lights, lit at run time with their shadowmask channels.
                    try
                    {
                        frame.lights = hemi::render::mixed_lights(asset, frame.model);
                    }
                    catch (const std::invalid_argument& e)
                    {
                        throw std::invalid_argument(asset_path + ": " + e.what());
                    }
                    if (!frame.spheres.empty() && asset.probes.empty())
                        throw std::invalid_argument(
                            asset_path + " has no light probes for --sphere (bake it with --probes)");
                    image = view.render(frame);
                    env = "baked";
                }
                else
                {
                    const hemi::io::PrtAsset asset = hemi::io::read_prt_asset(asset_path);
                    check_extent(asset.mesh);
                    device = std::make_unique<hemi::gpu::Device>(desc);
                    hemi::render::PrtView view(*device, asset, technique, cpca, w, h);
                    hemi::render::PrtFrame frame;
                    frame.world_lighting = hemi::render::environment_lighting(env, int(asset.order));
                    frame.rotate_degrees = rotate;
                    frame.white = white;
                    frame.camera = auto_camera ? hemi::render::auto_camera(asset.mesh, frame.model, aspect)
                                               : view_camera;
                    image = view.render(frame);
                }
            }
            catch (const std::bad_alloc&)
            {
                throw;
            }
            catch (const std::exception& e)
            {
                const std::string what = e.what();
                if (what.find(asset_path) != std::string::npos)
                    throw;
                throw std::runtime_error(asset_path + ": " + what);
            }
            if (ext == ".exr")
                hemi::io::write_exr(output, image);
            else
                hemi::io::write_png(output, image, {exposure, hemi::io::ToneMap::Curve::Clamp});
            std::printf("rendered %s (%s%s, %s, %ux%u) in %.2f s -> %s\n", asset_path.c_str(),
                        technique.c_str(), cpca ? " + CPCA" : "", env.c_str(), w, h,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                        output.c_str());
            if (device->validation_messages() > 0)
            {
                std::fprintf(stderr, "hemi-render: the validation layer reported %llu problem(s)\n",
                             (unsigned long long)device->validation_messages());
                return 2;
            }
            return 0;
        });
}
