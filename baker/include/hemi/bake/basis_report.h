#pragma once
// The numbers behind `hemi-bake basis-report`: every basis's projection from SH9, Sloan 2006 Table 2, the
// singular values of the separable basis, and Habel & Wimmer 2010 Fig. 3 re-measured: the mean integrated
// squared error (IMSE) over the hemisphere of representing random irradiance signals in each basis.
//
// The random signals (Habel does not say how his were made; this is ours, documented and seeded):
// radiance in tangent space = a constant ambient term a ~ U[0, 1] plus 1 to 3 directional lights with
// directions uniform on the sphere and HDR intensities log-uniform in [0.1, 10] (W/m^2 at normal
// incidence). Its irradiance is exact in closed form, E(n) = pi a + sum_k I_k max(0, n . d_k): the "fully
// correct irradiance" of Habel's Eq. (16). Each basis receives what a bake would give it: the exact SH9
// irradiance coefficients (L_lm = I_k y_lm(d_k), times A_l), projected with the basis's matrix. IMSE is
// int_H (fit - E)^2 by quadrature; rel_rms = sqrt(sum IMSE / sum int_H E^2) over all signals.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace hemi::bake
{

struct BasisErrorStats
{
    int coefficients = 0;
    double mean_imse = 0.0;
    double rel_rms = 0.0;
};

struct BasisReport
{
    std::map<std::string, std::vector<std::vector<double>>> projection; // basis -> K rows of 9
    std::map<std::string, std::vector<double>> sloan_table2;            // "sal4", "hl2" -> 9 values
    std::map<std::string, BasisErrorStats> imse;                        // every basis incl. "sh9"
    std::vector<double> svd_singular_values;                            // A
    std::vector<double> svd_singular_values_convolved;                  // A C
    int signals = 0;
    uint64_t seed = 0;
};

// Deterministic for a given (signals, seed) and standard library (std::normal_distribution's algorithm is
// the library's), whatever the thread count; multi-threaded. Throws std::invalid_argument for signals < 1.
BasisReport make_basis_report(int signals, uint64_t seed);

// JSON with the keys "projection", "sloan_table2", "imse" ({"mean", "rel_rms", "coefficients"} per basis),
// "svd_singular_values" ({"A": [...], "A_convolved": [...]}), "signals", "seed". Written atomically.
void write_basis_report_json(const std::string& path, const BasisReport& report);

// Habel's Fig. 3: mean IMSE against the number of coefficients, one labelled point per basis, drawn by
// gnuplot (pngcairo). Throws std::runtime_error naming the file when gnuplot is missing or fails.
void plot_basis_report(const std::string& png_path, const BasisReport& report);

} // namespace hemi::bake
