// prt_normalmap: Sloan 2006's comparison (its Figures 1 and 3), re-made with hemi. Two models are written
// as glTF, baked with hemi-bake's code path (interreflected transfer, CPCA 1x24 on the complex one), and
// rendered under the analytic sky with every technique: classic PRT (no normal map), the SH9 gold standard,
// the separable basis, HL2, SAL, H4, H6, and the gold standard through CPCA. Writes one comparison image
// (rows: models; columns: techniques) and a table of each technique's error against the gold standard, and a
// second image of the complex object's lighting with each transfer kind (unshadowed, shadowed, 1 and 2
// bounces).
#include "figure.h"
#include "models.h"

#include <hemi/bake/gnuplot.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/gpu/device.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>
#include <hemi/render/view/prt_view.h>

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace
{

struct Column
{
    const char* technique;
    bool cpca;
    const char* label;
};
const Column kColumns[] = {
    {"prt", false, "classic PRT"}, {"gs", false, "SH9 (gold standard)"},
    {"sep4", false, "separable"},  {"hl2", false, "HL2"},
    {"sal4", false, "SAL"},        {"h4", false, "H4"},
    {"h6", false, "H6"},           {"gs", true, "SH9 + CPCA 1x24"},
};

struct Error
{
    double rmse = 0.0, psnr = 0.0; // RMSE of linear radiance; PSNR of the displayed sRGB values (peak 1)
};

Error compare(const hemi::io::ImageRgba& image, const hemi::io::ImageRgba& reference, float exposure)
{
    double linear = 0.0, display = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < image.pixels.size(); i += 4)
    {
        if (reference.pixels[i + 3] < 0.5f)
            continue;
        for (int c = 0; c < 3; ++c)
        {
            const double d = image.pixels[i + c] - reference.pixels[i + c];
            linear += d * d;
            auto shown = [&](float v) { return hemi::io::srgb_oetf(std::clamp(v * exposure, 0.0f, 1.0f)); };
            const double s = shown(image.pixels[i + c]) - shown(reference.pixels[i + c]);
            display += s * s;
        }
        count += 3;
    }
    Error e;
    e.rmse = std::sqrt(linear / double(std::max<size_t>(count, 1)));
    const double mse = display / double(std::max<size_t>(count, 1));
    e.psnr = mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : INFINITY;
    return e;
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"prt_normalmap: Sloan 2006's technique comparison, baked and rendered with hemi"};
    std::string out_dir = "prt_normalmap", image_path = "prt_normalmap.png", table_path = "prt_normalmap.md",
                kinds_path = "prt_transfer_kinds.png";
    int rays = 256, tile = 180;
    float detail = 1.0f, exposure = 0.6f, rotate = 30.0f;
    app.add_option("--dir", out_dir, "folder for the models, textures and baked assets")
        ->capture_default_str();
    app.add_option("-o,--output", image_path, "comparison image (PNG)")->capture_default_str();
    app.add_option("--table", table_path, "error table (Markdown)")->capture_default_str();
    app.add_option("--kinds", kinds_path, "transfer-kinds figure (PNG; empty: skip)")->capture_default_str();
    app.add_option("--rays", rays, "rays per vertex of the bakes")->capture_default_str();
    app.add_option("--tile", tile, "pixel size of each square tile")->capture_default_str();
    app.add_option("--detail", detail, "tessellation scale of the models (1: 703 and 29,197 vertices)")
        ->capture_default_str();
    app.add_option("--rotate", rotate, "environment turn about the up axis, degrees")->capture_default_str();
    app.add_option("--exposure", exposure, "exposure of the PNG")->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    try
    {
        hemi::gpu::Device device;
        const uint32_t t = uint32_t(tile), columns = uint32_t(std::size(kColumns));
        std::vector<hemi::io::ImageRgba> tiles;
        std::ostringstream table;
        table << "| model | vertices | technique | RMSE (linear) | PSNR (dB, sRGB) |\n| --- | ---: | --- | "
                 "---: | ---: |\n";
        std::vector<std::string> row_labels, column_labels;
        for (const Column& c : kColumns)
            column_labels.push_back(c.label);
        for (auto [model, name] : {std::pair{hemi::samples::PrtModel::Simple, "simple"},
                                   std::pair{hemi::samples::PrtModel::Complex, "complex"}})
        {
            const auto gltf = hemi::samples::write_prt_model(out_dir, name, model, detail);
            const auto asset_path = std::filesystem::path(out_dir) / (std::string(name) + ".hemi");
            hemi::bake::PrtAssetOptions options;
            options.bake.rays = rays;
            options.cpca_clusters = 1;
            options.cpca_vectors = 24;
            std::fprintf(stderr, "baking %s ...\n", gltf.c_str());
            const hemi::bake::PrtBakeSummary s = hemi::bake::bake_prt_file(gltf, asset_path, options);
            std::printf("%s: %u vertices, %.2f Mrays/s, bake %.1f s\n", name, s.vertices,
                        s.rays_per_second() * 1e-6, s.total_seconds);
            const hemi::io::PrtAsset asset = hemi::io::read_prt_asset(asset_path);
            row_labels.push_back(std::string(name) + ", " + std::to_string(s.vertices) + " vertices");
            hemi::render::PrtFrame frame;
            frame.world_lighting = hemi::render::environment_lighting("sky", int(asset.order));
            frame.rotate_degrees = rotate;
            frame.camera = hemi::render::auto_camera(asset.mesh, frame.model, 1.0f);
            std::vector<hemi::io::ImageRgba> images;
            for (const Column& c : kColumns)
            {
                hemi::render::PrtView view(device, asset, c.technique, c.cpca, t, t);
                images.push_back(view.render(frame));
            }
            const hemi::io::ImageRgba& gold = images[1];
            tiles.insert(tiles.end(), images.begin(), images.end());
            for (uint32_t col = 0; col < columns; ++col)
            {
                if (col == 1)
                    continue;
                const Error e = compare(images[col], gold, exposure);
                char line[256];
                std::snprintf(line, sizeof line, "| %s | %u | %s | %.4f | %.1f |\n", name, s.vertices,
                              kColumns[col].label, e.rmse, e.psnr);
                table << line;
            }
        }
        hemi::samples::write_labeled_grid(image_path, tiles, t, t, column_labels, row_labels, exposure);

        // The transfer kinds on the complex object, lighting only (albedo 1), SH9 under the sky: what
        // shadowing and each bounce of interreflection add.
        if (!kinds_path.empty())
        {
            const auto gltf = std::filesystem::path(out_dir) / "complex.gltf";
            std::vector<hemi::io::ImageRgba> kinds;
            const uint32_t kt = std::max(t, 320u);
            const std::vector<std::pair<hemi::bake::TransferKind, int>> settings = {
                {hemi::bake::TransferKind::Unshadowed, 0},
                {hemi::bake::TransferKind::Shadowed, 0},
                {hemi::bake::TransferKind::Interreflected, 1},
                {hemi::bake::TransferKind::Interreflected, 2}};
            for (const auto& [kind, bounces] : settings)
            {
                hemi::bake::PrtAssetOptions options;
                options.bake.rays = rays;
                options.bake.kind = kind;
                options.bake.bounces = bounces;
                options.techniques = {"gs"};
                const auto asset_path = std::filesystem::path(out_dir) / "complex_kind.hemi";
                std::fprintf(stderr, "baking %s (%s, %d bounces) ...\n", gltf.c_str(),
                             std::string(hemi::bake::to_string(kind)).c_str(), bounces);
                hemi::bake::bake_prt_file(gltf, asset_path, options);
                const hemi::io::PrtAsset asset = hemi::io::read_prt_asset(asset_path);
                hemi::render::PrtView view(device, asset, "gs", false, kt, kt);
                hemi::render::PrtFrame frame;
                frame.world_lighting = hemi::render::environment_lighting("sky", int(asset.order));
                frame.rotate_degrees = rotate;
                frame.white = true;
                frame.camera = hemi::render::auto_camera(asset.mesh, frame.model, 1.0f);
                kinds.push_back(view.render(frame));
            }
            hemi::samples::write_labeled_grid(kinds_path, kinds, kt, kt,
                                              {"unshadowed", "shadowed", "+ 1 bounce", "+ 2 bounces"},
                                              {"lighting only (albedo 1), SH9"}, exposure * 0.7f);
            std::printf("wrote %s\n", kinds_path.c_str());
        }
        const std::string text = table.str();
        hemi::io::write_atomically(table_path,
                                   [&](const std::filesystem::path& tmp)
                                   {
                                       std::ofstream f(tmp);
                                       f << text;
                                       f.close();
                                       if (f.fail())
                                           throw hemi::io::FormatError(table_path + ": cannot write");
                                   });
        std::printf("%s\ncolumns: ", text.c_str());
        for (const Column& c : kColumns)
            std::printf("%s%s", c.label, &c == &kColumns[columns - 1] ? "\n" : " | ");
        std::printf("wrote %s and %s\n", image_path.c_str(), table_path.c_str());
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "prt_normalmap: %s\n", e.what());
        return 1;
    }
    return 0;
}
