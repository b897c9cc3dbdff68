#include <hemi/bake/lightmap_denoise.h>
#include <hemi/math/luminance.h>

#include <glm/geometric.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

namespace
{
uint32_t find(std::vector<uint32_t>& parent, uint32_t i)
{
    while (parent[i] != i)
        i = parent[i] = parent[parent[i]];
    return i;
}
} // namespace

std::vector<uint32_t> lightmap_charts(const io::Mesh& mesh, size_t* count)
{
    if (mesh.uvs1.size() != mesh.positions.size())
        throw std::invalid_argument("lightmap charts need lightmap UVs (TEXCOORD_1) at every vertex");
    // Each vertex's (position, UV) bits name its UV-space vertex; triangles join through them.
    std::map<std::array<uint32_t, 5>, uint32_t> key_of;
    std::vector<uint32_t> vertex(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v)
    {
        std::array<uint32_t, 5> key;
        std::memcpy(key.data(), &mesh.positions[v], 12);
        std::memcpy(key.data() + 3, &mesh.uvs1[v], 8);
        vertex[v] = key_of.emplace(key, uint32_t(key_of.size())).first->second;
    }
    std::vector<uint32_t> parent(key_of.size());
    std::iota(parent.begin(), parent.end(), 0u);
    const size_t triangles = mesh.indices.size() / 3;
    for (size_t t = 0; t < triangles; ++t)
        for (int e = 1; e < 3; ++e)
        {
            const uint32_t a = find(parent, vertex[mesh.indices[3 * t]]),
                           b = find(parent, vertex[mesh.indices[3 * t + size_t(e)]]);
            if (a != b)
                parent[std::max(a, b)] = std::min(a, b);
        }
    std::vector<uint32_t> chart(triangles), number(parent.size(), UINT32_MAX);
    uint32_t charts = 0;
    for (size_t t = 0; t < triangles; ++t)
    {
        const uint32_t root = find(parent, vertex[mesh.indices[3 * t]]);
        if (number[root] == UINT32_MAX)
            number[root] = charts++;
        chart[t] = number[root];
    }
    if (count)
        *count = charts;
    return chart;
}

LightmapDenoiseReport denoise_lightmap(const io::Mesh& mesh, const LightmapAtlas& atlas, LightmapSh& sh,
                                       const LightmapDenoiseOptions& o)
{
    const size_t n = atlas.texels.size();
    if (sh.irradiance.size() != n || sh.direct.size() != n || sh.half.size() != n || sh.valid.size() != n)
        throw std::invalid_argument(
            "denoising needs a bake's irradiance, direct values, half-sample values and "
            "validity for each of the atlas's " +
            std::to_string(n) + " texels");
    if (o.iterations < 0 || o.iterations > 10 || !(o.sigma_luminance > 0.0f) || !(o.sigma_normal > 0.0f) ||
        !(o.sigma_plane > 0.0f))
        throw std::invalid_argument("denoising needs 0 to 10 iterations and positive sigmas");
    LightmapDenoiseReport report;
    const std::vector<uint32_t> chart_of_triangle = lightmap_charts(mesh, &report.charts);
    std::vector<uint32_t> chart(n);
    for (size_t i = 0; i < n; ++i)
    {
        chart[i] = chart_of_triangle[atlas.texels[i].triangle];
        report.texels += sh.valid[i] != 0;
    }

    // Every value of a texel in one row, SH9 (27 floats) then plain's and rnm's (12), for each half of its
    // samples: half[0] is A, half[1] is B = the whole less A.
    constexpr size_t kValues = 39;
    using Guide = std::array<float, 4>; // luminance of E at the normal and of SH9's band-1 coefficients
    std::array<std::vector<float>, 2> half, next;
    for (auto& h : half)
        h.resize(n * kValues);
    for (auto& h : next)
        h.resize(n * kValues);
    for (size_t i = 0; i < n; ++i)
    {
        float* a = &half[0][i * kValues];
        float* b = &half[1][i * kValues];
        std::memcpy(a, sh.half[i].data(), kValues * sizeof(float));
        std::memcpy(b, sh.irradiance[i].data(), 27 * sizeof(float));
        std::memcpy(b + 27, sh.direct[i].data(), 12 * sizeof(float));
        for (size_t c = 0; c < kValues; ++c)
            b[c] -= a[c];
    }
    // Each half's guides, and the variance of a half's guide: (A - B)^2 / 2 to begin with (A and B are two
    // independent estimates of the same), then what each pass leaves of it (sum l_j^2 v_j).
    std::array<std::vector<Guide>, 2> guide{std::vector<Guide>(n), std::vector<Guide>(n)};
    std::array<std::vector<Guide>, 2> variance{std::vector<Guide>(n), std::vector<Guide>(n)};
    std::array<std::vector<Guide>, 2> next_variance{std::vector<Guide>(n), std::vector<Guide>(n)};
    std::vector<Guide> smooth(n); // a half's variance averaged over the texel's 3 x 3 neighbours
    static constexpr float kSpline[5] = {1.0f / 16, 4.0f / 16, 6.0f / 16, 4.0f / 16, 1.0f / 16};
    const auto guides_of = [&](int h)
    {
        for (size_t i = 0; i < n; ++i)
        {
            const float* v = &half[size_t(h)][i * kValues];
            guide[size_t(h)][i] = {
                math::luminance(glm::vec3(v[27], v[28], v[29])), math::luminance(glm::vec3(v[3], v[4], v[5])),
                math::luminance(glm::vec3(v[6], v[7], v[8])), math::luminance(glm::vec3(v[9], v[10], v[11]))};
        }
    };
    guides_of(0);
    guides_of(1);
    for (size_t i = 0; i < n; ++i)
        for (size_t c = 0; c < 4; ++c)
        {
            const float d = guide[0][i][c] - guide[1][i][c];
            variance[0][i][c] = variance[1][i][c] = 0.5f * d * d;
        }

    for (int pass = 0; pass < o.iterations; ++pass)
    {
        const int step = 1 << pass;
        // Half h is filtered with weights from the other half's guides (w): a weight taken from the same
        // noise as the value it weighs is biased where the noise is skewed (importance-sampled light: most
        // samples dim, a few bright), since it keeps a dim texel from its brighter neighbours and lets a
        // bright one take its dimmer ones; the other half's noise is independent of it.
        for (int h = 0; h < 2; ++h)
        {
            const size_t w = size_t(1 - h);
            const std::vector<Guide>& g = guide[w];
            const std::vector<Guide>& gv = variance[w];
            tbb::parallel_for(size_t(0), n,
                              [&](size_t i)
                              {
                                  smooth[i] = {};
                                  if (!sh.valid[i])
                                      return;
                                  const LightmapTexel& t = atlas.texels[i];
                                  std::array<double, 4> sum{};
                                  double weights = 0.0;
                                  for (int dy = -1; dy <= 1; ++dy)
                                      for (int dx = -1; dx <= 1; ++dx)
                                      {
                                          const int32_t j =
                                              atlas.texel_of(int64_t(t.x) + dx, int64_t(t.y) + dy);
                                          if (j < 0 || !sh.valid[size_t(j)] || chart[size_t(j)] != chart[i])
                                              continue;
                                          const double k = (2 - std::abs(dx)) * (2 - std::abs(dy));
                                          for (size_t c = 0; c < 4; ++c)
                                              sum[c] += k * double(gv[size_t(j)][c]);
                                          weights += k;
                                      }
                                  for (size_t c = 0; c < 4; ++c)
                                      smooth[i][c] = float(sum[c] / weights);
                              });
            tbb::parallel_for(
                size_t(0), n,
                [&](size_t i)
                {
                    float* out = &next[size_t(h)][i * kValues];
                    if (!sh.valid[i])
                    {
                        std::memcpy(out, &half[size_t(h)][i * kValues], kValues * sizeof(float));
                        next_variance[size_t(h)][i] = variance[size_t(h)][i];
                        return;
                    }
                    const LightmapTexel& t = atlas.texels[i];
                    const float size = std::max(t.world_size, 1e-30f);
                    // The light's term for neighbour j whose guides differ by `difference` (from the
                    // centre's, or from the fitted planes): its worst guide, in standard deviations of the
                    // two texels' noise together (the same both ways); 0 where the weighing half's guide has
                    // no variance at the centre and the neighbour's differs from it at all (a sealed room,
                    // black in both halves everywhere, stays black; a texel black only by chance, where the
                    // light is dim, takes neighbours that are black in the weighing half, whatever the other
                    // half saw, so that dim light is not lost to the texels that happened to miss it).
                    const auto light_weight = [&](size_t j, const std::array<double, 4>& difference)
                    {
                        double worst = 0.0;
                        for (size_t c = 0; c < 4; ++c)
                        {
                            if (gv[i][c] > 0.0f)
                            {
                                const double sd =
                                    double(o.sigma_luminance) *
                                    std::sqrt(0.5 * (double(smooth[i][c]) + double(smooth[j][c])));
                                worst = std::max(worst, std::abs(difference[c]) / sd);
                            }
                            else if (g[j][c] != g[i][c])
                                return 0.0;
                        }
                        return std::exp(-worst);
                    };
                    // The neighbours that weigh anything, with their offsets (in texels of this pass's
                    // spacing).
                    struct Neighbour
                    {
                        size_t j;
                        double w, dx, dy, base; // base: w without the light's term
                    };
                    std::array<Neighbour, 25> used;
                    size_t count = 0;
                    for (int dy = -2; dy <= 2; ++dy)
                        for (int dx = -2; dx <= 2; ++dx)
                        {
                            const int32_t j =
                                atlas.texel_of(int64_t(t.x) + dx * step, int64_t(t.y) + dy * step);
                            if (j < 0 || !sh.valid[size_t(j)] || chart[size_t(j)] != chart[i])
                                continue;
                            const LightmapTexel& u = atlas.texels[size_t(j)];
                            double weight = double(kSpline[dx + 2] * kSpline[dy + 2]), base = weight;
                            if (size_t(j) != i)
                            {
                                const glm::vec3 d = u.position - t.position;
                                const float reach = 1.5f * float(step) * std::sqrt(float(dx * dx + dy * dy)) *
                                                        std::max(size, u.world_size) +
                                                    size;
                                if (glm::dot(d, d) > reach * reach)
                                    continue;
                                weight *= std::exp(-std::abs(glm::dot(d, t.geometric_normal)) /
                                                   (o.sigma_plane * size));
                                weight *=
                                    std::pow(std::max(0.0f, glm::dot(t.normal, u.normal)), o.sigma_normal);
                                base = weight;
                                std::array<double, 4> difference;
                                for (size_t c = 0; c < 4; ++c)
                                    difference[c] = double(g[size_t(j)][c]) - double(g[i][c]);
                                weight *= light_weight(size_t(j), difference);
                                if (!(weight > 0.0))
                                    continue;
                            }
                            used[count++] = {size_t(j), weight, double(dx), double(dy), base};
                        }
                    // A weighted first-order fit v ~ b0 + b1 dx + b2 dy; the texel takes b0 = sum l_j v_j
                    // (lightmap_denoise.h), and where the weighing half's noise is known, the light's term
                    // is taken again against its guides' fitted planes and the fit repeated.
                    std::array<double, 25> l;
                    const bool refit = gv[i] != Guide{};
                    for (int fit = 0; fit < (refit ? 2 : 1); ++fit)
                    {
                        double m[3][3] = {};
                        for (size_t k = 0; k < count; ++k)
                        {
                            const double x[3] = {1.0, used[k].dx, used[k].dy};
                            for (int r = 0; r < 3; ++r)
                                for (int c = 0; c < 3; ++c)
                                    m[r][c] += used[k].w * x[r] * x[c];
                        }
                        m[1][1] += 1e-2 * m[0][0];
                        m[2][2] += 1e-2 * m[0][0];
                        // m's inverse (symmetric: cofactors over the determinant).
                        const double i00 = m[1][1] * m[2][2] - m[1][2] * m[2][1],
                                     i01 = m[0][2] * m[2][1] - m[0][1] * m[2][2],
                                     i02 = m[0][1] * m[1][2] - m[0][2] * m[1][1],
                                     i11 = m[0][0] * m[2][2] - m[0][2] * m[2][0],
                                     i12 = m[0][2] * m[1][0] - m[0][0] * m[1][2],
                                     i22 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
                        const double det = m[0][0] * i00 + m[0][1] * i01 + m[0][2] * i02;
                        double total = 0.0;
                        for (size_t k = 0; k < count; ++k)
                        {
                            l[k] = used[k].w * (i00 + i01 * used[k].dx + i02 * used[k].dy);
                            total += l[k];
                        }
                        for (size_t k = 0; k < count; ++k)
                            l[k] /= total;
                        if (fit == 1 || !refit)
                            break;
                        std::array<std::array<double, 3>, 4> plane{};
                        for (size_t c = 0; c < 4; ++c)
                        {
                            double r[3] = {};
                            for (size_t k = 0; k < count; ++k)
                            {
                                const double y = used[k].w * double(g[used[k].j][c]);
                                r[0] += y;
                                r[1] += y * used[k].dx;
                                r[2] += y * used[k].dy;
                            }
                            plane[c] = {(i00 * r[0] + i01 * r[1] + i02 * r[2]) / det,
                                        (i01 * r[0] + i11 * r[1] + i12 * r[2]) / det,
                                        (i02 * r[0] + i12 * r[1] + i22 * r[2]) / det};
                        }
                        for (size_t k = 0; k < count; ++k)
                        {
                            if (used[k].j == i)
                                continue;
                            std::array<double, 4> difference;
                            for (size_t c = 0; c < 4; ++c)
                                difference[c] = double(g[used[k].j][c]) - plane[c][0] -
                                                plane[c][1] * used[k].dx - plane[c][2] * used[k].dy;
                            used[k].w = used[k].base * light_weight(used[k].j, difference);
                        }
                    }
                    std::array<double, kValues> sum{};
                    std::array<double, 4> v{};
                    for (size_t k = 0; k < count; ++k)
                    {
                        const float* value = &half[size_t(h)][used[k].j * kValues];
                        for (size_t c = 0; c < kValues; ++c)
                            sum[c] += l[k] * double(value[c]);
                        for (size_t c = 0; c < 4; ++c)
                            v[c] += l[k] * l[k] * double(variance[size_t(h)][used[k].j][c]);
                    }
                    for (size_t c = 0; c < kValues; ++c)
                        out[c] = float(sum[c]);
                    for (size_t c = 0; c < 4; ++c)
                        next_variance[size_t(h)][i][c] = float(v[c]);
                });
        }
        for (int h = 0; h < 2; ++h)
        {
            half[size_t(h)].swap(next[size_t(h)]);
            variance[size_t(h)].swap(next_variance[size_t(h)]);
            guides_of(h);
        }
    }
    for (size_t i = 0; i < n; ++i)
    {
        float whole[kValues];
        for (size_t c = 0; c < kValues; ++c)
            whole[c] = half[0][i * kValues + c] + half[1][i * kValues + c];
        // Irradiance integrated directly (plain, rnm) is never negative; an extrapolating fit could make it
        // so.
        for (size_t c = 27; c < kValues; ++c)
            whole[c] = std::max(whole[c], 0.0f);
        std::memcpy(sh.irradiance[i].data(), whole, 27 * sizeof(float));
        std::memcpy(sh.direct[i].data(), whole + 27, 12 * sizeof(float));
        std::memcpy(sh.half[i].data(), &half[0][i * kValues], kValues * sizeof(float));
    }
    return report;
}

} // namespace hemi::bake
