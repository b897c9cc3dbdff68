// hemi-bake: the offline side of hemi as a command line. Subcommands:
//   basis-report [--json FILE] [--plot FILE.png] [--signals N] [--seed S]
//   prt SCENE.gltf|.glb -o ASSET.hemi [--bases ...] [--transfer ...] [--bounces B] [--order N] [--rays R]
//       [--seed S] [--albedo A] [--cpca CxV] [--json REPORT.json]
#include <hemi/bake/basis_report.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/io/atomic_file.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <unistd.h>
#include <sstream>
#include <string>
#include <vector>

namespace
{
const char* kRows[9] = {"y0,0", "y1,-1", "y1,0", "y1,1", "y2,-2", "y2,-1", "y2,0", "y2,1", "y2,2"};

void print_report(const hemi::bake::BasisReport& r)
{
    std::printf("Projection matrices from SH9 irradiance (hemispherical least squares), rows = basis functions\n");
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
// Progress on stderr: one line rewritten in place, with the ETA over all passes.
class ProgressLine
{
public:
    void operator()(const hemi::bake::PrtBakeProgress& p)
    {
        if (!p.checkpoint_error.empty() && !checkpoint_reported_)
        {
            // When it happens, not after the bake: the user may want to free space and restart.
            std::fprintf(stderr, "%shemi-bake prt: warning: checkpoints stopped: %s\n", tty_ ? "\n" : "",
                         p.checkpoint_error.c_str());
            checkpoint_reported_ = true;
        }
        using clock = std::chrono::steady_clock;
        const double fraction =
            (p.pass + (p.vertex_count ? double(p.vertices_done) / double(p.vertex_count) : 1.0)) / p.passes;
        const double elapsed = std::chrono::duration<double>(clock::now() - start_).count();
        const char* what = p.pass == 0 ? "visibility" : "bounce";
        char eta[32] = "";
        if (fraction > 0.02 && fraction < 1.0)
            std::snprintf(eta, sizeof eta, ", ETA %.0f s", elapsed * (1.0 - fraction) / fraction);
        const bool done = p.pass + 1 == p.passes && p.vertices_done == p.vertex_count;
        // On a terminal one line is rewritten in place; in a log, a line per 10% (and the last).
        const int decile = int(fraction * 10.0);
        if (!tty_ && decile == last_decile_ && !done)
            return;
        last_decile_ = decile;
        std::fprintf(stderr, "%shemi-bake prt: pass %d/%d (%s%s) %5.1f%%%s%s", tty_ ? "\r" : "", p.pass + 1,
                     p.passes, what, p.pass == 0 ? "" : (" " + std::to_string(p.pass)).c_str(), 100.0 * fraction,
                     eta, tty_ ? "      " : "\n");
        if (done && tty_)
            std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
    bool tty_ = isatty(fileno(stderr)) != 0;
    int last_decile_ = -1;
    bool checkpoint_reported_ = false;

public:
    bool checkpoint_reported() const { return checkpoint_reported_; }
};

std::vector<std::string> split(const std::string& list)
{
    std::vector<std::string> out;
    std::stringstream in(list);
    for (std::string item; std::getline(in, item, ',');)
        if (!item.empty())
            out.push_back(item);
    return out;
}

void print_prt_summary(const hemi::bake::PrtBakeSummary& s, const hemi::bake::PrtAssetOptions& o,
                       const std::string& scene, const std::string& asset)
{
    for (const std::string& w : s.warnings)
        std::fprintf(stderr, "hemi-bake: warning: %s: %s\n", scene.c_str(), w.c_str());
    std::printf("baked %s: %u vertices, %u triangles, %s transfer, order %d (L = %d)", asset.c_str(), s.vertices,
                s.triangles, std::string(hemi::bake::to_string(o.bake.kind)).c_str(), o.bake.order,
                o.bake.order * o.bake.order);
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
        std::printf("resumed from a checkpoint at pass %d, vertex %u\n", s.resumed_pass + 1, s.resumed_vertex);
    if (!s.checkpoint_error.empty())
        std::fprintf(stderr, "hemi-bake prt: warning: checkpoints stopped: %s\n", s.checkpoint_error.c_str());
    std::printf("rays: %llu in %.2f s = %.2f Mrays/s; total %.2f s\n", (unsigned long long)s.rays, s.trace_seconds,
                s.rays_per_second() * 1e-6, s.total_seconds);
    std::printf("  %-6s %3s %12s", "tech", "K", "dense MB");
    if (o.cpca_clusters)
        std::printf(" %10s %12s %12s", "CPCA MB", "CPCA RMS", "relative");
    std::printf("\n");
    for (const auto& t : s.techniques)
    {
        std::printf("  %-6s %3d %12.2f", t.name.c_str(), t.k, double(t.dense_bytes) / 1048576.0);
        if (o.cpca_clusters)
            std::printf(" %10.2f %12.3e %12.3e", double(t.cpca_bytes) / 1048576.0, t.cpca_rms, t.cpca_relative);
        std::printf("\n");
    }
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"hemi-bake: precompute lighting data for hemi"};
    app.require_subcommand(1);

    std::string json, plot;
    int signals = 10000;
    uint64_t seed = 1;
    CLI::App* report = app.add_subcommand("basis-report", "compare the hemispherical bases (Sloan 2006, Habel 2010)");
    report->add_option("--json", json, "write the report as JSON to FILE");
    report->add_option("--plot", plot, "draw Habel's Fig. 3 (mean IMSE vs coefficients) into FILE.png with gnuplot");
    report->add_option("--signals", signals, "number of random irradiance signals")->check(CLI::Range(1, 10000000))
        ->capture_default_str();
    report->add_option("--seed", seed, "seed of the random signals")->capture_default_str();

    std::string scene, asset, bases, transfer = "interreflected", cpca, prt_json;
    hemi::bake::PrtAssetOptions prt_options;
    {
        std::string all;
        for (const auto& t : hemi::bake::default_techniques())
            all += (all.empty() ? "" : ",") + t;
        bases = all;
    }
    CLI::App* prt = app.add_subcommand("prt", "bake per-vertex PRT transfer matrices (Sloan 2006) from a glTF scene");
    prt->add_option("scene", scene, "glTF 2.0 scene (.gltf or .glb)")->required()->check(CLI::ExistingFile);
    prt->add_option("-o,--output", asset, "baked asset to write (.hemi)")->required();
    prt->add_option("--bases", bases, "comma-separated techniques: gs (SH9, the gold standard), hl2, sal4, h4, h6, "
                                      "sep4, prt (classic PRT, no normal map); also sh4ls, zernike3, zernike6")
        ->capture_default_str();
    prt->add_option("--transfer", transfer, "unshadowed | shadowed | interreflected")->capture_default_str();
    prt->add_option("--bounces", prt_options.bake.bounces, "interreflection bounces")->check(CLI::Range(0, 16))
        ->capture_default_str();
    prt->add_option("--order", prt_options.bake.order, "lighting SH order n (L = n^2)")->check(CLI::Range(3, 6))
        ->capture_default_str();
    prt->add_option("--rays", prt_options.bake.rays, "rays per vertex")->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    prt->add_option("--seed", prt_options.bake.seed, "seed of the ray directions (same seed, same bytes)")
        ->capture_default_str();
    prt->add_option("--albedo", prt_options.bake.albedo, "grey albedo for interreflection, in [0, 1)")
        ->capture_default_str();
    prt->add_option("--cpca", cpca, "compress with CPCA: CLUSTERSxVECTORS, e.g. 1x24 (dense matrices are kept)");
    prt->add_option("--json", prt_json, "write the bake summary as JSON to FILE");
    prt->add_option("--checkpoint-interval", prt_options.bake.checkpoint_seconds,
                    "seconds between checkpoints to ASSET.partial (an interrupted bake resumes from it)")
        ->check(CLI::Range(0.0, 1e9))
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    if (prt->parsed())
    {
        try
        {
            prt_options.bake.kind = hemi::bake::parse_transfer_kind(transfer);
            prt_options.techniques = split(bases);
            if (!cpca.empty())
            {
                unsigned c = 0, v = 0;
                char x = 0, rest = 0;
                if (std::sscanf(cpca.c_str(), "%u%c%u%c", &c, &x, &v, &rest) != 3 || x != 'x' || c == 0 || v == 0)
                    throw std::invalid_argument("--cpca expects CLUSTERSxVECTORS (e.g. 1x24), got '" + cpca + "'");
                prt_options.cpca_clusters = c;
                prt_options.cpca_vectors = v;
            }
            if (!prt_json.empty())
                hemi::io::check_writable(prt_json); // before the bake, like the asset and its checkpoint
            ProgressLine line;
            hemi::bake::PrtBakeSummary s = hemi::bake::bake_prt_file(scene, asset, prt_options, std::ref(line));
            print_prt_summary(s, prt_options, scene, asset);
            if (!prt_json.empty())
            {
                hemi::bake::write_prt_bake_json(prt_json, s, prt_options);
                std::printf("wrote %s\n", prt_json.c_str());
            }
        }
        catch (const std::exception& e)
        {
            std::fprintf(stderr, "\nhemi-bake prt: %s\n", e.what());
            return 1;
        }
        return 0;
    }

    try
    {
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
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "hemi-bake: %s\n", e.what());
        return 1;
    }
    return 0;
}
