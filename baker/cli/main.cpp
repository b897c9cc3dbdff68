// hemi-bake: the offline side of hemi as a command line. Subcommands (hemi-bake SUBCOMMAND --help for
// every option):
//   basis-report [--json FILE] [--plot FILE.png] [--signals N] [--seed S]
//   prt SCENE.gltf|.glb -o ASSET.hemi [--bases ...] [--transfer ...] [--bounces B] [--order N]
//       [--rays R] [--seed S] [--albedo A] [--cpca CxV] [--json REPORT.json]
//   ssbump HEIGHT.png|.exr -o OUT.png [--scale S] [--channel r|g|b|a|grey] [--rays R]
//       [--filter RADIUS,SIGMA] [--no-occlusion] [--no-wrap] [--convention normalized|valve]
//       [--exr OUT.exr] [--json REPORT.json]
//   ssbump --from-normal NORMAL.png -o OUT.png;  ssbump --to-normal SSBUMP.png -o NORMAL.png
//   lightmap SCENE.gltf|.glb -o LEVEL.hemi [--unwrap] [--strict-uv] [--uv-report FILE.png] [--env
//   uniform|FILE.exr] [--env-scale X]
//       [--sun X,Y,Z,R,G,B[,DIAMETER]] [--bounces B] [--bases sh9,hl2,h4,h6,sal4,plain,rnm]
//       [--size WxH | --texel-size S] [--rays R] [--seed S] [--probes NX,NY,NZ|auto:N|file:PATH|gltf]
//       [--probe-rays R]
//       [--probe-depth R] [--reflection-probe X,Y,Z[,BOX]]... [--reflection-size N]
//       [--exr-dir DIR] [--json REPORT.json]
//   brdf --model torrance-sparrow|banks|phong|blinn-phong|cosine-lobe [--ior N] [--roughness R]
//       [--exponent E] [--distribution beckmann|gaussian] [--size N] [--8bit] -o BRDF.exr
//       [--json REPORT.json]
//   envmap ENV.exr -o ENVMAP.hemi [--size N] [--exponents E1,E2,...] [--ior N1,...] [--exr-dir DIR]
//       [--report REPORT.json]
//   reference SCENE.gltf|.glb -o REF.exr [the lightmap's light options] [--bounces B]
//       [--camera auto|EYE,TARGET] [--size WxH] [--white] [--roughness R] [--f0 F] [--rays R] [--seed S]
//       [--json REPORT.json]
//   export LEVEL.hemi -o LEVEL_LIT.glb|.gltf [--outputs all|none|NAME,...] [--rgbm-range R]
// Every error names the file or option it is about and exits 1 (usage errors too); outputs are checked
// (writable, regular files, none of them an input) before any work starts (tool_options.h).
// `mpirun -np N hemi-bake lightmap|prt|ssbump ...` shares the bake among N processes (mpi_distribution.h,
// docs/distributed.md); rank 0 writes the outputs, the same bytes as one process.
#include <hemi/bake/basis_report.h>
#include <hemi/bake/checkpoint.h>
#include <hemi/bake/factored.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/probe_placement.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/bake/reference.h>
#include <hemi/bake/ssbump.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_gltf.h>
#include <hemi/io/memory.h>
#include <hemi/math/camera.h>
#include <hemi/math/paraboloid.h>
#include <hemi/math/sh_environment.h>

#include <nlohmann/json.hpp>

#include "mpi_distribution.h"
#include "tool_options.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <unistd.h>
#include <vector>

namespace
{
const char* kRows[9] = {"y0,0", "y1,-1", "y1,0", "y1,1", "y2,-2", "y2,-1", "y2,0", "y2,1", "y2,2"};

void print_report(const hemi::bake::BasisReport& r)
{
    std::printf(
        "Projection matrices from SH9 irradiance (hemispherical least squares), rows = basis functions\n");
    for (const auto& [name, rows] : r.projection)
    {
        std::printf("  %s\n", name.c_str());
        for (const auto& row : rows)
        {
            std::printf("    ");
            for (double v : row)
                std::printf("%10.6f", std::abs(v) < 5e-7 ? 0.0 : v); // no "-0.000000" from quadrature noise
            std::printf("\n");
        }
    }
    std::printf("\nSloan 2006 Table 2: integrated squared error of projecting each SH9 function\n      ");
    for (const char* c : kRows)
        std::printf("%9s", c);
    std::printf("\n");
    for (const auto& [name, values] : r.sloan_table2)
    {
        std::printf("  %-4s", name.c_str());
        for (double v : values)
            std::printf("%9.2e", std::abs(v) < 1e-12 ? 0.0 : v);
        std::printf("\n");
    }
    std::printf("\nSeparable basis singular values (A, then A with the cosine convolution folded in)\n  ");
    for (double v : r.svd_singular_values)
        std::printf("%9.4f", v);
    std::printf("\n  ");
    for (double v : r.svd_singular_values_convolved)
        std::printf("%9.4f", v);
    std::printf("\n\nIMSE of %d random irradiance signals (seed %llu)\n  %-9s %6s %12s %10s\n", r.signals,
                (unsigned long long)r.seed, "basis", "coeffs", "mean IMSE", "rel RMS");
    for (const auto& [name, st] : r.imse)
        std::printf("  %-9s %6d %12.5f %10.4f\n", name.c_str(), st.coefficients, st.mean_imse, st.rel_rms);
}
// Progress on stderr: one line rewritten in place on a terminal (a line per 10% in a log), with the ETA,
// and a checkpoint failure reported when it happens, not after the bake (the user may want to free space
// and restart).
class ProgressLine
{
  public:
    explicit ProgressLine(std::string tool) : tool_(std::move(tool)) {}

    void checkpoint_error(const std::string& error)
    {
        if (error.empty() || checkpoint_reported_)
            return;
        std::fprintf(stderr, "%s%s: warning: checkpoints stopped: %s\n", tty_ ? "\n" : "", tool_.c_str(),
                     error.c_str());
        checkpoint_reported_ = true;
    }
    void update(double fraction, const std::string& what, bool done)
    {
        using clock = std::chrono::steady_clock;
        const double elapsed = std::chrono::duration<double>(clock::now() - start_).count();
        char eta[32] = "";
        if (fraction > 0.02 && fraction < 1.0)
            std::snprintf(eta, sizeof eta, ", ETA %.0f s", elapsed * (1.0 - fraction) / fraction);
        const int decile = int(fraction * 10.0);
        if (!tty_ && decile == last_decile_ && !done)
            return;
        last_decile_ = decile;
        hemi::tool::set_stage(what);
        std::fprintf(stderr, "%s%s: %s %5.1f%%%s%s", tty_ ? "\r" : "", tool_.c_str(), what.c_str(),
                     100.0 * fraction, eta, tty_ ? "      " : "\n");
        if (done && tty_)
            std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }
    bool checkpoint_reported() const { return checkpoint_reported_; }

  private:
    std::string tool_;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
    bool tty_ = isatty(fileno(stderr)) != 0;
    int last_decile_ = -1;
    bool checkpoint_reported_ = false;
};

// The PRT bake's progress: over all passes.
struct PrtProgressLine
{
    ProgressLine line{"hemi-bake prt"};
    void operator()(const hemi::bake::PrtBakeProgress& p)
    {
        line.checkpoint_error(p.checkpoint_error);
        const double fraction =
            (p.pass + (p.vertex_count ? double(p.vertices_done) / double(p.vertex_count) : 1.0)) / p.passes;
        const std::string what =
            "pass " + std::to_string(p.pass + 1) + "/" + std::to_string(p.passes) + " (" +
            (p.pass == 0 ? std::string("visibility") : "bounce " + std::to_string(p.pass)) + ")";
        line.update(fraction, what, p.pass + 1 == p.passes && p.vertices_done == p.vertex_count);
    }
};

void print_prt_summary(const hemi::bake::PrtBakeSummary& s, const hemi::bake::PrtAssetOptions& o,
                       const std::string& scene, const std::string& asset)
{
    for (const std::string& w : s.warnings)
        std::fprintf(stderr, "hemi-bake: warning: %s: %s\n", scene.c_str(), w.c_str());
    std::printf("baked %s: %u vertices, %u triangles, %s transfer, order %d (L = %d)", asset.c_str(),
                s.vertices, s.triangles, std::string(hemi::bake::to_string(o.bake.kind)).c_str(),
                o.bake.order, o.bake.order * o.bake.order);
    if (o.bake.kind != hemi::bake::TransferKind::Unshadowed)
        std::printf(", %d rays per vertex", o.bake.rays);
    if (o.bake.kind == hemi::bake::TransferKind::Interreflected)
        std::printf(", %d bounces, albedo %.2f", o.bake.bounces, o.bake.albedo);
    std::printf("\n");
    std::printf("surfaces: %zu material(s), %zu primitive(s), %zu image(s) embedded in the asset\n",
                s.materials, s.primitives, s.images);
    if (s.tangents_generated)
        std::printf("tangents were generated from the UV layout (the scene has none)\n");
    if (s.resumed)
        std::printf("resumed from a checkpoint at pass %d, vertex %u\n", s.resumed_pass + 1,
                    s.resumed_vertex);
    if (!s.checkpoint_error.empty())
        std::fprintf(stderr, "hemi-bake prt: warning: checkpoints stopped: %s\n", s.checkpoint_error.c_str());
    std::printf("rays: %llu in %.2f s = %.2f Mrays/s; total %.2f s\n", (unsigned long long)s.rays,
                s.trace_seconds, s.rays_per_second() * 1e-6, s.total_seconds);
    std::printf("  %-6s %3s %12s", "tech", "K", "dense MB");
    if (o.cpca_clusters)
        std::printf(" %10s %12s %12s", "CPCA MB", "CPCA RMS", "relative");
    std::printf("\n");
    for (const auto& t : s.techniques)
    {
        std::printf("  %-6s %3d %12.2f", t.name.c_str(), t.k, double(t.dense_bytes) / 1048576.0);
        if (o.cpca_clusters)
            std::printf(" %10.2f %12.3e %12.3e", double(t.cpca_bytes) / 1048576.0, t.cpca_rms,
                        t.cpca_relative);
        std::printf("\n");
    }
}

struct SsbumpCli
{
    std::string input, output, from_normal, to_normal, exr, json, channel = "grey", filter,
                                                                  convention = "normalized";
    hemi::bake::SsbumpOptions options;
    bool no_occlusion = false, no_wrap = false;
};

void write_ssbump_png(const std::string& path, const hemi::bake::SsbumpMap& m, std::span<const uint8_t> alpha,
                      bool normals)
{
    hemi::io::ImageRgba8 image{m.width, m.height,
                               hemi::bake::ssbump_rgba8(normals ? m.normals : m.weights, alpha, normals)};
    hemi::io::write_png(path, image);
}

int run_ssbump(SsbumpCli& c)
{
    namespace bake = hemi::bake;
    const int modes = int(!c.input.empty()) + int(!c.from_normal.empty()) + int(!c.to_normal.empty());
    if (modes != 1)
        throw std::invalid_argument("give one of HEIGHT (a height map to bake), --from-normal NORMAL.png or "
                                    "--to-normal SSBUMP.png");
    const bake::SsbumpConvention convention = bake::parse_ssbump_convention(c.convention);
    hemi::tool::Files files;
    files.input("HEIGHT", c.input);
    files.input("--from-normal", c.from_normal);
    files.input("--to-normal", c.to_normal);
    files.output("-o", c.output);
    files.output("--exr", c.exr);
    files.output("--json", c.json);
    if (!c.input.empty())
        files.output("its checkpoint", bake::checkpoint_path(c.output));
    // Under mpirun only the bake is shared; rank 0 checks, converts and writes.
    const bool leader = !c.options.distribution || c.options.distribution->leader();
    if (leader)
        files.check();
    else if (!c.to_normal.empty() || !c.from_normal.empty())
        return 0;
    if (!c.to_normal.empty())
    {
        // The way back: a tangent-space ("bent") normal from each texel's weights.
        const hemi::io::DataImage image = hemi::io::read_data_image(c.to_normal);
        if (image.bits == 32 || image.channels < 3)
            throw hemi::io::FormatError(c.to_normal + ": an SSBump map is an RGB(A) PNG");
        bake::SsbumpMap m;
        m.width = image.width;
        m.height = image.height;
        std::vector<uint8_t> alpha;
        for (size_t i = 0; i < size_t(image.width) * image.height; ++i)
        {
            m.normals.push_back(bake::ssbump_normal(
                glm::vec3(image.rgba(i, 0), image.rgba(i, 1), image.rgba(i, 2)), convention));
            if (image.channels == 4)
                alpha.push_back(uint8_t(std::lround(image.rgba(i, 3) * 255.0f)));
        }
        write_ssbump_png(c.output, m, alpha, true);
        std::printf("wrote %s: %ux%u tangent-space normals from %s weights\n", c.output.c_str(), m.width,
                    m.height, std::string(to_string(convention)).c_str());
        return 0;
    }
    if (!c.from_normal.empty())
    {
        uint32_t w = 0, h = 0;
        std::vector<uint8_t> alpha;
        size_t zeros = 0;
        const std::vector<glm::vec3> normals = bake::read_normal_map(c.from_normal, w, h, alpha, &zeros);
        if (zeros)
            std::fprintf(
                stderr, "hemi-bake ssbump: warning: %s: %zu texel(s) hold a zero vector; read as (0, 0, 1)\n",
                c.from_normal.c_str(), zeros);
        const bake::SsbumpMap m = bake::ssbump_from_normals(w, h, normals, convention);
        write_ssbump_png(c.output, m, alpha, false);
        if (!c.exr.empty())
        {
            hemi::io::ImageRgba img{w, h, {}};
            for (const glm::vec3& v : m.weights)
                img.pixels.insert(img.pixels.end(), {v.x, v.y, v.z, 1.0f});
            hemi::io::write_exr(c.exr, img);
        }
        std::printf("wrote %s: %ux%u SSBump weights (%s, no occlusion) from a normal map\n", c.output.c_str(),
                    w, h, std::string(to_string(convention)).c_str());
        return 0;
    }

    bake::SsbumpOptions& o = c.options;
    o.convention = convention;
    o.occlusion = !c.no_occlusion;
    o.wrap = !c.no_wrap;
    const bool filter_given = !c.filter.empty();
    if (filter_given)
    {
        const std::vector<double> v = hemi::tool::parse_numbers(
            c.filter, "--filter", "RADIUS,SIGMA (e.g. 2,0.02) or 0 for none", {1, 2});
        if ((v.size() == 1 && v[0] != 0.0) || v[0] != std::floor(v[0]) || std::abs(v[0]) > 1e6)
            throw std::invalid_argument("--filter expects RADIUS,SIGMA (e.g. 2,0.02) or 0 for none, got '" +
                                        c.filter + "' (the radius is a whole number of texels)");
        o.filter = {int(v[0]), v.size() == 2 ? float(v[1]) : 0.0f};
    }
    bake::check_ssbump_options(o); // before the map is read: a bad option fails at once
    o.checkpoint = bake::checkpoint_path(c.output);
    std::optional<hemi::io::OutputLock> lock; // one job per output (and its checkpoint): on the leader
    if (leader)
        lock.emplace(c.output);
    // The map's size from its header, so that one the machine cannot hold is refused before it is read.
    if (const uint64_t texels = hemi::io::image_pixels(c.input))
        hemi::io::check_memory(bake::ssbump_memory(texels, o),
                               c.input + ": an SSBump bake of its " + std::to_string(texels) + " texels");
    const bake::HeightMapFile file = bake::read_height_map(c.input, bake::parse_height_channel(c.channel));
    if (!filter_given)
        o.filter = bake::default_filter(file.bits);
    char filter_text[64] = "off";
    if (o.filter.enabled())
        std::snprintf(filter_text, sizeof filter_text, "%d,%g", o.filter.radius, double(o.filter.sigma));
    if (leader)
        std::printf("%s: %ux%u, %d-bit, scale %g texels, %s, %s convention, filter %s%s\n", c.input.c_str(),
                    file.field.width, file.field.height, file.bits, double(o.scale),
                    o.wrap ? "tiling" : "not tiling", std::string(to_string(o.convention)).c_str(),
                    filter_text, filter_given ? "" : " (default)");
    ProgressLine line("hemi-bake ssbump");
    const bake::SsbumpMap m = hemi::tool::naming_input(
        c.input, files,
        [&]
        {
            return bake::bake_ssbump(file.field, o,
                                     [&](const bake::SsbumpProgress& p)
                                     {
                                         line.checkpoint_error(p.checkpoint_error);
                                         if (o.occlusion)
                                             line.update(p.texels ? double(p.texels_done) / double(p.texels)
                                                                  : 1.0,
                                                         "occlusion", p.texels_done == p.texels);
                                     });
        });
    if (!leader)
        return 0;
    write_ssbump_png(c.output, m, file.alpha, false);
    std::printf("wrote %s\n", c.output.c_str());
    if (!c.exr.empty())
    {
        hemi::io::ImageRgba img{m.width, m.height, {}};
        img.pixels.reserve(m.weights.size() * 4);
        for (const glm::vec3& v : m.weights)
            img.pixels.insert(img.pixels.end(), {v.x, v.y, v.z, 1.0f});
        hemi::io::write_exr(c.exr, img);
        std::printf("wrote %s\n", c.exr.c_str());
    }
    bake::remove_checkpoint(o.checkpoint); // the finished work is in the outputs now
    glm::dvec3 mean(0.0);
    float lowest = 1.0f;
    for (const glm::vec3& v : m.occlusion)
    {
        mean += glm::dvec3(v);
        lowest = std::min(lowest, std::min(v.x, std::min(v.y, v.z)));
    }
    mean /= double(m.occlusion.size());
    if (o.occlusion)
        std::printf("occlusion: mean %.3f %.3f %.3f, lowest %.3f; %llu rays in %.2f s = %.2f Mrays/s%s\n",
                    mean.x, mean.y, mean.z, double(lowest), (unsigned long long)m.rays, m.trace_seconds,
                    m.trace_seconds > 0 ? double(m.rays) / m.trace_seconds * 1e-6 : 0.0,
                    m.resumed ? " (resumed from a checkpoint)" : "");
    if (!c.json.empty())
    {
        nlohmann::json j;
        j["input"] = c.input;
        j["width"] = m.width;
        j["height"] = m.height;
        j["bits"] = file.bits;
        j["channel"] = c.channel;
        j["scale"] = o.scale;
        j["rays_per_texel"] = o.occlusion ? o.rays : 0;
        j["occlusion"] = o.occlusion;
        j["wrap"] = o.wrap;
        j["convention"] = std::string(to_string(o.convention));
        j["filter"] = {{"radius", o.filter.radius}, {"sigma", o.filter.sigma}};
        j["seed"] = o.seed;
        j["epsilon"] = o.epsilon;
        j["max_distance"] = o.max_distance > 0 ? o.max_distance : float(std::max(m.width, m.height));
        j["rays"] = m.rays;
        j["trace_seconds"] = m.trace_seconds;
        j["rays_per_second"] = m.trace_seconds > 0 ? double(m.rays) / m.trace_seconds : 0.0;
        j["resumed"] = m.resumed;
        // How the ranks shared the rows (one process: all of them on rank 0).
        const std::vector<uint64_t> rows = o.distribution
                                               ? o.distribution->items_by_rank()
                                               : std::vector<uint64_t>{o.occlusion ? m.height : 0u};
        j["ranks"] = rows.size();
        j["rows_by_rank"] = rows;
        j["mean_occlusion"] = {mean.x, mean.y, mean.z};
        j["lowest_occlusion"] = lowest;
        j["output"] = c.output;
        if (!c.exr.empty())
            j["exr"] = c.exr;
        hemi::io::write_text_atomically(c.json, j.dump(2) + "\n");
        std::printf("wrote %s\n", c.json.c_str());
    }
    return 0;
}

// The light options hemi-bake lightmap and hemi-bake reference share: the same words give the same lights.
// An environment EXR for a bake: read, its small negative values (real HDRIs' compression) read as 0 with a
// warning, a larger negative radiance refused naming the pixel (io::clamp_negative_radiance).
hemi::io::ImageRgba read_environment(const std::string& path, const char* tool)
{
    hemi::io::ImageRgba image = hemi::io::read_exr(path); // names the file when it is missing or not an EXR
    const hemi::io::NegativeRadiance n = hemi::io::clamp_negative_radiance(image, path);
    if (n.clamped)
        std::fprintf(
            stderr, "%s: warning: %s: %zu pixel value(s) below zero (down to %g; the mean is %g) read as 0\n",
            tool, path.c_str(), n.clamped, double(n.least), double(n.mean));
    return image;
}

struct LightCli
{
    std::string env = "uniform", sun;
    float env_scale = 1.0f;

    void add_to(CLI::App* app)
    {
        app->add_option("--env", env,
                        "environment: uniform (radiance 1 from every direction) or an equirect EXR "
                        "(z up, hemi-render's convention)")
            ->capture_default_str();
        app->add_option("--env-scale", env_scale, "multiplies the environment's radiance (>= 0)")
            ->check(hemi::tool::finite(0.0, 1e20))
            ->capture_default_str();
        app->add_option("--sun", sun,
                        "a sun: X,Y,Z (towards it, world z up),R,G,B (irradiance on a surface "
                        "facing it)[,DIAMETER in degrees, default 0.53]");
    }

    hemi::bake::LightmapLights lights() const
    {
        hemi::bake::LightmapLights l;
        if (!sun.empty())
        {
            const char* form = "X,Y,Z,R,G,B[,DIAMETER_DEGREES] (towards the sun, world z up; R,G,B the "
                               "irradiance on a surface facing it, >= 0; the diameter in [0, 90))";
            const std::vector<double> v = hemi::tool::parse_numbers(sun, "--sun", form, {6, 7});
            if (v[3] < 0.0 || v[4] < 0.0 || v[5] < 0.0 || (v.size() == 7 && !(v[6] >= 0.0 && v[6] < 90.0)) ||
                v[0] * v[0] + v[1] * v[1] + v[2] * v[2] == 0.0)
                throw std::invalid_argument("--sun expects " + std::string(form) + ", got '" + sun + "'");
            l.sun = true;
            l.sun_direction = glm::vec3(float(v[0]), float(v[1]), float(v[2]));
            l.sun_irradiance = glm::vec3(float(v[3]), float(v[4]), float(v[5]));
            l.sun_diameter_degrees = v.size() == 7 ? float(v[6]) : 0.53f;
        }
        if (env != "uniform")
        {
            l.environment = read_environment(env, "hemi-bake");
            l.environment_name = env;
        }
        l.environment_scale = env_scale;
        l.uniform = glm::vec3(env_scale);
        return l;
    }
};

struct LightmapCli
{
    std::string scene, asset, bases = "sh9,hl2,h4,h6,sal4,plain,rnm", size, exr_dir, json, probes, uv_report,
                              memory_budget, sun_mode = "baked", reflection_exponents = "10,100";
    std::vector<std::string> reflection_probes;
    LightCli light;
    hemi::bake::LightmapFileOptions options;
};

int run_lightmap(LightmapCli& c)
{
    namespace bake = hemi::bake;
    bake::LightmapFileOptions& o = c.options;
    o.outputs = hemi::tool::parse_names(c.bases, "--bases");
    if (!c.size.empty())
        std::tie(o.width, o.height) = hemi::tool::parse_size(c.size, "--size", hemi::io::kMaxAtlasSide);
    if (c.probes == "gltf")
        o.gltf_probes = true;
    else if (c.probes.rfind("auto:", 0) == 0)
        o.probe_budget = uint32_t(hemi::tool::parse_counts(c.probes.substr(5), "--probes auto:N",
                                                           "N, the most probes to place (1 to 2^20)", ',',
                                                           {1}, 1, 1u << 20)[0]);
    else if (c.probes.rfind("file:", 0) == 0)
        o.probe_points = bake::read_probe_points(c.probes.substr(5));
    else if (!c.probes.empty())
    {
        const std::vector<uint64_t> n = hemi::tool::parse_counts(
            c.probes, "--probes", "NX,NY,NZ (at least 1 each, 2^24 in all)", ',', {3}, 1, 1u << 24);
        if (hemi::io::probe_grid_count(n[0], n[1], n[2]) == 0)
            throw std::invalid_argument("--probes " + c.probes + ": more than 2^24 probes in all");
        o.probes = glm::uvec3(uint32_t(n[0]), uint32_t(n[1]), uint32_t(n[2]));
    }
    for (const std::string& r : c.reflection_probes)
    {
        const std::vector<double> v = hemi::tool::parse_numbers(
            r, "--reflection-probe", "X,Y,Z[,MINX,MINY,MINZ,MAXX,MAXY,MAXZ]", {3, 9});
        bake::ReflectionProbePlacement p;
        p.centre = glm::vec3(float(v[0]), float(v[1]), float(v[2]));
        if (v.size() == 9)
        {
            p.box_min = glm::vec3(float(v[3]), float(v[4]), float(v[5]));
            p.box_max = glm::vec3(float(v[6]), float(v[7]), float(v[8]));
            if (!(p.box_min.x < p.box_max.x && p.box_min.y < p.box_max.y && p.box_min.z < p.box_max.z))
                throw std::invalid_argument("--reflection-probe " + r +
                                            ": the box's minimum must be below its "
                                            "maximum along every axis");
        }
        o.reflection_probes.push_back(p);
    }
    if (!c.reflection_probes.empty())
    {
        o.reflection.exponents.clear();
        for (double e : hemi::tool::parse_numbers(c.reflection_exponents, "--reflection-exponents",
                                                  "comma-separated Phong exponents"))
            o.reflection.exponents.push_back(e);
    }
    o.exr_dir = c.exr_dir;
    o.memory_held = hemi::io::resident_memory(); // --memory-budget is a ceiling on the whole process's peak
    if (!c.memory_budget.empty() && !(o.memory_budget = hemi::io::parse_bytes(c.memory_budget)))
        throw std::invalid_argument("--memory-budget " + c.memory_budget +
                                    ": not a size (bytes, or a number with K, M, G or T: 8G, 1.5GiB)");
    // Every file before any work: the outputs writable, none of them an input.
    hemi::tool::Files files;
    files.scene("SCENE", c.scene);
    if (c.light.env != "uniform")
        files.input("--env", c.light.env);
    files.output("-o", c.asset);
    files.output("its checkpoint", bake::checkpoint_path(c.asset));
    files.output("its tiles", bake::lightmap_tile_path(c.asset));
    files.output("its spool", c.asset + ".spool");
    files.output("--json", c.json);
    files.output("--uv-report", c.uv_report);
    o.uv_report = c.uv_report;
    const bool leader = !o.bake.distribution || o.bake.distribution->leader();
    if (!c.exr_dir.empty())
    {
        if (leader) // the other ranks write nothing
            hemi::tool::make_folder(c.exr_dir, "--exr-dir");
        for (const std::string& name : o.outputs)
            files.output("--exr-dir", bake::lightmap_exr_path(c.exr_dir, c.asset, name));
    }
    if (leader) // the other ranks write nothing (their machines may not even see the outputs' folder)
        files.check();
    o.lights = c.light.lights(); // read_exr names the environment's file; check_lights names it too
    if (!hemi::io::parse_light_mode(c.sun_mode, o.lights.sun_mode))
        throw std::invalid_argument("--sun-mode must be baked, mixed or realtime, not '" + c.sun_mode + "'");
    if (o.lights.sun_mode != hemi::io::LightMode::Baked && !o.lights.sun)
        throw std::invalid_argument("--sun-mode " + c.sun_mode + " needs a --sun");
    ProgressLine line("hemi-bake lightmap");
    // What the job is doing, for an out-of-memory message: the stage after the one just done.
    hemi::tool::set_stage("reading the scene");
    hemi::tool::out_of_memory_advice() = "; a --memory-budget below what the machine (or ulimit -v) can give "
                                         "bakes in tiles";
    o.on_stage = [&o](std::string_view done)
    {
        const bool any = o.probes.x || o.probe_budget || !o.probe_points.empty() || o.gltf_probes;
        const std::string probes = !any             ? "making and writing the outputs"
                                   : o.probe_budget ? "placing and baking the light probes"
                                                    : "baking the light probes";
        if (done == "scene")
            hemi::tool::set_stage("laying out the lightmap atlas");
        else if (done == "atlas")
            hemi::tool::set_stage("baking");
        else if (done == "bake")
            hemi::tool::set_stage(o.denoise ? "denoising" : probes);
        else if (done == "denoise")
            hemi::tool::set_stage(probes);
        else if (done == "probes")
            hemi::tool::set_stage("making and writing the outputs");
    };
    const bake::LightmapBakeSummary s = hemi::tool::naming_input(
        c.scene, files,
        [&]
        {
            return bake::bake_lightmap_file(
                c.scene, c.asset, o,
                [&](const bake::LightmapProgress& p)
                {
                    line.checkpoint_error(p.checkpoint_error);
                    const double fraction =
                        (p.pass + (p.texels ? double(p.texels_done) / double(p.texels) : 1.0)) / p.passes;
                    const std::string what =
                        "pass " + std::to_string(p.pass + 1) + "/" + std::to_string(p.passes) + " (" +
                        (p.pass == 0 ? std::string("direct") : "bounce " + std::to_string(p.pass)) + ")";
                    line.update(fraction, what, p.pass + 1 == p.passes && p.texels_done == p.texels);
                });
        });
    if (!leader)
        return 0;
    for (const std::string& w : s.warnings)
        std::fprintf(stderr, "hemi-bake lightmap: warning: %s: %s\n", c.scene.c_str(), w.c_str());
    std::printf("baked %s: %ux%u atlas, %zu texels covered, %zu triangles, outputs %s\n", c.asset.c_str(),
                s.width, s.height, s.uv_report.covered_texels, s.triangles, c.bases.c_str());
    if (s.unwrapped_charts)
        std::printf("unwrapped: %zu planar charts at %.4g units per texel\n", s.unwrapped_charts,
                    double(s.unwrap_texel_size));
    std::printf("texel size %.4g to %.4g units; %d rays per texel and pass, %d bounce(s)",
                double(s.uv_report.min_texel_size), double(s.uv_report.max_texel_size), o.bake.rays,
                o.bake.bounces);
    if (o.lights.sun)
        std::printf(" + %d towards the sun", o.bake.sun_rays);
    std::printf("\nrays: %llu in %.2f s = %.2f Mrays/s; total %.2f s%s\n", (unsigned long long)s.rays,
                s.trace_seconds, s.trace_seconds > 0 ? double(s.rays) / s.trace_seconds * 1e-6 : 0.0,
                s.total_seconds, s.resumed ? " (resumed from a checkpoint)" : "");
    // The lights that are not all baked: mixed ones with their shadowmask channel, realtime ones.
    std::string modes;
    for (const hemi::io::LightmapLight& l : s.light_table)
        if (l.light.mode != hemi::io::LightMode::Baked)
            modes +=
                (modes.empty() ? "" : ", ") +
                (l.light.name.empty() ? std::string("(unnamed)") : l.light.name) + " " +
                hemi::io::light_mode_name(l.light.mode) +
                (l.channel >= 0 ? std::string(" (shadowmask ") + "RGBA"[l.channel] + ")" : std::string());
    if (!modes.empty())
        std::printf("lights: %s\n", modes.c_str());
    if (s.probes)
    {
        if (o.probes.x)
            std::printf("%zu light probes (%ux%ux%u, %d rays each), %zu inside geometry\n", s.probes,
                        o.probes.x, o.probes.y, o.probes.z, o.probe_rays, s.invalid_probes);
        else if (o.probe_budget)
            std::printf("%zu light probes placed (budget %u, %d rays each) from %zu candidates in open space "
                        "of %zu; their lookup's mean error at the others %.1f%%\n",
                        s.probes, o.probe_budget, o.probe_rays, s.open_probe_candidates, s.probe_candidates,
                        100.0 * s.probe_placement_error);
        else
            std::printf("%zu light probes (%s, %d rays each), %zu inside geometry (never used)\n", s.probes,
                        o.gltf_probes ? "the glTF's hemi_probe nodes" : "the points file", o.probe_rays,
                        s.invalid_probes);
    }
    if (s.reflection_probes)
        std::printf("%zu reflection probe(s), %u^2 a half\n", s.reflection_probes, o.reflection.size);
    if (s.pushed || s.invalid)
        std::printf(
            "%zu texel(s) moved out of walls their footprint reached, %zu inside geometry (filled from "
            "their neighbours)\n",
            s.pushed, s.invalid);
    if (s.tile_texels)
        std::printf("memory: %u tiles of %u texels a pass, their sums on disk, to stay within %s "
                    "(%s); peak %s\n",
                    s.tiles, s.tile_texels, hemi::io::format_bytes(s.memory_budget).c_str(),
                    o.memory_budget ? "--memory-budget"
                                    : "what is available: free memory, HEMI_MEMORY_BUDGET, ulimit -v",
                    hemi::io::format_bytes(hemi::io::peak_memory()).c_str());
    if (s.denoised_texels)
        std::printf("--denoise: %zu texels filtered (%d passes)\n", s.denoised_texels, o.denoise_passes);
    if (s.seams)
    {
        // The first output's (the shadowmask has its own line in --json).
        const auto first = std::find_if(s.seam_difference.begin(), s.seam_difference.end(),
                                        [](const auto& d) { return d.first != "shadowmask"; });
        const auto& [before, after] = first->second;
        if (s.stitched_texels)
            std::printf("%zu seam edge(s) between charts, stitched (%zu texels): their sides differed by "
                        "%.1f%% on average, %.1f%% at the 95th percentile, and now by %.2f%%, %.2f%% (%s; "
                        "--json has every output)\n",
                        s.seams, s.stitched_texels, 100.0 * before.first, 100.0 * before.second,
                        100.0 * after.first, 100.0 * after.second, first->first.c_str());
        else
            std::printf("%zu seam edge(s) between charts, not stitched: their sides differ by %.1f%% on "
                        "average, %.1f%% at the 95th percentile (%s; --json has every output)\n",
                        s.seams, 100.0 * before.first, 100.0 * before.second,
                        s.seam_difference.begin()->first.c_str());
    }
    for (const auto& [name, changed] : s.non_negative)
        std::printf("--non-negative: %zu texel(s) of %s lifted out of negative irradiance\n", changed,
                    name.c_str());
    if (s.uv_report.overlapping_texels)
        std::printf("%zu texel(s) of overlapping lightmap UVs, each given to one triangle%s\n",
                    s.uv_report.overlapping_texels, c.uv_report.empty() ? " (--uv-report shows where)" : "");
    if (!c.uv_report.empty())
        std::printf("wrote %s\n", c.uv_report.c_str());
    for (const std::filesystem::path& p : s.exr_files)
        std::printf("wrote %s\n", p.string().c_str());
    if (!c.json.empty())
    {
        bake::write_lightmap_bake_json(c.json, s, o);
        std::printf("wrote %s\n", c.json.c_str());
    }
    return 0;
}

struct ReferenceCli
{
    std::string scene, output, size = "800x600", camera = "auto", json;
    LightCli light;
    hemi::bake::ReferenceOptions options;
};

int run_reference(ReferenceCli& c)
{
    namespace bake = hemi::bake;
    bake::ReferenceOptions& o = c.options;
    std::tie(o.width, o.height) = hemi::tool::parse_size(c.size, "--size");
    const std::optional<hemi::math::Camera> camera = hemi::math::parse_camera(c.camera);
    o.auto_camera = !camera;
    if (camera)
        o.camera = *camera;
    if (std::filesystem::path(c.output).extension() != ".exr")
        throw std::invalid_argument("-o must end in .exr (linear RGBA, alpha = coverage), got '" + c.output +
                                    "'");
    hemi::tool::Files files;
    files.scene("SCENE", c.scene);
    if (c.light.env != "uniform")
        files.input("--env", c.light.env);
    files.output("-o", c.output);
    files.output("--json", c.json);
    files.check();
    // The image (RGBA floats), its per-pixel noise (a double) and the EXR's copy: refused before the scene is
    // read if they cannot fit.
    hemi::io::check_memory(uint64_t(o.width) * o.height * 48,
                           "--size " + c.size + ": a " + c.size + " reference image");
    const bake::LightmapLights lights = c.light.lights();
    ProgressLine line("hemi-bake reference");
    const bake::ReferenceImage r = hemi::tool::naming_input(
        c.scene, files,
        [&]
        {
            return bake::render_reference_file(
                c.scene, c.output, lights, o,
                [&](uint32_t done, uint32_t rows)
                {
                    line.update(double(done) / double(rows),
                                "rows " + std::to_string(done) + "/" + std::to_string(rows), done == rows);
                });
        });
    std::printf(
        "wrote %s: %ux%u, %d paths per pixel, %d bounce(s)%s; camera %.3g,%.3g,%.3g -> %.3g,%.3g,%.3g\n",
        c.output.c_str(), o.width, o.height, o.rays, o.bounces, o.white ? ", lighting only (E / pi)" : "",
        double(r.camera.eye.x), double(r.camera.eye.y), double(r.camera.eye.z), double(r.camera.target.x),
        double(r.camera.target.y), double(r.camera.target.z));
    std::printf("rays: %llu in %.2f s = %.2f Mrays/s; noise (standard error of a pixel, RMS) %.3g\n",
                (unsigned long long)r.rays, r.seconds,
                r.seconds > 0 ? double(r.rays) / r.seconds * 1e-6 : 0.0, r.noise);
    if (!c.json.empty())
    {
        nlohmann::json j;
        j["scene"] = c.scene;
        j["output"] = c.output;
        j["width"] = o.width;
        j["height"] = o.height;
        j["rays_per_pixel"] = o.rays;
        j["bounces"] = o.bounces;
        j["white"] = o.white;
        j["seed"] = o.seed;
        j["camera"] = {{"eye", {r.camera.eye.x, r.camera.eye.y, r.camera.eye.z}},
                       {"target", {r.camera.target.x, r.camera.target.y, r.camera.target.z}},
                       {"fov_y_degrees", r.camera.fov_y_degrees}};
        j["rays"] = r.rays;
        j["seconds"] = r.seconds;
        j["noise"] = r.noise;
        hemi::io::write_text_atomically(c.json, j.dump(2) + "\n");
        std::printf("wrote %s\n", c.json.c_str());
    }
    return 0;
}

struct BrdfCli
{
    hemi::bake::BrdfBakeOptions options;
    std::string output, json;
};

void print_brdf_error(const char* what, const hemi::bake::BrdfError& e)
{
    std::printf("  %-22s bulk: max %.4f%%  rms %.4f%% (%llu pairs)   grazing (cos < 0.1): max %.4f%%  rms "
                "%.4f%% (%llu pairs)\n",
                what, 100.0 * e.bulk_max, 100.0 * e.bulk_rms, (unsigned long long)e.bulk_samples,
                100.0 * e.grazing_max, 100.0 * e.grazing_rms, (unsigned long long)e.grazing_samples);
}

nlohmann::json brdf_error_json(const hemi::bake::BrdfError& e)
{
    return {{"bulk_max", e.bulk_max},       {"bulk_rms", e.bulk_rms},
            {"bulk_pairs", e.bulk_samples}, {"grazing_max", e.grazing_max},
            {"grazing_rms", e.grazing_rms}, {"grazing_pairs", e.grazing_samples}};
}

int run_brdf(BrdfCli& c)
{
    hemi::tool::Files files;
    files.output("-o", c.output);
    files.output("--json", c.json);
    files.check();
    const hemi::bake::BrdfBake b = hemi::bake::bake_brdf(c.options);
    hemi::bake::write_brdf_exr(c.output, c.options, b);
    std::printf("wrote %s: %s, %u x %u, %s\n", c.output.c_str(), c.options.model.c_str(), c.options.size,
                c.options.size, c.options.eight_bit ? "8-bit (scaled)" : "float");
    std::printf(
        "table product against the model evaluated directly (relative to max(value, 1%% of the peak)):\n");
    print_brdf_error("float tables", b.float_error);
    if (c.options.eight_bit)
        print_brdf_error("8-bit tables", b.error);
    if (!c.json.empty())
    {
        nlohmann::json j;
        j["output"] = c.output;
        j["model"] = c.options.model;
        j["size"] = c.options.size;
        j["eight_bit"] = c.options.eight_bit;
        if (c.options.model == "torrance-sparrow")
        {
            j["distribution"] = c.options.distribution;
            j["roughness"] = c.options.roughness;
            j["ior"] = c.options.ior;
        }
        else
            j["exponent"] = c.options.exponent;
        j["float_error"] = brdf_error_json(b.float_error);
        j["error"] = brdf_error_json(b.error);
        hemi::io::write_text_atomically(c.json, j.dump(2) + "\n");
        std::printf("wrote %s\n", c.json.c_str());
    }
    return 0;
}

struct ExportCli
{
    std::string input, output, outputs = "all";
    float rgbm_range = 0.0f;
};

// hemi-bake export: a baked lightmap level as glTF (io/lightmap_gltf.h, docs/gltf_export.md).
int run_export(const ExportCli& c)
{
    hemi::io::LightmapGltfOptions options;
    options.rgbm_range = c.rgbm_range;
    if (c.outputs == "none")
        options.all_outputs = false;
    else if (c.outputs != "all")
        options.outputs = hemi::tool::parse_names(c.outputs, "--outputs");
    hemi::tool::Files files;
    files.input("LEVEL", c.input);
    files.output("-o", c.output);
    files.check();
    const std::filesystem::path out(c.output);
    if (out.extension() != ".glb" && out.extension() != ".gltf")
        throw std::invalid_argument("-o " + c.output + ": the output must end in .glb or .gltf");
    const auto t0 = std::chrono::steady_clock::now();
    const std::string kind = hemi::io::asset_kind(c.input);
    if (kind != "lightmap")
        throw std::invalid_argument(
            c.input + ": a " + kind +
            " asset; export writes lightmap assets (hemi-bake lightmap -o LEVEL.hemi)");
    const hemi::io::LightmapAsset asset = hemi::io::read_lightmap_asset(c.input);
    const hemi::io::LightmapGltfSummary s = hemi::tool::naming_input(
        c.input, files, [&] { return hemi::io::write_lightmap_gltf(out, asset, options); });
    std::string names;
    for (const std::string& n : s.outputs)
        names += (names.empty() ? "" : ",") + n;
    std::printf("wrote %s: %zu triangles, %u x %u lightmap (RGBM, range %g), outputs under HEMI_lightmaps: "
                "%s, %.1f MiB of buffer (%.2f s)\n",
                c.output.c_str(), asset.mesh.indices.size() / 3, asset.width, asset.height,
                double(s.rgbm_range), names.empty() ? "none" : names.c_str(), double(s.bytes) / (1 << 20),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (s.clipped_texels)
        std::fprintf(stderr,
                     "hemi-bake export: warning: %llu texel(s) of the plain lightmap lie outside [0, %g] and "
                     "were clipped in the RGBM image (a larger --rgbm-range keeps them)\n",
                     (unsigned long long)s.clipped_texels, double(s.rgbm_range));
    return 0;
}

struct EnvmapCli
{
    std::string input, output, exponents = "10,100,1000", iors = "1.5", exr_dir, report;
    hemi::bake::EnvmapBakeOptions options;
};

std::vector<double> parse_numbers(const std::string& list, const char* option)
{
    std::vector<double> out;
    out = hemi::tool::parse_numbers(list, option, "comma-separated numbers");
    for (size_t i = 0; i < out.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (out[i] == out[j])
                throw std::invalid_argument(std::string(option) + " names " + std::to_string(out[i]) +
                                            " twice");
    return out;
}

// Texel solid angles of the parabolic halves (texels wholly inside the circle: the paper's factor 4) and of a
// cube map with the same largest texel (face size N / 2), each measured over its texels.
nlohmann::json sampling_report(uint32_t n)
{
    double pmin = 1e30, pmax = 0.0, total = 0.0;
    hemi::math::ParabolicImage p;
    p.size = n;
    for (uint32_t row = 0; row < n; ++row)
        for (uint32_t col = 0; col < n; ++col)
        {
            const double in = p.solid_angle_in_circle(col, row), whole = p.solid_angle(col, row);
            total += 2.0 * in;
            if (std::abs(in - whole) < 1e-15 * (1.0 + whole))
            {
                pmin = std::min(pmin, whole);
                pmax = std::max(pmax, whole);
            }
        }
    const uint32_t m = std::max(1u, n / 2);
    double cmin = 1e30, cmax = 0.0;
    for (uint32_t j = 0; j < m; ++j)
        for (uint32_t i = 0; i < m; ++i)
        {
            const double s0 = -1.0 + 2.0 * i / m, t0 = -1.0 + 2.0 * j / m;
            const double w = hemi::math::cubemap_solid_angle(s0, t0, s0 + 2.0 / m, t0 + 2.0 / m);
            cmin = std::min(cmin, w);
            cmax = std::max(cmax, w);
        }
    return {{"parabolic",
             {{"texels", 2ull * n * n},
              {"largest_over_smallest", pmax / pmin},
              {"solid_angle_sum_in_circles", total}}},
            {"cube", {{"face_size", m}, {"texels", 6ull * m * m}, {"largest_over_smallest", cmax / cmin}}}};
}

int run_envmap(EnvmapCli& c)
{
    c.options.exponents = parse_numbers(c.exponents, "--exponents");
    c.options.iors = parse_numbers(c.iors, "--ior");
    hemi::bake::check_envmap_options(c.options);
    hemi::tool::Files files;
    files.input("ENV", c.input);
    files.output("-o", c.output);
    files.output("--report", c.report);
    files.check();
    if (!c.exr_dir.empty())
    {
        hemi::tool::make_folder(c.exr_dir, "--exr-dir");
        hemi::io::check_writable(std::filesystem::path(c.exr_dir) / "mirror_0_front.exr");
    }
    const hemi::io::ImageRgba env = read_environment(c.input, "hemi-bake envmap");
    hemi::bake::EnvmapBakeStats stats;
    ProgressLine line("hemi-bake envmap");
    const auto t0 = std::chrono::steady_clock::now();
    const hemi::io::EnvmapAsset a = hemi::tool::naming_input(
        c.input, files,
        [&]
        {
            return hemi::bake::bake_envmap(env, c.options, &stats,
                                           [&](const std::string& stage) {
                                               std::fprintf(stderr, "hemi-bake envmap: %s\n", stage.c_str());
                                           });
        });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    hemi::io::write_envmap_asset(c.output, a);
    std::printf(
        "wrote %s: 2 x %u^2 mirror map, %zu mip levels, diffuse %u^2, %zu glossy maps, %zu Fresnel tables "
        "(%.2f s)\n",
        c.output.c_str(), a.mirror[0].size, a.mirror.size(), a.diffuse.size, a.glossy.size(), a.iors.size(),
        seconds);
    for (size_t i = 0; i < a.glossy.size(); ++i)
        std::printf("  glossy exponent %-8g %4u^2  %.2f s (%.3g lobe evaluations)\n", double(a.exponents[i]),
                    a.glossy[i].size, stats.glossy_seconds[i], double(stats.glossy_pairs[i]));
    if (!c.exr_dir.empty())
    {
        const auto written = hemi::bake::write_envmap_exrs(c.exr_dir, a);
        std::printf("wrote %zu EXR files into %s\n", written.size(), c.exr_dir.c_str());
    }
    if (!c.report.empty())
    {
        size_t bytes = 0;
        for (const auto& level : a.mirror)
            bytes += level.rgb.size() * 4;
        nlohmann::json j;
        j["input"] = c.input;
        j["output"] = c.output;
        j["size"] = a.mirror[0].size;
        j["sampling"] = sampling_report(a.mirror[0].size);
        j["mirror_bytes_f32_rgb"] = bytes;
        j["seconds"] = {{"resample", stats.resample_seconds},
                        {"mipmaps", stats.mip_seconds},
                        {"diffuse", stats.diffuse_seconds},
                        {"total", seconds}};
        nlohmann::json glossy = nlohmann::json::array();
        for (size_t i = 0; i < a.glossy.size(); ++i)
            glossy.push_back({{"exponent", a.exponents[i]},
                              {"size", a.glossy[i].size},
                              {"seconds", stats.glossy_seconds[i]},
                              {"lobe_evaluations", stats.glossy_pairs[i]}});
        j["glossy"] = glossy;
        std::fprintf(stderr,
                     "hemi-bake envmap: comparing with cube maps against the reference (Eq. 9 over every "
                     "pixel of the environment)\n");
        const auto comparisons = hemi::bake::compare_prefiltered_maps(env, a);
        nlohmann::json prefiltered = nlohmann::json::array();
        std::printf("prefiltered maps against the reference at 1024 directions (RMSE, relative to the "
                    "reference's RMS):\n"
                    "  %-9s %-22s %-22s\n",
                    "exponent", "parabolic", "cube (faces of half the size)");
        for (const auto& cmp : comparisons)
        {
            prefiltered.push_back({{"exponent", cmp.exponent},
                                   {"parabolic",
                                    {{"size", cmp.parabolic_size},
                                     {"texels", cmp.parabolic_texels},
                                     {"rmse", cmp.parabolic_rmse}}},
                                   {"cube",
                                    {{"face_size", cmp.cube_size},
                                     {"texels", cmp.cube_texels},
                                     {"rmse", cmp.cube_rmse},
                                     {"seconds", cmp.cube_seconds}}},
                                   {"reference_rms", cmp.reference_rms}});
            char p[64], q[64];
            std::snprintf(p, sizeof p, "%u^2 x 2: %.4f%%", cmp.parabolic_size,
                          100.0 * cmp.parabolic_rmse / cmp.reference_rms);
            std::snprintf(q, sizeof q, "%u^2 x 6: %.4f%%", cmp.cube_size,
                          100.0 * cmp.cube_rmse / cmp.reference_rms);
            std::printf("  %-9g %-22s %-22s\n", cmp.exponent, p, q);
        }
        j["prefiltered"] = prefiltered;
        hemi::io::write_text_atomically(c.report, j.dump(2) + "\n");
        std::printf("wrote %s\n", c.report.c_str());
    }
    return 0;
}

struct PrtCli
{
    std::string scene, asset, bases, transfer = "interreflected", cpca, json;
    hemi::bake::PrtAssetOptions options;
};

int run_prt(PrtCli& c)
{
    hemi::bake::PrtAssetOptions& o = c.options;
    o.bake.kind = hemi::bake::parse_transfer_kind(c.transfer);
    o.techniques = hemi::tool::parse_names(c.bases, "--bases");
    if (!c.cpca.empty())
    {
        const std::vector<uint64_t> v =
            hemi::tool::parse_counts(c.cpca, "--cpca", "CLUSTERSxVECTORS (e.g. 1x24)", 'x', {2}, 1, 1u << 20);
        o.cpca_clusters = uint32_t(v[0]);
        o.cpca_vectors = uint32_t(v[1]);
    }
    hemi::tool::Files files;
    files.scene("SCENE", c.scene);
    files.output("-o", c.asset);
    files.output("its checkpoint", hemi::bake::checkpoint_path(c.asset));
    files.output("--json", c.json);
    const bool leader = !o.bake.distribution || o.bake.distribution->leader();
    if (leader) // the other ranks write nothing
        files.check();
    PrtProgressLine line;
    const hemi::bake::PrtBakeSummary s = hemi::tool::naming_input(
        c.scene, files, [&] { return hemi::bake::bake_prt_file(c.scene, c.asset, o, std::ref(line)); });
    if (!leader)
        return 0;
    print_prt_summary(s, o, c.scene, c.asset);
    if (!c.json.empty())
    {
        hemi::bake::write_prt_bake_json(c.json, s, o);
        std::printf("wrote %s\n", c.json.c_str());
    }
    return 0;
}

int run_basis_report(const std::string& json, const std::string& plot, int signals, uint64_t seed)
{
    hemi::tool::Files files;
    files.output("--json", json);
    files.output("--plot", plot);
    files.check();
    auto t0 = std::chrono::steady_clock::now();
    hemi::bake::BasisReport r = hemi::bake::make_basis_report(signals, seed);
    print_report(r);
    if (!json.empty())
    {
        hemi::bake::write_basis_report_json(json, r);
        std::printf("\nwrote %s\n", json.c_str());
    }
    if (!plot.empty())
    {
        hemi::bake::plot_basis_report(plot, r);
        std::printf("wrote %s\n", plot.c_str());
    }
    std::fprintf(stderr, "basis-report: %.1f s\n",
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    // Under mpirun every rank runs this; the bakes that share their work (lightmap) hand it out, rank 0
    // writes the outputs (mpi_distribution.h, docs/distributed.md).
    const std::unique_ptr<hemi::tool::MpiJob> job = hemi::tool::join_mpi_job(argc, argv);
    CLI::App app{"hemi-bake: precompute lighting data for hemi"};
    app.require_subcommand(1);

    std::string json, plot;
    int signals = 10000;
    uint64_t seed = 1;
    CLI::App* report =
        app.add_subcommand("basis-report", "compare the hemispherical bases (Sloan 2006, Habel 2010)");
    report->add_option("--json", json, "write the report as JSON to FILE");
    report->add_option("--plot", plot,
                       "draw Habel's Fig. 3 (mean IMSE vs coefficients) into FILE.png with gnuplot");
    report->add_option("--signals", signals, "number of random irradiance signals")
        ->check(CLI::Range(1, 10000000))
        ->capture_default_str();
    report->add_option("--seed", seed, "seed of the random signals")->capture_default_str();

    PrtCli pc;
    for (const auto& t : hemi::bake::default_techniques())
        pc.bases += (pc.bases.empty() ? "" : ",") + t;
    CLI::App* prt =
        app.add_subcommand("prt", "bake per-vertex PRT transfer matrices (Sloan 2006) from a glTF scene");
    prt->add_option("scene", pc.scene, "glTF 2.0 scene (.gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    prt->add_option("-o,--output", pc.asset, "baked asset to write (.hemi)")->required();
    prt->add_option("--bases", pc.bases,
                    "comma-separated techniques: gs (SH9, the gold standard), hl2, sal4, h4, h6, "
                    "sep4, prt (classic PRT, no normal map); also sh4ls, zernike3, zernike6")
        ->capture_default_str();
    prt->add_option("--transfer", pc.transfer, "unshadowed | shadowed | interreflected")
        ->capture_default_str();
    prt->add_option("--bounces", pc.options.bake.bounces, "interreflection bounces")
        ->check(CLI::Range(0, 16))
        ->capture_default_str();
    prt->add_option("--order", pc.options.bake.order, "lighting SH order n (L = n^2)")
        ->check(CLI::Range(3, 6))
        ->capture_default_str();
    prt->add_option("--rays", pc.options.bake.rays, "rays per vertex")
        ->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    prt->add_option("--seed", pc.options.bake.seed, "seed of the ray directions (same seed, same bytes)")
        ->capture_default_str();
    prt->add_option("--albedo", pc.options.bake.albedo, "grey albedo for interreflection, in [0, 1)")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 0.999999));
    prt->add_option("--cpca", pc.cpca,
                    "compress with CPCA: CLUSTERSxVECTORS, e.g. 1x24 (dense matrices are kept)");
    prt->add_option("--json", pc.json, "write the bake summary as JSON to FILE");
    prt->add_option("--checkpoint-interval", pc.options.bake.checkpoint_seconds,
                    "seconds between checkpoints to ASSET.partial (an interrupted bake resumes from it)")

        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e9));

    SsbumpCli sb;
    CLI::App* ssbump = app.add_subcommand(
        "ssbump",
        "bake a self-shadowed bump map (Green 2007) from a height map, or convert to and from normal maps");
    ssbump->add_option("height", sb.input,
                       "height map: 8- or 16-bit PNG, or EXR (white stands --scale texels above black)");
    ssbump
        ->add_option("-o,--output", sb.output,
                     "SSBump map (8-bit PNG) to write; a normal map with --to-normal")
        ->required();
    ssbump->add_option("--scale", sb.options.scale, "height of white above black, in texel widths")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e6));
    ssbump->add_option("--channel", sb.channel, "channel that holds the heights: grey, r, g, b or a")
        ->capture_default_str();
    ssbump->add_option("--rays", sb.options.rays, "rays per texel for the directional occlusion")
        ->capture_default_str();
    ssbump->add_option("--filter", sb.filter,
                       "bilateral filter on the heights, RADIUS,SIGMA (texels, height units), "
                       "or 0 for none [default: 2,0.02 for 8-bit input, none otherwise]");
    ssbump->add_flag("--no-occlusion", sb.no_occlusion, "weights of the normal only (no rays)");
    ssbump->add_flag("--no-wrap", sb.no_wrap, "the map does not tile: the relief ends at its borders");
    ssbump
        ->add_option("--convention", sb.convention,
                     "normalized (flat = 1/3 each, the paper's Eq. 3) or valve "
                     "(flat = 0.577 each, Source's height2ssbump)")
        ->capture_default_str();
    ssbump->add_option("--exr", sb.exr, "also write the weights as a float EXR");
    ssbump->add_option("--json", sb.json, "write the bake report as JSON to FILE");
    ssbump->add_option("--from-normal", sb.from_normal,
                       "convert this tangent-space normal map (PNG) instead of baking");
    ssbump->add_option("--to-normal", sb.to_normal,
                       "convert this SSBump map back to a tangent-space normal map");
    ssbump->add_option("--seed", sb.options.seed, "seed of the ray directions (same seed, same bytes)")
        ->capture_default_str();
    ssbump
        ->add_option("--max-distance", sb.options.max_distance,
                     "how far rays go, in texel widths (0: the map's larger side)")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e9));
    ssbump
        ->add_option("--checkpoint-interval", sb.options.checkpoint_seconds,
                     "seconds between checkpoints to OUT.png.partial (an interrupted bake resumes from it)")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e9));
    LightmapCli lm;
    CLI::App* lightmap = app.add_subcommand(
        "lightmap", "bake directional lightmaps (Habel & Wimmer 2010) of a glTF scene's TEXCOORD_1 atlas");
    lightmap->add_option("scene", lm.scene, "glTF 2.0 scene (.gltf or .glb) with lightmap UVs (TEXCOORD_1)")
        ->required()
        ->check(CLI::ExistingFile);
    lightmap->add_option("-o,--output", lm.asset, "lightmap asset to write (.hemi)")->required();
    lm.light.add_to(lightmap);
    lightmap
        ->add_option("--sun-mode", lm.sun_mode,
                     "how the sun is baked: baked (direct and indirect light in the lightmap), mixed (only "
                     "its indirect light; its shadows in a shadowmask channel, its direct light at run "
                     "time) or realtime (not baked). glTF lights take theirs from extras.hemi_bake_mode")
        ->capture_default_str();
    lightmap
        ->add_option("--bases", lm.bases,
                     "comma-separated outputs: sh9, hl2, h4, h6, sal4 (and every basis of "
                     "hemi-bake basis-report), plain (E at the surface normal), rnm (E towards "
                     "each radiosity-normal-mapping direction)")
        ->capture_default_str();
    lightmap->add_option("--size", lm.size, "atlas size W or WxH [default: from --texel-size, else 512]");
    lightmap
        ->add_option("--texel-size", lm.options.texel_size,
                     "world units per texel: the atlas size that gives the scene that texel density")
        ->check(hemi::tool::finite(0.0, 1e30));
    lightmap->add_option("--rays", lm.options.bake.rays, "hemisphere rays per texel")->capture_default_str();
    lightmap
        ->add_option("--sun-rays", lm.options.bake.sun_rays, "shadow rays per texel towards the sun's disc")
        ->capture_default_str();
    lightmap
        ->add_option("--bounces", lm.options.bake.bounces,
                     "bounces of indirect light, coloured by each surface's base colour")
        ->check(CLI::Range(0, 16))
        ->capture_default_str();
    lightmap->add_option("--seed", lm.options.bake.seed, "seed of the rays (same seed, same bytes)")
        ->capture_default_str();
    lightmap->add_flag("--unwrap", lm.options.unwrap,
                       "make the lightmap UVs (planar charts at one texel density, "
                       "from --texel-size or to fill --size) instead of reading TEXCOORD_1");
    lightmap->add_flag("--strict-uv", lm.options.strict_uv,
                       "refuse overlapping lightmap UVs instead of giving each contested texel to one "
                       "triangle (with a warning)");
    lightmap->add_flag(
        "--non-negative", lm.options.non_negative,
        "ringing-free directional outputs: each texel's coefficients lifted by the least "
        "change that keeps every normal within 75 degrees of the surface's from negative "
        "irradiance (a low sun's SH9 and H-basis fits ring); plain and rnm are never negative");
    lightmap->add_flag("--no-stitch{false}", lm.options.stitch,
                       "keep the seams between charts as baked: without it, the texels along every edge "
                       "where a smooth surface continues into another chart are changed, in least squares, "
                       "until both sides' bilinear lookups agree (the JSON's \"seams\" has the difference "
                       "before and after)");
    lightmap
        ->add_option("--stitch-closeness", lm.options.stitch_closeness,
                     "stitching's weight on keeping the baked texels against one texel of seam agreeing "
                     "(smaller stitches tighter)")
        ->check(hemi::tool::finite(1e-6, 1e6))
        ->capture_default_str();
    lightmap->add_flag("--denoise", lm.options.denoise,
                       "filter the baked texels' noise (an edge-avoiding a-trous filter inside each chart, "
                       "guided by positions, normals and the bake's own per-texel variance) before the "
                       "outputs are made");
    lightmap
        ->add_option("--denoise-passes", lm.options.denoise_passes,
                     "a-trous passes of --denoise: it reaches 2 (2^N - 1) texels")
        ->check(CLI::Range(1, 10))
        ->capture_default_str();
    lightmap->add_option("--uv-report", lm.uv_report,
                         "write a PNG of the atlas before the bake: covered texels grey, texels two or more "
                         "triangles overlap red (at most 2048 pixels a side, each the worst of its texels)");
    lightmap->add_option("--probes", lm.probes,
                         "light probes for dynamic objects (SH9 irradiance): NX,NY,NZ on a grid over the "
                         "scene's bounding box, at the centres of its cells; auto:N at most N placed in the "
                         "level's open space, denser where the light changes; file:PATH at the points of a "
                         "text file (\"x y z\" a line, the glTF's frame); gltf at the scene's nodes named "
                         "hemi_probe*");
    lightmap->add_option("--probe-rays", lm.options.probe_rays, "sphere rays per probe")
        ->capture_default_str();
    lightmap
        ->add_option("--probe-depth", lm.options.probe_depth,
                     "R: each probe keeps an RxR octahedral map of the distances it sees, so that a "
                     "lookup leaves out the probes behind walls; 0: none (trilinear alone)")
        ->check(CLI::Range(0u, hemi::io::kMaxProbeDepthResolution))
        ->capture_default_str();
    lightmap
        ->add_option("--reflection-probe", lm.reflection_probes,
                     "X,Y,Z[,MINX,MINY,MINZ,MAXX,MAXY,MAXZ]: a reflection probe at X,Y,Z (the scene's own "
                     "frame, glTF's), lighting the box given (else the scene's bounding box); repeat for "
                     "more")
        ->take_all();
    lightmap
        ->add_option("--reflection-size", lm.options.reflection.size,
                     "each reflection probe's parabolic halves (a power of two)")
        ->capture_default_str();
    lightmap
        ->add_option("--reflection-rays", lm.options.reflection.rays,
                     "rays per pixel of a reflection probe's gathered image (a square number)")
        ->capture_default_str();
    lightmap
        ->add_option("--reflection-exponents", lm.reflection_exponents,
                     "the Phong exponents of each reflection probe's glossy maps")
        ->capture_default_str();
    lightmap->add_option("--exr-dir", lm.exr_dir,
                         "also write each output as an EXR with named channels into DIR");
    lightmap->add_option("--json", lm.json, "write the bake summary as JSON to FILE");
    lightmap->add_option("--memory-budget", lm.memory_budget,
                         "the memory the bake may use (bytes, or 8G, 512M, 1.5GiB); when the whole atlas "
                         "does not fit, it bakes in tiles, the sums of its passes in LEVEL.hemi.tiles on "
                         "disk, with the same bytes (default: the memory the machine has free, lowered by "
                         "HEMI_MEMORY_BUDGET)");
    lightmap
        ->add_option(
            "--checkpoint-interval", lm.options.bake.checkpoint_seconds,
            "seconds between checkpoints to LEVEL.hemi.partial (an interrupted bake resumes from it)")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e9));
    ReferenceCli rf;
    CLI::App* reference = app.add_subcommand(
        "reference",
        "path-trace the ground truth a lightmap is measured against, framed like hemi-render's view");
    reference->add_option("scene", rf.scene, "glTF 2.0 scene (.gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    reference->add_option("-o,--output", rf.output, "REF.exr: linear RGBA, alpha = coverage")->required();
    rf.light.add_to(reference);
    reference
        ->add_option("--bounces", rf.options.bounces,
                     "surface reflections per path (as hemi-bake lightmap's)")
        ->check(CLI::Range(0, 16))
        ->capture_default_str();
    reference
        ->add_option("--camera", rf.camera,
                     "auto (frames the scene like hemi-render) or EYE,TARGET as "
                     "x,y,z,x,y,z in world space (z up; glTF +y is world +z)")
        ->capture_default_str();
    reference->add_option("--size", rf.size, "WIDTHxHEIGHT in pixels")->capture_default_str();
    reference->add_flag("--white", rf.options.white, "albedo 1 and no emission: the lighting alone, E / pi");
    reference
        ->add_option(
            "--roughness", rf.options.roughness,
            "a GGX coat of this roughness (glTF's, 0.03 to 1; 0: none) over every surface, its specular "
            "added (hemi-render --roughness; docs/specular.md)")
        ->capture_default_str();
    reference->add_option("--f0", rf.options.f0, "the GGX coat's reflectance at normal incidence (0 to 1)")
        ->capture_default_str();
    reference->add_option("--rays", rf.options.rays, "paths per pixel")->capture_default_str();
    reference->add_option("--seed", rf.options.seed, "seed of the paths (same seed, same bytes)")
        ->capture_default_str();
    reference->add_option("--json", rf.json,
                          "write the render's summary (camera, rays, noise) as JSON to FILE");
    BrdfCli br;
    CLI::App* brdf = app.add_subcommand("brdf", "factor a reflection model into 2D lookup tables (Heidrich & "
                                                "Seidel 1999, section 3), written as EXR");
    brdf->add_option("--model", br.options.model,
                     "torrance-sparrow | banks | phong | blinn-phong | cosine-lobe")
        ->capture_default_str();
    brdf->add_option("--ior", br.options.ior,
                     "torrance-sparrow: index of refraction of the Fresnel term (> 1)")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e6));
    brdf->add_option(
            "--roughness", br.options.roughness,
            "torrance-sparrow: m, the facets' RMS slope (beckmann) or angle spread in radians (gaussian)")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e6));
    brdf->add_option("--exponent", br.options.exponent,
                     "banks, phong, blinn-phong, cosine-lobe: the lobe's exponent")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e6));
    brdf->add_option("--distribution", br.options.distribution, "torrance-sparrow: beckmann | gaussian")
        ->capture_default_str();
    brdf->add_option("--size", br.options.size, "samples per table axis")->capture_default_str();
    brdf->add_flag(
        "--8bit", br.options.eight_bit,
        "store each channel as 8-bit codes / 255 times a scale in the metadata (reports that form's error)");
    brdf->add_option("-o,--output", br.output, "the tables as EXR (model and parameters in its metadata)")
        ->required();
    brdf->add_option("--json", br.json, "write the tables' measured error as JSON to FILE");
    EnvmapCli em;
    CLI::App* envmap = app.add_subcommand(
        "envmap",
        "parabolic environment maps with solid-angle mipmaps, prefiltered glossy and diffuse maps and "
        "Fresnel tables (Heidrich & Seidel 1999, section 4)");
    envmap->add_option("environment", em.input, "equirectangular (2:1) environment, OpenEXR, z up")
        ->required();
    envmap->add_option("-o,--output", em.output, "environment asset to write (.hemi)")->required();
    envmap->add_option("--size", em.options.size, "texels per side of each half at level 0 (a power of two)")
        ->capture_default_str();
    envmap
        ->add_option("--exponents", em.exponents,
                     "Phong exponents of the prefiltered glossy maps, comma-separated")
        ->capture_default_str();
    envmap->add_option("--ior", em.iors, "indices of refraction of the Fresnel tables, comma-separated")
        ->capture_default_str();
    envmap->add_option("--fresnel-samples", em.options.fresnel_samples, "samples of each Fresnel table")
        ->capture_default_str();
    envmap->add_flag(
        "--exact", em.options.exact,
        "prefilter by the brute-force sum over every texel of each lobe's cap (slow; the default "
        "sums coarser texels at every other texel, within 0.5% RMSE of it)");
    envmap->add_option("--exr-dir", em.exr_dir,
                       "also write every image (each half, mip level, exponent) as EXR into DIR");
    envmap->add_option("--report", em.report,
                       "write the sampling comparison with cube maps and the timings as JSON");
    ExportCli ex;
    CLI::App* exporter = app.add_subcommand(
        "export",
        "write a baked lightmap level as glTF 2.0 for engines and viewers without hemi: the plain "
        "lightmap as an RGBM PNG on TEXCOORD_1, every output under HEMI_lightmaps (docs/gltf_export.md)");
    exporter->add_option("level", ex.input, "lightmap asset (.hemi, from hemi-bake lightmap)")
        ->required()
        ->check(CLI::ExistingFile);
    exporter
        ->add_option("-o,--output", ex.output, "glTF file to write (.glb, or .gltf with its buffer embedded)")
        ->required();
    exporter
        ->add_option("--outputs", ex.outputs,
                     "the asset's outputs stored at full precision (half floats) under HEMI_lightmaps: all, "
                     "none, or comma-separated names (plain, rnm, sh9, ...)")
        ->capture_default_str();
    exporter
        ->add_option("--rgbm-range", ex.rgbm_range,
                     "the RGBM lightmap's range R (E = rgb * a * R); 0: the brightest texel's channel")
        ->capture_default_str()
        ->check(hemi::tool::finite(0.0, 1e30));
    const int code = hemi::tool::run(
        app, argc, argv, "hemi-bake",
        [&]() -> int
        {
            if (job && job->ranks() > 1 && !lightmap->parsed() && !prt->parsed() && !ssbump->parsed())
                throw std::invalid_argument("runs as one process: of the bakes, only lightmap, prt and "
                                            "ssbump are shared among mpirun's "
                                            "ranks so far "
                                            "(run this one without mpirun)");
            lm.options.bake.distribution = job.get();
            pc.options.bake.distribution = job.get();
            sb.options.distribution = job.get();
            if (exporter->parsed())
                return run_export(ex);
            if (brdf->parsed())
                return run_brdf(br);
            if (envmap->parsed())
                return run_envmap(em);
            if (reference->parsed())
                return run_reference(rf);
            if (lightmap->parsed())
                return run_lightmap(lm);
            if (ssbump->parsed())
                return run_ssbump(sb);
            if (prt->parsed())
                return run_prt(pc);
            return run_basis_report(json, plot, signals, seed);
        });
    if (job && code != 0)
        job->abort(code); // no rank waits for this one
    return code;
}
