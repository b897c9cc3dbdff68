// light_probes: light probes that do not leak through walls (issue 44; docs/probes.md). Bakes the two rooms
// of two_rooms.h (a lit room open to the sky and sun beside a closed one, sealed or with a door) and their
// probes on an 8 x 4 x 4 grid, then draws what an object would receive at 0.7 m above the floor, seen from
// above: the trilinear lookup alone, the lookup weighted by each probe's visibility (its depth map), and a
// probe baked at every pixel. Also a plot of the light along a walk through the door and a Markdown table of
// the figures. And a reflection probe (box_room.h) seen from a point 1.8 m off its centre: what the path
// tracer sees there, the probe looked up box-projected, and the probe looked up as if infinitely far.
// Headless, writes PNGs.
//   light_probes [-o MAPS.png] [--plot DOOR.png] [--reflection VIEWS.png] [--table TABLE.md]
//                [--pixels-per-metre N]
#include "box_room.h"
#include "figure.h"
#include "two_rooms.h"

#include <hemi/bake/gnuplot.h>
#include <hemi/bake/reference.h>
#include <hemi/bake/reflection_probe.h>
#include <hemi/io/image.h>
#include <hemi/math/box_projection.h>
#include <hemi/math/camera.h>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace
{

using hemi::io::LightProbes;
using hemi::samples::received_light;
using hemi::samples::TwoRooms;

constexpr float kHeight = 0.7f;            // the maps' and the walk's height above the floor
constexpr float kX0 = -2.05f, kX1 = 2.05f; // the two rooms along x; y in [0, 2]

// What an object at each pixel's centre receives (the SH9's constant term's luminance), x to the right, y up
// the image; black inside the shared wall.
template <typename Light> hemi::io::ImageRgba light_map(uint32_t w, uint32_t h, const Light& light)
{
    hemi::io::ImageRgba img{w, h, std::vector<float>(size_t(w) * h * 4, 1.0f)};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const glm::vec3 p(kX0 + (kX1 - kX0) * (float(x) + 0.5f) / float(w),
                              2.0f * (1.0f - (float(y) + 0.5f) / float(h)), kHeight);
            const float v = std::abs(p.x) < 0.05f ? 0.0f : float(light(p, size_t(y) * w + x));
            float* px = img.pixels.data() + (size_t(y) * w + x) * 4;
            px[0] = px[1] = px[2] = v;
        }
    return img;
}

struct Walk
{
    std::vector<double> reference, lookup, trilinear;
    double reference_step = 0, lookup_step = 0, trilinear_step = 0, error = 0, trilinear_error = 0;
};

// The test's walk (tests/bake/light_probes_test.cpp): diagonally through the door, 2 m in 1 cm steps.
Walk walk(const TwoRooms& rooms, const LightProbes& probes)
{
    const LightProbes blind = hemi::samples::without_visibility(probes);
    const glm::vec3 from(-0.7071f, 0.2929f, kHeight), to(0.7071f, 1.7071f, kHeight);
    Walk w;
    constexpr int kPoints = 201;
    for (int i = 0; i < kPoints; ++i)
    {
        const glm::vec3 p = from + (to - from) * (float(i) / float(kPoints - 1));
        w.reference.push_back(received_light(rooms.probes(glm::uvec3(1), p, p, 4096, 0).irradiance[0]));
        w.lookup.push_back(received_light(probes.at(p)));
        w.trilinear.push_back(received_light(blind.at(p)));
        w.error += std::abs(w.lookup.back() - w.reference.back()) / kPoints;
        w.trilinear_error += std::abs(w.trilinear.back() - w.reference.back()) / kPoints;
        if (i == 0)
            continue;
        const size_t j = size_t(i);
        w.reference_step = std::max(w.reference_step, std::abs(w.reference[j] - w.reference[j - 1]));
        w.lookup_step = std::max(w.lookup_step, std::abs(w.lookup[j] - w.lookup[j - 1]));
        w.trilinear_step = std::max(w.trilinear_step, std::abs(w.trilinear[j] - w.trilinear[j - 1]));
    }
    return w;
}

void write_plot(const std::filesystem::path& path, const Walk& w)
{
    hemi::bake::run_gnuplot(
        path,
        [&](const std::filesystem::path& folder, std::ostream& script, const std::filesystem::path& output)
        {
            {
                std::ofstream data(folder / "walk.dat");
                for (size_t i = 0; i < w.reference.size(); ++i)
                    data << 0.01 * double(i) << ' ' << w.reference[i] << ' ' << w.lookup[i] << ' '
                         << w.trilinear[i] << '\n';
            }
            const std::string d = "'" + (folder / "walk.dat").string() + "'";
            script << "set terminal pngcairo size 760,420 noenhanced font 'Sans,11'\n"
                   << "set output '" << output.string() << "'\n"
                   << "set title 'Walking through the door from the sky-lit room into the other, 0.7 m up'\n"
                   << "set xlabel 'metres along the walk (the door at 1.0)'\n"
                   << "set ylabel 'light received (SH9 constant term, luminance)'\n"
                   << "set grid\nset key top right\nset yrange [0:*]\n"
                   << "plot " << d
                   << " using 1:2 with lines lw 3 lc rgb '#999999' title 'probe baked at each point', " << d
                   << " using 1:4 with lines lw 2 dt 2 lc rgb '#d95f02' title 'trilinear lookup', " << d
                   << " using 1:3 with lines lw 2 lc rgb '#1b9e77' title 'lookup with visibility'\n";
        });
}

// The reflection figure: from the test's off-centre point (ReflectionProbe.ABoxProjectedLookupOffCentre...)
// a 100-degree view towards the blue wall and the panel, three ways; their RMS against the tracer (of the
// tracer's mean) goes into `md`.
void reflection_figure(const std::string& path, std::string& md)
{
    const hemi::samples::BoxRoom room;
    const glm::vec3 centre(0.3f, -0.2f, 1.2f), p(-1.2f, 0.7f, 0.6f);
    hemi::bake::ReflectionProbeOptions o;
    o.size = 128;
    o.rays = 16;
    const hemi::io::EnvmapAsset probe = hemi::bake::bake_reflection_probe(
        room.mesh, room.atlas, room.sh, room.lights, &room.surfaces, centre, o);
    constexpr uint32_t kSize = 200;
    hemi::bake::ReferenceOptions r;
    r.width = r.height = kSize;
    r.auto_camera = false;
    r.camera = {p, glm::vec3(2.0f, -0.4f, 1.6f), 100.0f};
    r.model = glm::mat4(1.0f);
    r.rays = 256;
    r.bounces = 2;
    const hemi::bake::ReferenceImage traced =
        hemi::bake::render_reference(room.mesh, room.surfaces, room.lights, r);
    const glm::mat4 inverse = glm::inverse(hemi::math::camera_ray_matrix(r.camera, 1.0f));
    hemi::io::ImageRgba projected{kSize, kSize, std::vector<float>(size_t(kSize) * kSize * 4, 1.0f)},
        infinite = projected, reference = projected;
    double mean = 0.0, error[2] = {0.0, 0.0};
    for (uint32_t y = 0; y < kSize; ++y)
        for (uint32_t x = 0; x < kSize; ++x)
        {
            const glm::vec2 ndc((x + 0.5f) / kSize * 2.0f - 1.0f, (y + 0.5f) / kSize * 2.0f - 1.0f);
            const glm::vec4 n = inverse * glm::vec4(ndc, 0.0f, 1.0f),
                            f = inverse * glm::vec4(ndc, 1.0f, 1.0f);
            const glm::vec3 d = glm::normalize(glm::vec3(f) / f.w - glm::vec3(n) / n.w);
            const glm::vec3 looked[2] = {
                glm::vec3(probe.mirror[0].sample(glm::dvec3(hemi::math::box_projected_direction(
                    p, d, hemi::samples::kBoxRoomMin, hemi::samples::kBoxRoomMax, centre)))),
                glm::vec3(probe.mirror[0].sample(glm::dvec3(d)))};
            const size_t i = (size_t(y) * kSize + x) * 4;
            const float* t = traced.image.at(x, y);
            for (int c = 0; c < 3; ++c)
            {
                reference.pixels[i + size_t(c)] = t[c];
                projected.pixels[i + size_t(c)] = looked[0][c];
                infinite.pixels[i + size_t(c)] = looked[1][c];
                mean += t[c];
                for (int k = 0; k < 2; ++k)
                    error[k] += (looked[k][c] - t[c]) * (looked[k][c] - t[c]);
            }
        }
    const double n = 3.0 * kSize * kSize;
    mean /= n;
    char row[400];
    std::snprintf(
        row, sizeof row,
        "\nThe reflection probe 1.8 m off its centre (a 100-degree view, %u^2, %d paths a pixel): "
        "box-projected %.1f%% RMS of the tracer's mean, without the projection %.1f%%; the tracer's own "
        "noise %.1f%%.\n",
        kSize, r.rays, 100.0 * std::sqrt(error[0] / n) / mean, 100.0 * std::sqrt(error[1] / n) / mean,
        100.0 * traced.noise / mean);
    md += row;
    hemi::samples::write_labeled_grid(
        path, {reference, projected, infinite}, kSize, kSize,
        {"path traced at the point", "probe, box-projected", "probe, no projection"}, {""}, 0.45f);
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"light_probes: probes that do not leak through walls, beside trilinear interpolation"};
    std::string maps = "light_probes.png", plot = "light_probes_door.png",
                reflection = "light_probes_reflection.png", table;
    uint32_t per_metre = 60;
    app.add_option("-o,--output", maps,
                   "the maps: rows sealed and door, columns trilinear, visibility, "
                   "reference")
        ->capture_default_str();
    app.add_option("--plot", plot, "the walk through the door (gnuplot; empty: none)")->capture_default_str();
    app.add_option(
           "--reflection", reflection,
           "a reflection probe seen 1.8 m off its centre: traced, box-projected, not projected (empty: "
           "none)")
        ->capture_default_str();
    app.add_option("--table", table, "the figures as a Markdown table (empty: none)");
    app.add_option("--pixels-per-metre", per_metre, "the maps' resolution")
        ->check(CLI::Range(4u, 400u))
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    try
    {
        const auto start = std::chrono::steady_clock::now();
        const uint32_t w = uint32_t(std::lround((kX1 - kX0) * float(per_metre))), h = 2 * per_metre;
        std::vector<hemi::io::ImageRgba> tiles;
        std::string md =
            "| scene | lookup | largest share of the lit side's light at a mirrored point in the "
            "dark room | mean error against the reference over the map |\n| --- | --- | --- | --- |\n";
        Walk door_walk;
        for (const bool door : {false, true})
        {
            const TwoRooms rooms(door, true);
            const LightProbes probes = rooms.grid(glm::uvec3(8, 4, 4), 1024);
            const LightProbes blind = hemi::samples::without_visibility(probes);
            // The reference: a probe baked at every pixel (256 rays).
            const glm::vec2 half(0.5f * (kX1 - kX0) / float(w), 1.0f / float(h));
            const LightProbes exact =
                rooms.probes(glm::uvec3(w, h, 1), glm::vec3(kX0 + half.x, half.y, kHeight),
                             glm::vec3(kX1 - half.x, 2.0f - half.y, kHeight), 256, 0);
            auto reference = [&](const glm::vec3&, size_t i)
            {
                const uint32_t x = uint32_t(i % w), y = uint32_t(i / w);
                return received_light(exact.irradiance[x + size_t(w) * (h - 1 - y)]);
            };
            const hemi::io::ImageRgba ref = light_map(w, h, reference);
            double error[2] = {0, 0}, leak[2] = {0, 0};
            int n = 0;
            for (int which = 0; which < 2; ++which)
            {
                const LightProbes& p = which == 0 ? blind : probes;
                tiles.push_back(
                    light_map(w, h, [&](const glm::vec3& q, size_t) { return received_light(p.at(q)); }));
                for (size_t i = 0; i < size_t(w) * h; ++i)
                    error[which] += std::abs(tiles.back().pixels[i * 4] - ref.pixels[i * 4]);
                for (const float x : {0.1f, 0.2f, 0.3f})
                    for (const float y : {0.3f, 1.0f, 1.7f})
                        for (const float z : {0.3f, 1.0f, 1.7f})
                            leak[which] =
                                std::max(leak[which], received_light(p.at(glm::vec3(x, y, z))) /
                                                          received_light(p.at(glm::vec3(-x, y, z))));
                n = int(w * h);
            }
            tiles.push_back(ref);
            for (int which = 0; which < 2; ++which)
            {
                char row[256], share[32] = "(the door lets light in)";
                if (!door)
                    std::snprintf(share, sizeof share, "%.3g", leak[which]);
                std::snprintf(row, sizeof row, "| %s | %s | %s | %.3f |\n", door ? "with a door" : "sealed",
                              which == 0 ? "trilinear" : "visibility", share, error[which] / n);
                md += row;
            }
        }
        {
            // The walk as the test takes it: the door, no sun (whose shadow edge would be a step of its own),
            // probes 0.4 m apart along y so that those behind the jambs drop out as the walk passes them.
            const TwoRooms rooms(true, false);
            door_walk = walk(rooms, rooms.grid(glm::uvec3(8, 5, 4), 1024));
        }
        char row[512];
        std::snprintf(
            row, sizeof row,
            "\nThe walk through the door (201 points 1 cm apart): largest step %.4f with visibility, %.4f "
            "trilinear alone, %.4f for probes baked at each point; mean error %.4f and %.4f.\n",
            door_walk.lookup_step, door_walk.trilinear_step, door_walk.reference_step, door_walk.error,
            door_walk.trilinear_error);
        md += row;
        hemi::samples::write_labeled_grid(maps, tiles, w, h,
                                          {"trilinear", "visibility (depth maps)", "probe at every pixel"},
                                          {"sealed", "door"}, 0.15f);
        if (!plot.empty())
            write_plot(plot, door_walk);
        if (!reflection.empty())
            reflection_figure(reflection, md);
        if (!table.empty())
            std::ofstream(table) << md;
        std::printf("%s", md.c_str());
        std::printf("wrote %s%s%s%s%s in %.1f s\n", maps.c_str(), plot.empty() ? "" : ", ", plot.c_str(),
                    reflection.empty() ? "" : ", ", reflection.c_str(),
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        return 0;
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "light_probes: %s\n", e.what());
        return 1;
    }
}
