// hemi-bake: the offline side of hemi as a command line. Subcommands:
//   basis-report [--json FILE] [--plot FILE.png] [--signals N] [--seed S]
#include <hemi/bake/basis_report.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>

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
    CLI11_PARSE(app, argc, argv);

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
