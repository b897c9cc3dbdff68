// irradiance_normalmap: Habel & Wimmer 2010's comparison, re-made with hemi on the sample level (a room with
// openings, pillars, bevelled tiles and bricks in its normal maps): the level's directional lightmap is baked
// (SH9 irradiance per texel), each basis is drawn at the normal-map normal through the material system, and
// every image is measured against the path-traced ground truth (hemi-bake reference) of the same scene,
// lights and camera, under a sky with a sun and under the sky alone. Writes the comparison figure (lighting
// alone, E / pi, and each technique's error), a bar chart of the errors (gnuplot), a Markdown table, and in
// DIR the level as level.glb, its lightmap assets (level_sun.hemi, level_sky.hemi), the references (EXR) and
// every image on its own, so that hemi-bake and hemi-render can re-make each from the command line.
//
//   irradiance_normalmap [--dir DIR] [-o FIGURE.png] [--table TABLE.md] [--plot PLOT.png] [--atlas N]
//                        [--rays R] [--reference-rays R] [--bounces B] [--size WxH] [--glossy-table
//                        GLOSSY.md]
#include "figure.h"
#include "level.h"

#include <hemi/bake/gnuplot.h>
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/reference.h>
#include <hemi/gpu/device.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/camera.h>
#include <hemi/render/view/lightmap_view.h>

#include <CLI/CLI.hpp>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace
{

struct Column
{
    const char* technique;
    const char* label;
};
// Habel's order, best first, and the non-directional baseline.
const Column kTechniques[] = {
    {"sh9", "SH9"}, {"h6", "H6"}, {"h4", "H4"}, {"hl2", "HL2"}, {"plain", "plain lightmap"}};
// The directional bases again with their ringing-free outputs (hemi-bake lightmap --non-negative): the
// table's last rows.
const Column kNonNegative[] = {{"sh9", "SH9, --non-negative"},
                               {"h6", "H6, --non-negative"},
                               {"h4", "H4, --non-negative"},
                               {"hl2", "HL2, --non-negative"}};

struct Error
{
    double rmse = 0.0;      // linear E / pi over the pixels both images cover fully
    double corrected = 0.0; // with the reference's own noise taken out: sqrt(rmse^2 - noise^2)
    double relative = 0.0;  // corrected over the reference's mean
    size_t pixels = 0;
};

Error compare(const hemi::io::ImageRgba& image, const hemi::bake::ReferenceImage& reference)
{
    double squared = 0.0, mean = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < image.pixels.size(); i += 4)
    {
        if (image.pixels[i + 3] != 1.0f || reference.image.pixels[i + 3] != 1.0f)
            continue;
        for (int c = 0; c < 3; ++c)
        {
            const double d = double(image.pixels[i + c]) - reference.image.pixels[i + c];
            squared += d * d;
            mean += reference.image.pixels[i + c];
        }
        ++count;
    }
    Error e;
    e.pixels = count;
    const double n = double(std::max<size_t>(count, 1) * 3);
    e.rmse = std::sqrt(squared / n);
    e.corrected = std::sqrt(std::max(0.0, squared / n - reference.noise * reference.noise));
    e.relative = e.corrected / std::max(mean / n, 1e-12);
    return e;
}

// |a - b| times `gain`, in every channel the same (the mean of the channels' errors), where both cover the
// pixel.
hemi::io::ImageRgba error_image(const hemi::io::ImageRgba& a, const hemi::io::ImageRgba& b, float gain)
{
    hemi::io::ImageRgba out{a.width, a.height, std::vector<float>(a.pixels.size(), 0.0f)};
    for (size_t i = 0; i < a.pixels.size(); i += 4)
    {
        if (a.pixels[i + 3] != 1.0f || b.pixels[i + 3] != 1.0f)
            continue;
        float d = 0.0f;
        for (int c = 0; c < 3; ++c)
            d += std::abs(a.pixels[i + c] - b.pixels[i + c]) / 3.0f;
        out.pixels[i] = out.pixels[i + 1] = out.pixels[i + 2] = d * gain;
        out.pixels[i + 3] = 1.0f;
    }
    return out;
}

// A 2 x 2 box filter: the figure's tiles at half the measured size.
hemi::io::ImageRgba half(const hemi::io::ImageRgba& image)
{
    hemi::io::ImageRgba out{image.width / 2, image.height / 2, {}};
    out.pixels.assign(size_t(out.width) * out.height * 4, 0.0f);
    for (uint32_t y = 0; y < out.height; ++y)
        for (uint32_t x = 0; x < out.width; ++x)
            for (int c = 0; c < 4; ++c)
                out.pixels[(size_t(y) * out.width + x) * 4 + c] =
                    0.25f * (image.at(2 * x, 2 * y)[c] + image.at(2 * x + 1, 2 * y)[c] +
                             image.at(2 * x, 2 * y + 1)[c] + image.at(2 * x + 1, 2 * y + 1)[c]);
    return out;
}

// The GGX coat's table (--glossy-table): per roughness, each technique's error of the total image (diffuse
// and specular) against the glossy reference, and of its specular alone against the reference's.
struct GlossyRow
{
    std::string label;
    Error total[3];
    double specular[3] = {0.0, 0.0, 0.0}; // RMSE of the specular over the reference specular's mean
};
constexpr double kGlossyRoughness[3] = {0.2, 0.5, 0.8};
constexpr double kGlossyF0 = 0.04;

// RMSE of (a - a0) - (b - b0) over the pixels all four cover, over the mean of b - b0: the specular's
// relative error when a0 and b0 are the diffuse views of a and b. `noise` is b - b0's own (the reference
// specular's standard error per pixel), taken out in quadrature.
double specular_error(const hemi::io::ImageRgba& a, const hemi::io::ImageRgba& a0,
                      const hemi::io::ImageRgba& b, const hemi::io::ImageRgba& b0, double noise)
{
    double squared = 0.0, mean = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < a.pixels.size(); i += 4)
    {
        if (a.pixels[i + 3] != 1.0f || a0.pixels[i + 3] != 1.0f || b.pixels[i + 3] != 1.0f ||
            b0.pixels[i + 3] != 1.0f)
            continue;
        for (int c = 0; c < 3; ++c)
        {
            const double s = double(b.pixels[i + c]) - b0.pixels[i + c];
            const double d = double(a.pixels[i + c]) - a0.pixels[i + c] - s;
            squared += d * d;
            mean += s;
            ++n;
        }
    }
    return n ? std::sqrt(std::max(0.0, squared / double(n) - noise * noise)) /
                   std::max(mean / double(n), 1e-12)
             : 0.0;
}

struct Setup
{
    const char* name;
    const char* file;
    bool sun;
    fs::path figure;
    hemi::bake::ReferenceImage reference;
    std::vector<Error> errors;
};

void write_plot(const fs::path& path, const std::vector<Setup>& setups)
{
    hemi::bake::run_gnuplot(
        path,
        [&](const fs::path& folder, std::ostream& script, const fs::path& output)
        {
            {
                std::ofstream data(folder / "errors.dat");
                for (size_t i = 0; i < std::size(kTechniques); ++i)
                {
                    data << i << " \"" << kTechniques[i].label << "\"";
                    for (const Setup& setup : setups)
                        data << " " << setup.errors[i].corrected;
                    data << "\n";
                }
            }
            script << "set terminal pngcairo size 760,420 noenhanced font 'Sans,11'\n"
                   << "set output '" << output.string() << "'\n"
                   << "set title 'Irradiance normal mapping on the sample level: RMSE of E/pi against the "
                      "path-traced "
                      "reference'\n"
                   << "set ylabel 'RMSE (linear E/pi, reference noise removed)'\nset style fill solid 0.8 "
                      "border -1\n"
                   << "set boxwidth 0.35\nset yrange [0:*]\nset grid ytics\nset key top left\n"
                   << "plot '" << (folder / "errors.dat").string()
                   << "' using ($1-0.19):3:xtic(2) with boxes lc rgb '#d08020' title '" << setups[0].name
                   << "', "
                   << "'' using ($1+0.19):4 with boxes lc rgb '#3070b0' title '" << setups[1].name << "'\n";
        });
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{
        "irradiance_normalmap: Habel & Wimmer 2010's basis comparison on a lightmapped level, against a "
        "path-traced reference"};
    std::string dir = "irradiance_normalmap", figure = "irradiance_normalmap.png",
                table = "irradiance_normalmap.md", plot = "irradiance_normalmap_rmse.png", size = "640x400",
                ssbump_figure = "irradiance_normalmap_ssbump.png", glossy_table;
    uint32_t atlas = 384;
    int rays = 256, reference_rays = 256, bounces = 1;

    app.add_option("--dir", dir, "folder for level.glb, level.hemi, the reference EXR and the single images")
        ->capture_default_str();
    app.add_option("-o,--output", figure,
                   "the comparison figure under the sky and the sun (PNG; FIGURE_sky.png: the "
                   "sky alone)")
        ->capture_default_str();
    app.add_option("--ssbump-figure", ssbump_figure,
                   "Green 2007's room: the level's rnm lightmap with Listing 1 "
                   "and with SSBump maps (PNG; empty: none)")
        ->capture_default_str();
    app.add_option("--table", table, "the errors as a Markdown table")->capture_default_str();
    app.add_option(
        "--glossy-table", glossy_table,
        "also measure the GGX coat's specular (roughness 0.2, 0.5, 0.8, f0 0.04) of each technique "
        "under the sky and the sun against the glossy reference, as a Markdown table (three more "
        "references: minutes; docs/specular.md)");
    app.add_option("--plot", plot, "the errors as a bar chart (PNG, gnuplot)")->capture_default_str();
    app.add_option("--atlas", atlas, "lightmap atlas size (square)")
        ->check(CLI::Range(64u, 4096u))
        ->capture_default_str();
    app.add_option("--rays", rays, "lightmap rays per texel and pass")
        ->check(CLI::Range(1, 1 << 16))
        ->capture_default_str();
    app.add_option("--reference-rays", reference_rays, "reference paths per pixel")
        ->check(CLI::Range(2, 1 << 16))
        ->capture_default_str();
    app.add_option("--bounces", bounces, "bounces of indirect light (bake and reference alike)")
        ->check(CLI::Range(0, 16))
        ->capture_default_str();
    app.add_option("--size", size, "WIDTHxHEIGHT of the measured images (the figure shows them at half size)")
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    try
    {
        unsigned w = 0, h = 0;
        char x = 0, rest = 0;
        if (std::sscanf(size.c_str(), "%u%c%u%c", &w, &x, &h, &rest) != 3 || x != 'x' || w < 16 || h < 16 ||
            w > 4096 || h > 4096)
            throw std::invalid_argument("--size expects WIDTHxHEIGHT (16 to 4096 each), got '" + size + "'");
        fs::create_directories(dir);
        for (const fs::path& p : {fs::path(figure), fs::path(figure).replace_extension().concat("_sky.png"),
                                  fs::path(table), fs::path(plot)})
            hemi::io::check_writable(p);
        if (!ssbump_figure.empty())
            hemi::io::check_writable(ssbump_figure);
        if (!glossy_table.empty())
            hemi::io::check_writable(glossy_table);
        std::vector<GlossyRow> glossy;

        // The level, as a file too (hemi-bake lightmap / reference read it).
        const hemi::io::GltfScene level = hemi::samples::make_level(atlas);
        hemi::io::write_gltf(fs::path(dir) / "level.glb", level);

        const hemi::bake::LightmapSurfaces surfaces(level.mesh, level.materials, level.images,
                                                    level.primitives);
        hemi::bake::LightmapUvReport report;
        const hemi::bake::LightmapAtlas lightmap_atlas =
            hemi::bake::rasterize_lightmap(level.mesh, atlas, atlas, report);
        if (!report.ok())
            throw std::runtime_error("the level's lightmap UVs: " + report.problems.front());
        hemi::gpu::Device device(hemi::gpu::DeviceDesc{});

        std::vector<std::string> columns = {"path-traced reference"};
        for (const Column& c : kTechniques)
            columns.push_back(c.label);
        const fs::path sky_figure = fs::path(figure).replace_extension().string() + "_sky.png";
        std::vector<Setup> setups = {{"sky and sun", "sun", true, figure, {}, {}},
                                     {"sky only", "sky", false, sky_figure, {}, {}}};
        const float exposure = 1.6f, gain = 4.0f;
        for (Setup& setup : setups)
        {
            // Lights, in hemi's z-up world (the level is placed there by gltf_to_world, as hemi-render places
            // it): a blue sky, and a sun low in the west shining through the wide opening onto the floor.
            hemi::bake::LightmapLights lights;
            lights.uniform = glm::vec3(0.35f, 0.45f, 0.65f);
            lights.sun = setup.sun;
            lights.sun_direction = glm::normalize(glm::vec3(-0.75f, -0.3f, 0.55f));
            lights.sun_irradiance = glm::vec3(5.0f, 4.6f, 4.0f);
            lights.scene_to_world = glm::mat3(hemi::math::gltf_to_world());

            // The bake: one SH9 irradiance per texel, every output from it.
            std::fprintf(stderr, "%s: baking the lightmap (%ux%u, %d rays per texel, %d bounce(s)) ...\n",
                         setup.name, atlas, atlas, rays, bounces);
            hemi::bake::LightmapBakeOptions bake;
            bake.rays = rays;
            bake.bounces = bounces;
            const hemi::bake::LightmapSh sh =
                hemi::bake::bake_lightmap_sh(level.mesh, lightmap_atlas, lights, bake, &surfaces);
            std::fprintf(stderr, "  %zu texels, %.1f s (%.1f Mrays/s)\n", lightmap_atlas.texels.size(),
                         sh.trace_seconds, double(sh.rays) / sh.trace_seconds * 1e-6);
            hemi::io::LightmapAsset asset;
            asset.mesh = level.mesh;
            asset.materials = level.materials;
            asset.images = level.images;
            asset.primitives = level.primitives;
            asset.width = asset.height = atlas;
            asset.rays = uint32_t(rays);
            asset.bounces = uint32_t(bounces);
            asset.seed = bake.seed;
            asset.covered_texels = uint32_t(lightmap_atlas.texels.size());
            std::vector<std::string> techniques;
            for (const Column& c : kTechniques)
            {
                techniques.push_back(c.technique);
                asset.outputs.push_back({c.technique, uint32_t(hemi::bake::lightmap_output_size(c.technique)),
                                         hemi::bake::lightmap_maps(c.technique, lightmap_atlas, sh)});
            }
            // Light probes for dynamic objects, from the same lights and the lightmap's bounces.
            asset.probes = hemi::bake::probe_grid(level.mesh, glm::uvec3(6, 3, 6));
            hemi::bake::LightmapBakeOptions probe_options = bake;
            probe_options.rays = 2048;
            hemi::bake::bake_light_probes(asset.probes, level.mesh, lightmap_atlas, sh, lights, probe_options,
                                          &surfaces);
            const std::string stem = std::string("level_") + setup.file;
            hemi::io::write_lightmap_asset(fs::path(dir) / (stem + ".hemi"), asset);

            // The ground truth, from outside the room's south-east corner (the near walls' backs are culled),
            // the camera `hemi-render --camera` takes as 1.5,-7.5,5,-0.5,0.5,0.6.
            hemi::bake::ReferenceOptions ro;
            ro.auto_camera = false;
            ro.camera.eye = glm::vec3(1.5f, -7.5f, 5.0f);
            ro.camera.target = glm::vec3(-0.5f, 0.5f, 0.6f);
            ro.width = w;
            ro.height = h;
            ro.rays = reference_rays;
            ro.bounces = bounces;
            ro.white = true;
            std::fprintf(stderr, "%s: tracing the reference (%ux%u, %d paths per pixel) ...\n", setup.name, w,
                         h, reference_rays);
            setup.reference = hemi::bake::render_reference(level.mesh, surfaces, lights, ro);
            const hemi::bake::ReferenceImage& reference = setup.reference;
            std::fprintf(stderr, "  %.1f s (%.1f Mrays/s), noise %.4f\n", reference.seconds,
                         double(reference.rays) / reference.seconds * 1e-6, reference.noise);
            hemi::io::write_exr(fs::path(dir) / (stem + "_reference.exr"), reference.image);
            hemi::io::write_png(fs::path(dir) / (stem + "_reference.png"), reference.image,
                                {exposure, hemi::io::ToneMap::Curve::Clamp});

            // Every technique through the material system, the same camera.
            hemi::render::LightmapView view(device, asset, techniques, w, h);
            hemi::render::LightmapFrame frame;
            frame.camera = reference.camera;
            frame.white = true;
            std::vector<hemi::io::ImageRgba> tiles = {half(reference.image)},
                                             errors_row = {
                                                 half(error_image(reference.image, reference.image, gain))};
            for (const Column& c : kTechniques)
            {
                frame.technique = c.technique;
                const hemi::io::ImageRgba image = view.render(frame);
                setup.errors.push_back(compare(image, reference));
                errors_row.push_back(half(error_image(image, reference.image, gain)));
                hemi::io::write_png(fs::path(dir) / (stem + "_" + c.technique + ".png"), image,
                                    {exposure, hemi::io::ToneMap::Curve::Clamp});
                tiles.push_back(half(image));
            }
            // The same bake's ringing-free outputs: the table's last rows.
            hemi::io::LightmapAsset clean = asset;
            clean.outputs.clear();
            std::vector<std::string> clean_techniques;
            for (const Column& c : kNonNegative)
            {
                clean_techniques.push_back(c.technique);
                clean.outputs.push_back(
                    {c.technique, uint32_t(hemi::bake::lightmap_output_size(c.technique)),
                     hemi::bake::lightmap_maps(c.technique, lightmap_atlas, sh, 2, true)});
            }
            {
                hemi::render::LightmapView clean_view(device, clean, clean_techniques, w, h);
                hemi::render::LightmapFrame clean_frame = frame;
                for (const Column& c : kNonNegative)
                {
                    clean_frame.technique = c.technique;
                    setup.errors.push_back(compare(clean_view.render(clean_frame), reference));
                }
            }
            if (setup.sun && !glossy_table.empty())
            {
                // The GGX coat: each technique's "+ggx" (its coefficients' specular) against the reference
                // with the same coat (the same seed: the same diffuse paths, so that the difference of the
                // two references is the specular alone), and the diffuse view as the baseline.
                std::vector<std::string> ggx;
                for (const Column& c : kTechniques)
                    ggx.push_back(std::string(c.technique) + "+ggx");
                hemi::render::LightmapView ggx_view(device, asset, ggx, w, h);
                glossy.assign(std::size(kTechniques) + 1, {});
                for (size_t i = 0; i < std::size(kTechniques); ++i)
                    glossy[i].label = kTechniques[i].label;
                glossy.back().label = "diffuse only (SH9, no specular)";
                for (int ri = 0; ri < 3; ++ri)
                {
                    hemi::bake::ReferenceOptions glossy_options = ro;
                    glossy_options.roughness = kGlossyRoughness[ri];
                    glossy_options.f0 = kGlossyF0;
                    std::fprintf(stderr, "%s: tracing the glossy reference (roughness %.1f) ...\n",
                                 setup.name, kGlossyRoughness[ri]);
                    const hemi::bake::ReferenceImage coat =
                        hemi::bake::render_reference(level.mesh, surfaces, lights, glossy_options);
                    std::fprintf(stderr, "  %.1f s, noise %.4f\n", coat.seconds, coat.noise);
                    hemi::render::LightmapFrame glossy_frame = frame;
                    glossy_frame.glossy_roughness = float(kGlossyRoughness[ri]);
                    glossy_frame.glossy_f0 = float(kGlossyF0);
                    for (size_t i = 0; i < std::size(kTechniques); ++i)
                    {
                        frame.technique = kTechniques[i].technique;
                        const hemi::io::ImageRgba diffuse = view.render(frame);
                        glossy_frame.technique = ggx[i];
                        const hemi::io::ImageRgba image = ggx_view.render(glossy_frame);
                        glossy[i].total[ri] = compare(image, coat);
                        // The two references share their diffuse paths: the specular's noise is what the coat
                        // adds to the reference's.
                        const double specular_noise = std::sqrt(
                            std::max(0.0, coat.noise * coat.noise - reference.noise * reference.noise));
                        glossy[i].specular[ri] =
                            specular_error(image, diffuse, coat.image, reference.image, specular_noise);
                        if (i == 1 && ri == 0)
                            hemi::io::write_png(fs::path(dir) / (stem + "_h6_ggx.png"), image,
                                                {exposure, hemi::io::ToneMap::Curve::Clamp});
                        if (i == 0)
                        {
                            glossy.back().total[ri] = compare(diffuse, coat);
                            // No specular, by the same measure (at least 1: RMS over mean).
                            glossy.back().specular[ri] =
                                specular_error(diffuse, diffuse, coat.image, reference.image, specular_noise);
                        }
                    }
                    if (ri == 0)
                        hemi::io::write_png(fs::path(dir) / (stem + "_reference_ggx.png"), coat.image,
                                            {exposure, hemi::io::ToneMap::Curve::Clamp});
                }
            }
            frame.technique = "sh9";
            frame.white = false;
            // Three dynamic objects, lit by the probes: one in the sun's patch, one in the shade, one by a
            // wall.
            frame.spheres = {
                {-1.2f, 0.4f, 0.45f, 0.45f}, {1.2f, 1.4f, 0.6f, 0.6f}, {2.9f, -2.4f, 1.4f, 0.4f}};
            hemi::io::write_png(fs::path(dir) / (stem + "_sh9_colour.png"), view.render(frame),
                                {exposure, hemi::io::ToneMap::Curve::Clamp});
            if (setup.sun && !ssbump_figure.empty())
            {
                // Green's room: the same lightmap's rnm colours, drawn with Listing 1 and the normal maps,
                // and with the reliefs baked into SSBump maps (directional occlusion) in the normal slots.
                hemi::io::LightmapAsset rnm = asset, ssbump = asset;
                rnm.outputs = {{"rnm", 3, hemi::bake::lightmap_maps("rnm", lightmap_atlas, sh)}};
                ssbump.outputs = rnm.outputs;
                const hemi::io::GltfScene ss_level =
                    hemi::samples::make_level(atlas, hemi::samples::LevelMaps::Ssbump);
                ssbump.images = ss_level.images;
                ssbump.materials = ss_level.materials;
                hemi::render::LightmapView rnm_view(device, rnm, {"rnm"}, w, h),
                    ss_view(device, ssbump, {"ssbump"}, w, h);
                hemi::render::LightmapFrame room;
                room.camera = frame.camera;
                room.technique = "rnm";
                const hemi::io::ImageRgba listing1 = rnm_view.render(room);
                room.technique = "ssbump";
                const hemi::io::ImageRgba self_shadowed = ss_view.render(room);
                hemi::io::write_png(fs::path(dir) / (stem + "_rnm.png"), listing1,
                                    {exposure, hemi::io::ToneMap::Curve::Clamp});
                hemi::io::write_png(fs::path(dir) / (stem + "_ssbump.png"), self_shadowed,
                                    {exposure, hemi::io::ToneMap::Curve::Clamp});
                hemi::samples::write_labeled_grid(
                    ssbump_figure, {half(listing1), half(self_shadowed)}, w / 2, h / 2,
                    {"radiosity normal mapping (Listing 1)", "self-shadowed bump maps (SSBump)"},
                    {"the rnm lightmap, sky and sun"}, exposure);
            }
            tiles.insert(tiles.end(), errors_row.begin(), errors_row.end());
            hemi::samples::write_labeled_grid(
                setup.figure, tiles, w / 2, h / 2, columns,
                {std::string(setup.name) + ": E / pi",
                 std::string(setup.name) + ": |error| x " + std::to_string(int(gain))},
                exposure);
        }
        write_plot(plot, setups);

        std::ostringstream md;
        md << "| technique |";
        for (const Setup& setup : setups)
            md << " " << setup.name << ": RMSE of E/π | noise removed | relative |";
        md << "\n|---|";
        for (size_t i = 0; i < setups.size(); ++i)
            md << "---|---|---|";
        md << "\n";
        for (size_t i = 0; i < std::size(kTechniques) + std::size(kNonNegative); ++i)
        {
            md << "| "
               << (i < std::size(kTechniques) ? kTechniques[i].label
                                              : kNonNegative[i - std::size(kTechniques)].label)
               << " |";
            for (const Setup& setup : setups)
            {
                char cell[128];
                const Error& e = setup.errors[i];
                std::snprintf(cell, sizeof cell, " %.4f | %.4f | %.1f%% |", e.rmse, e.corrected,
                              100.0 * e.relative);
                md << cell;
            }
            md << "\n";
        }
        char foot[512];
        std::snprintf(
            foot, sizeof foot,
            "\n%ux%u pixels (%zu compared), reference %d paths per pixel (noise %.4f with the sun, %.4f "
            "without), lightmap %ux%u at %d rays per texel, %d bounce(s).\n",
            w, h, setups[0].errors[0].pixels, reference_rays, setups[0].reference.noise,
            setups[1].reference.noise, atlas, atlas, rays, bounces);
        md << foot;
        hemi::io::write_text_atomically(table, md.str());
        if (!glossy_table.empty())
        {
            std::ostringstream g;
            g << "| technique, sky and sun |";
            for (const double r : kGlossyRoughness)
                g << " roughness " << r << ": total, relative | specular, relative |";
            g << "\n|---|---|---|---|---|---|---|\n";
            for (const GlossyRow& row : glossy)
            {
                g << "| " << row.label << " |";
                for (int ri = 0; ri < 3; ++ri)
                {
                    char cell[96];
                    std::snprintf(cell, sizeof cell, " %.1f%% | %.1f%% |", 100.0 * row.total[ri].relative,
                                  100.0 * row.specular[ri]);
                    g << cell;
                }
                g << "\n";
            }
            g << "\nA white GGX coat (f0 " << kGlossyF0
              << ") over the level, the lighting-only view (E / pi plus the coat's specular); \"total\" is "
                 "the "
                 "RMSE of the whole image (the glossy reference's noise removed) over its mean, \"specular\" "
                 "the "
                 "RMSE of the technique's specular (its coat minus its diffuse view) against the reference's "
                 "(the glossy reference minus the diffuse one, the same paths) over the reference specular's "
                 "mean.\n";
            hemi::io::write_text_atomically(glossy_table, g.str());
            std::printf("%s", g.str().c_str());
        }
        std::printf("%s", md.str().c_str());
        std::printf("wrote %s, %s, %s, %s and the single images in %s\n", figure.c_str(), sky_figure.c_str(),
                    plot.c_str(), table.c_str(), dir.c_str());
        return 0;
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "irradiance_normalmap: %s\n", e.what());
        return 1;
    }
}
