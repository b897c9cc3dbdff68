#include <hemi/bake/basis_report.h>
#include <hemi/bake/gnuplot.h>

#include <hemi/io/atomic_file.h>
#include <hemi/math/basis.h>
#include <hemi/math/separable_basis.h>
#include <hemi/math/sh.h>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <stdexcept>

namespace hemi::bake
{
namespace
{

struct Signal
{
    double ambient = 0.0;
    int count = 0;
    glm::dvec3 dir[3];
    double intensity[3];
};

// See basis_report.h for the distribution. One generator per signal (seeded by seed and index) so that the
// result does not depend on how TBB splits the work.
Signal random_signal(uint64_t seed, int index)
{
    std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + uint64_t(index));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> g;
    Signal s;
    s.ambient = u(rng);
    s.count = 1 + std::min(2, int(u(rng) * 3.0));
    for (int k = 0; k < s.count; ++k)
    {
        glm::dvec3 d(g(rng), g(rng), g(rng));
        s.dir[k] = d / std::sqrt(glm::dot(d, d));
        s.intensity[k] = 0.1 * std::pow(100.0, u(rng));
    }
    return s;
}

// Exact SH9 irradiance coefficients of the signal: A_l (a 2 sqrt(pi) delta_l0 + sum_k I_k y_lm(d_k)).
std::array<double, 9> sh9_irradiance(const Signal& s)
{
    std::array<double, 9> c{};
    c[0] = s.ambient * 2.0 * std::sqrt(M_PI);
    for (int k = 0; k < s.count; ++k)
    {
        math::Sh9 y = math::sh9_eval(glm::vec3(s.dir[k]));
        for (int j = 0; j < 9; ++j)
            c[j] += s.intensity[k] * y[j];
    }
    for (int j = 0; j < 9; ++j)
        c[j] *= math::clamped_cosine_factor(j == 0 ? 0 : (j < 4 ? 1 : 2));
    return c;
}

double exact_irradiance(const Signal& s, const glm::dvec3& n)
{
    double e = M_PI * s.ambient;
    for (int k = 0; k < s.count; ++k)
        e += s.intensity[k] * std::max(0.0, glm::dot(n, s.dir[k]));
    return e;
}

} // namespace

BasisReport make_basis_report(int signals, uint64_t seed)
{
    if (signals < 1)
        throw std::invalid_argument("hemi: basis report needs at least one signal");
    BasisReport r;
    r.signals = signals;
    r.seed = seed;

    const auto all = math::bases();
    std::vector<std::vector<double>> projections;
    for (const math::BasisDesc& b : all)
    {
        projections.push_back(math::projection_from_sh9(b));
        if (b.id == HEMI_BASIS_SH9)
            continue; // the identity
        auto& rows = r.projection[std::string(b.name)];
        for (int i = 0; i < b.size; ++i)
            rows.emplace_back(projections.back().begin() + i * 9, projections.back().begin() + (i + 1) * 9);
    }
    for (const char* name : {"sal4", "hl2"})
        for (int j = 0; j < 9; ++j)
            r.sloan_table2[name].push_back(math::projection_error_of_sh9_function(math::basis(name), j));
    const math::SeparableSvd plain = math::separable_svd(false), folded = math::separable_svd(true);
    r.svd_singular_values.assign(plain.singular_values.begin(), plain.singular_values.end());
    r.svd_singular_values_convolved.assign(folded.singular_values.begin(), folded.singular_values.end());

    // Basis values at the quadrature nodes, once. The irradiance of point lights has a crease where
    // n . d = 0; 48 x 96 nodes put the quadrature error of the IMSE well below the differences reported.
    const std::vector<math::HemisphereSample> nodes = math::hemisphere_quadrature(48);
    const size_t nb = all.size();
    std::vector<std::vector<float>> values(nb);
    for (size_t b = 0; b < nb; ++b)
    {
        values[b].resize(nodes.size() * all[b].size);
        for (size_t i = 0; i < nodes.size(); ++i)
            all[b].eval(glm::vec3(nodes[i].n), &values[b][i * all[b].size]);
    }

    // Per-signal results land in their own slots and are summed in index order afterwards, so the report
    // is the same bytes whatever the thread count.
    std::vector<double> per_signal(size_t(signals) * (nb + 1), 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, signals, 64),
                      [&](const tbb::blocked_range<int>& range)
                      {
                          std::vector<double> exact(nodes.size());
                          for (int s = range.begin(); s != range.end(); ++s)
                          {
                              double* out = &per_signal[size_t(s) * (nb + 1)];
                              Signal sig = random_signal(seed, s);
                              std::array<double, 9> sh = sh9_irradiance(sig);
                              for (size_t i = 0; i < nodes.size(); ++i)
                              {
                                  exact[i] = exact_irradiance(sig, nodes[i].n);
                                  out[nb] += nodes[i].weight * exact[i] * exact[i];
                              }
                              for (size_t b = 0; b < nb; ++b)
                              {
                                  const int k = all[b].size;
                                  double coeff[HEMI_BASIS_MAX_SIZE] = {};
                                  for (int i = 0; i < k; ++i)
                                      for (int j = 0; j < 9; ++j)
                                          coeff[i] += projections[b][size_t(i) * 9 + j] * sh[j];
                                  double err = 0.0;
                                  for (size_t i = 0; i < nodes.size(); ++i)
                                  {
                                      double fit = 0.0;
                                      const float* v = &values[b][i * k];
                                      for (int m = 0; m < k; ++m)
                                          fit += coeff[m] * v[m];
                                      double d = fit - exact[i];
                                      err += nodes[i].weight * d * d;
                                  }
                                  out[b] = err;
                              }
                          }
                      });
    struct Sums
    {
        std::vector<double> imse;
        double energy = 0.0;
    } total{std::vector<double>(nb, 0.0), 0.0};
    for (int s = 0; s < signals; ++s)
    {
        const double* row = &per_signal[size_t(s) * (nb + 1)];
        for (size_t b = 0; b < nb; ++b)
            total.imse[b] += row[b];
        total.energy += row[nb];
    }
    for (size_t b = 0; b < nb; ++b)
    {
        BasisErrorStats& st = r.imse[std::string(all[b].name)];
        st.coefficients = all[b].size;
        st.mean_imse = total.imse[b] / signals;
        st.rel_rms = std::sqrt(total.imse[b] / total.energy);
    }
    return r;
}

void write_basis_report_json(const std::string& path, const BasisReport& r)
{
    nlohmann::json j;
    j["signals"] = r.signals;
    j["seed"] = r.seed;
    j["projection"] = r.projection;
    j["sloan_table2"] = r.sloan_table2;
    for (const auto& [name, st] : r.imse)
        j["imse"][name] = {
            {"mean", st.mean_imse}, {"rel_rms", st.rel_rms}, {"coefficients", st.coefficients}};
    j["svd_singular_values"] = {{"A", r.svd_singular_values},
                                {"A_convolved", r.svd_singular_values_convolved}};
    io::write_text_atomically(path, j.dump(2) + "\n");
}

void plot_basis_report(const std::string& png_path, const BasisReport& r)
{
    namespace fs = std::filesystem;
    run_gnuplot(
        png_path,
        [&](const fs::path& dir, std::ostream& script, const fs::path& output)
        {
            // Bases with the same count crowd one column: merge identical points (h4 = sh4ls) and put the
            // labels of a column alternately left and right of their points, in order of error.
            std::map<int, std::vector<std::pair<double, std::string>>> columns;
            for (const auto& [name, st] : r.imse)
            {
                auto& col = columns[st.coefficients];
                bool merged = false;
                for (auto& [value, label] : col)
                    if (std::abs(value - st.mean_imse) <= 1e-9 * std::abs(value))
                    {
                        label += " = " + name;
                        merged = true;
                    }
                if (!merged)
                    col.push_back({st.mean_imse, name});
            }
            std::ofstream data(dir / "imse.dat");
            script << "set terminal pngcairo size 900,600 noenhanced font 'Sans,11'\n"
                   << "set output '" << output.string() << "'\n"
                   << "set title 'Mean IMSE over the hemisphere of " << r.signals
                   << " random irradiance signals (cf. Habel and Wimmer 2010, Fig. 3)'\n"
                   << "set xlabel 'number of coefficients'\nset ylabel 'mean integrated squared error'\n"
                   << "set logscale y\nset xrange [2:10]\nset xtics 1\nset grid\nunset key\n";
            for (auto& [count, col] : columns)
            {
                std::sort(col.begin(), col.end());
                for (size_t i = 0; i < col.size(); ++i)
                {
                    data << count << " " << col[i].first << "\n";
                    bool right = i % 2 == 0;
                    script << "set label '" << col[i].second << "' at " << count << "," << col[i].first
                           << (right ? " left offset 1,0" : " right offset -1,0") << "\n";
                }
            }
            script << "plot '" << (dir / "imse.dat").string()
                   << "' using 1:2 with points pt 7 ps 1.5 lc rgb '#3060c0'\n";
        });
}

} // namespace hemi::bake
