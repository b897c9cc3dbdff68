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
#include <span>
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

namespace
{
// Lets a vector's memory go (assigning {} would keep its capacity).
template <class T> void release(std::vector<T>& v)
{
    std::vector<T>().swap(v);
}

// A range of texels' values, laid out as LightmapSh holds them: SH9 (27 floats) and plain's and rnm's (12).
using ShArray = std::array<glm::vec3, 9>;
using DirectArray = std::array<glm::vec3, 4>;
struct Values
{
    std::vector<ShArray> irradiance;
    std::vector<DirectArray> direct;
};

// The guides a neighbour's light is compared by: the luminance of the irradiance at the normal (plain) and of
// SH9's three band-1 coefficients (the light's direction); LightmapSh::noise holds the variance of each.
using Guide = std::array<float, 4>;
Guide guides_of(const ShArray& irradiance, const DirectArray& direct)
{
    return {math::luminance(direct[0]), math::luminance(irradiance[1]), math::luminance(irradiance[2]),
            math::luminance(irradiance[3])};
}

// Filters texels [first, first + n) of the atlas, `values`, in place, with `noise` the variance of each
// texel's guides (LightmapSh::noise); texels outside the range count as absent. The passes alternate between
// `values` and a second copy of them; everything is allocated before `values` is written, so that on a
// failure to allocate it is as it was. Plain and rnm come out >= 0; each chart's light is restored by the
// caller.
void filter_range(const LightmapAtlas& atlas, const std::vector<uint32_t>& chart,
                  const std::vector<uint8_t>& valid, size_t first, size_t n, Values& values,
                  const LightmapSh::Noise* noise, const LightmapDenoiseOptions& o)
{
    // Calls f(j, dx, dy) for each valid texel j of i's chart in the range at (dx, dy) texels of `step` from
    // it (i and j: indices in the range).
    const auto each_in_chart = [&](size_t i, int radius, int step, auto&& f)
    {
        const LightmapTexel& t = atlas.texels[first + i];
        for (int dy = -radius; dy <= radius; ++dy)
            for (int dx = -radius; dx <= radius; ++dx)
            {
                const int64_t j = atlas.texel_of(int64_t(t.x) + dx * step, int64_t(t.y) + dy * step);
                if (j >= int64_t(first) && j < int64_t(first + n) && valid[size_t(j)] &&
                    chart[size_t(j)] == chart[first + i])
                    f(size_t(j) - first, dx, dy);
            }
    };

    // Each texel's guides, and their noise: the variance of the bake's estimate of each.
    std::vector<Guide> guide(n), variance(n);
    Values second{std::vector<ShArray>(n), std::vector<DirectArray>(n)};
    Values *current = &values, *other = &second;
    for (size_t i = 0; i < n; ++i)
    {
        guide[i] = guides_of(values.irradiance[i], values.direct[i]);
        variance[i] = noise[i];
    }
    // One texel's guides are single draws: they are prefiltered over the texel's 3 x 3 neighbours in its
    // chart with weights (1, 2, 1) x (1, 2, 1), and their variance with them (the weights squared), so that
    // the weights below compare light, not the noise of single texels. x over texel i's 3 x 3 neighbours in
    // its chart, weighted by (1, 2, 1) x (1, 2, 1) normalised (power 1), or by their squares over the squared
    // sum (power 2: the variance of such a mean).
    const auto binomial = [&](const std::vector<Guide>& x, size_t i, int power)
    {
        std::array<double, 4> sum{};
        double weights = 0.0;
        each_in_chart(i, 1, 1,
                      [&](size_t j, int dx, int dy)
                      {
                          const double k = (2 - std::abs(dx)) * (2 - std::abs(dy));
                          for (size_t c = 0; c < 4; ++c)
                              sum[c] += (power == 2 ? k * k : k) * double(x[j][c]);
                          weights += k;
                      });
        Guide mean;
        for (size_t c = 0; c < 4; ++c)
            mean[c] = float(sum[c] / (power == 2 ? weights * weights : weights));
        return mean;
    };
    {
        std::vector<Guide> g(guide), v(variance);
        tbb::parallel_for(size_t(0), n,
                          [&](size_t i)
                          {
                              if (valid[first + i])
                              {
                                  g[i] = binomial(guide, i, 1);
                                  v[i] = binomial(variance, i, 2);
                              }
                          });
        guide.swap(g);
        variance.swap(v);
    }

    std::vector<Guide> next_guide(n), next_variance(n), smooth(n);
    static constexpr float kSpline[5] = {1.0f / 16, 4.0f / 16, 6.0f / 16, 4.0f / 16, 1.0f / 16};
    const double k2 = double(o.sigma_light) * double(o.sigma_light);
    for (int pass = 0; pass < o.iterations; ++pass)
    {
        const int step = 1 << pass;
        // The variance the light's term divides by: each texel's, averaged over its 3 x 3 neighbours.
        tbb::parallel_for(size_t(0), n,
                          [&](size_t i)
                          { smooth[i] = valid[first + i] ? binomial(variance, i, 1) : Guide{}; });
        tbb::parallel_for(
            size_t(0), n,
            [&](size_t i)
            {
                if (!valid[first + i])
                {
                    other->irradiance[i] = current->irradiance[i];
                    other->direct[i] = current->direct[i];
                    next_guide[i] = guide[i];
                    next_variance[i] = variance[i];
                    return;
                }
                const LightmapTexel& t = atlas.texels[first + i];
                const float size = std::max(t.world_size, 1e-30f);
                // The light's term for neighbour j whose guides differ by `difference` (from the centre's, or
                // from the fitted planes): exp(-max(0, D)) with D the mean over the guides of the squared
                // difference less what the two texels' noise explains, in units of that noise (the
                // non-local means distance of Rousselle, Knaus and Zwicker 2012): about 0 for a neighbour
                // whose light differs from the centre's by noise only, growing with the square of a real
                // difference. A guide without variance at the centre (its samples agreed, as in a sealed room
                // where none saw light) admits only neighbours with exactly its value.
                const auto light_weight = [&](size_t j, const std::array<double, 4>& difference)
                {
                    double distance = 0.0;
                    int counted = 0;
                    for (size_t c = 0; c < 4; ++c)
                    {
                        if (variance[i][c] > 0.0f)
                        {
                            const double vi = smooth[i][c], vj = smooth[j][c];
                            distance += (difference[c] * difference[c] - (vi + std::min(vi, vj))) /
                                        (k2 * (vi + vj) + 1e-30);
                            ++counted;
                        }
                        else if (guide[j][c] != guide[i][c])
                            return 0.0;
                    }
                    return counted && distance > 0.0 ? std::exp(-distance / counted) : 1.0;
                };
                // The neighbours that weigh anything, with their offsets (in texels of this pass's spacing).
                struct Neighbour
                {
                    size_t j;
                    double w, dx, dy, base; // base: w without the light's term
                };
                std::array<Neighbour, 25> used;
                size_t count = 0;
                each_in_chart(
                    i, 2, step,
                    [&](size_t j, int dx, int dy)
                    {
                        const LightmapTexel& u = atlas.texels[first + j];
                        double weight = double(kSpline[dx + 2] * kSpline[dy + 2]), base = weight;
                        if (j != i)
                        {
                            const glm::vec3 d = u.position - t.position;
                            const float reach = 1.5f * float(step) * std::sqrt(float(dx * dx + dy * dy)) *
                                                    std::max(size, u.world_size) +
                                                size;
                            if (glm::dot(d, d) > reach * reach)
                                return;
                            // (Each factor is exactly 1 on a flat chart: no exp or pow for it.)
                            if (const float off = std::abs(glm::dot(d, t.geometric_normal)); off > 0.0f)
                                weight *= std::exp(-off / (o.sigma_plane * size));
                            if (const float turn = glm::dot(t.normal, u.normal); turn < 1.0f)
                                weight *= std::pow(std::max(0.0f, turn), o.sigma_normal);
                            base = weight;
                            std::array<double, 4> difference;
                            for (size_t c = 0; c < 4; ++c)
                                difference[c] = double(guide[j][c]) - double(guide[i][c]);
                            weight *= light_weight(j, difference);
                            if (!(weight > 0.0))
                                return;
                        }
                        used[count++] = {j, weight, double(dx), double(dy), base};
                    });
                // A weighted first-order fit v ~ b0 + b1 dx + b2 dy; the texel takes b0 = sum l_j v_j
                // (lightmap_denoise.h), and where the centre's noise is known, the light's term is taken
                // again against the guides' fitted planes and the fit repeated.
                std::array<double, 25> l;
                const bool refit = variance[i] != Guide{};
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
                            const double y = used[k].w * double(guide[used[k].j][c]);
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
                            difference[c] = double(guide[used[k].j][c]) - plane[c][0] -
                                            plane[c][1] * used[k].dx - plane[c][2] * used[k].dy;
                        used[k].w = used[k].base * light_weight(used[k].j, difference);
                    }
                }
                // The values, the guides and what is left of their variance (sum l_j^2 v_j) go through the
                // same l_j.
                // (The values in float: 4 to a vector, and every texel's sums in the same order.)
                std::array<float, 27> sum_sh{};
                std::array<float, 12> sum_direct{};
                std::array<double, 4> g{}, v{};
                for (size_t k = 0; k < count; ++k)
                {
                    const float* x = &current->irradiance[used[k].j][0].x;
                    const float* y = &current->direct[used[k].j][0].x;
                    const float lk = float(l[k]);
                    for (size_t c = 0; c < 27; ++c)
                        sum_sh[c] += lk * x[c];
                    for (size_t c = 0; c < 12; ++c)
                        sum_direct[c] += lk * y[c];
                    for (size_t c = 0; c < 4; ++c)
                    {
                        g[c] += l[k] * double(guide[used[k].j][c]);
                        v[c] += l[k] * l[k] * double(variance[used[k].j][c]);
                    }
                }
                std::memcpy(&other->irradiance[i][0].x, sum_sh.data(), sizeof sum_sh);
                std::memcpy(&other->direct[i][0].x, sum_direct.data(), sizeof sum_direct);
                for (size_t c = 0; c < 4; ++c)
                {
                    next_guide[i][c] = float(g[c]);
                    next_variance[i][c] = float(v[c]);
                }
            });
        std::swap(current, other);
        guide.swap(next_guide);
        variance.swap(next_variance);
    }

    // Irradiance integrated directly (plain, rnm) is never negative; an extrapolating fit could make it so.
    for (size_t i = 0; i < n; ++i)
        for (glm::vec3& e : current->direct[i])
            e = glm::max(e, glm::vec3(0.0f));
    if (current != &values)
    {
        values.irradiance.swap(current->irradiance);
        values.direct.swap(current->direct);
    }
}

} // namespace

LightmapDenoiseReport denoise_lightmap(const io::Mesh& mesh, const LightmapAtlas& atlas, LightmapSh& sh,
                                       const LightmapDenoiseOptions& o)
{
    const size_t n = atlas.texels.size();
    if (sh.texels() != n || !sh.has_direct() || !sh.has_noise() || sh.valid.size() != n ||
        (!sh.tiles && (sh.direct.size() != n || sh.noise.size() != n)))
        throw std::invalid_argument("denoising needs a bake's irradiance, direct values, noise estimate and "
                                    "validity for each of the atlas's " +
                                    std::to_string(n) + " texels");
    if (o.iterations < 0 || o.iterations > 10 || !(o.sigma_light > 0.0f) || !(o.sigma_normal > 0.0f) ||
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
    // Each chart keeps the light it was baked with: the filter moves light within a chart (a texel's weights
    // sum to 1, its neighbours' weights on it need not: a flat, dim region takes more from a bright feature
    // than the feature takes from it), so the filtered chart is scaled, per colour channel, until its plain
    // sums to what the bake's did (an unbiased estimate of the chart's light; a chart with none stays as it
    // is). sums: per chart, plain as baked (0..2) and as filtered (3..5), added in texel order.
    std::vector<std::array<double, 6>> sums(report.charts);
    const auto add_baked = [&](size_t i, const glm::vec3& baked)
    {
        for (size_t c = 0; c < 3 && sh.valid[i]; ++c)
            sums[chart[i]][c] += double(baked[int(c)]);
    };
    const auto add_filtered = [&](size_t i, const glm::vec3& filtered)
    {
        for (size_t c = 0; c < 3 && sh.valid[i]; ++c)
            sums[chart[i]][3 + c] += double(filtered[int(c)]);
    };
    // Every value of texel i times its chart's factors, channel by channel.
    const auto scale = [&](size_t i, ShArray& irradiance, DirectArray& direct)
    {
        if (!sh.valid[i])
            return;
        const std::array<double, 6>& s = sums[chart[i]];
        glm::vec3 factor(1.0f);
        for (int c = 0; c < 3; ++c)
            if (s[size_t(3 + c)] > 0.0 && s[size_t(c)] > 0.0)
                factor[c] = float(s[size_t(c)] / s[size_t(3 + c)]);
        for (glm::vec3& x : irradiance)
            x *= factor;
        for (glm::vec3& x : direct)
            x *= factor;
    };

    if (!sh.tiles)
    {
        // Filtered in the bake's own arrays (and a second copy the filter holds while it runs).
        for (size_t i = 0; i < n; ++i)
            add_baked(i, sh.direct[i][0]);
        Values values;
        values.irradiance.swap(sh.irradiance);
        values.direct.swap(sh.direct);
        try
        {
            filter_range(atlas, chart, sh.valid, 0, n, values, sh.noise.data(), o);
        }
        catch (...)
        {
            sh.irradiance.swap(values.irradiance); // (only a failure to allocate: nothing was written)
            sh.direct.swap(values.direct);
            throw;
        }
        sh.irradiance.swap(values.irradiance);
        sh.direct.swap(values.direct);
        for (size_t i = 0; i < n; ++i)
            add_filtered(i, sh.direct[i][0]);
        for (size_t i = 0; i < n; ++i)
            scale(i, sh.irradiance[i], sh.direct[i]);
        release(sh.noise); // the estimate is done with
        return report;
    }

    // A bake in tiles (its sums and noise in sh.tiles, copy sh.tiles_copy): the atlas in bands of rows, each
    // read with `halo` rows above and below it, as far as a texel's result depends on others (the guides'
    // prefilter, and each pass's variance average and its 5 x 5 window 2^k apart), so that each band's rows
    // come out as the whole atlas's would; they are written to the file's other copy, then scaled there.
    const int64_t halo = 1 + 2 * ((int64_t(1) << o.iterations) - 1) + o.iterations;
    const size_t band_texels = o.tile_texels ? o.tile_texels : size_t(1) << 20;
    // The first texel at row y or below it (texels are in row-major order), n past the last row.
    const auto row_start = [&](int64_t y)
    {
        return size_t(std::partition_point(atlas.texels.begin(), atlas.texels.end(),
                                           [&](const LightmapTexel& t) { return int64_t(t.y) < y; }) -
                      atlas.texels.begin());
    };
    const int from = sh.tiles_copy, to = 1 - from;
    Values band;
    for (size_t out_first = 0; out_first < n;)
    {
        const int64_t y0 = atlas.texels[out_first].y;
        int64_t y1 = y0 + 1; // rows [y0, y1) come out of this band: as many as fit, at least one
        while (row_start(y1) < n && row_start(y1 + 1 + halo) - row_start(y0 - halo) <= band_texels)
            ++y1;
        const size_t out_end = row_start(y1), in_first = row_start(y0 - halo),
                     count = row_start(y1 + halo) - in_first;
        band.irradiance.resize(count);
        band.direct.resize(count);
        std::vector<LightmapSh::Noise> noise(count);
        sh.read(uint32_t(in_first), uint32_t(count), band.irradiance.data(), band.direct.data(),
                noise.data());
        for (size_t i = out_first; i < out_end; ++i)
            add_baked(i, band.direct[i - in_first][0]);
        filter_range(atlas, chart, sh.valid, in_first, count, band, noise.data(), o);
        for (size_t i = out_first; i < out_end; ++i)
            add_filtered(i, band.direct[i - in_first][0]);
        const size_t skip = out_first - in_first, rows = out_end - out_first;
        sh.tiles->write(to, 0, uint32_t(out_first),
                        std::as_bytes(std::span(band.irradiance).subspan(skip, rows)));
        sh.tiles->write(to, 1, uint32_t(out_first),
                        std::as_bytes(std::span(band.direct).subspan(skip, rows)));
        out_first = out_end;
    }
    sh.tiles_copy = to;
    sh.tiles_noise = false; // the estimate is done with
    for (size_t first = 0; first < n; first += band_texels)
    {
        const size_t count = std::min(band_texels, n - first);
        band.irradiance.resize(count);
        band.direct.resize(count);
        sh.read(uint32_t(first), uint32_t(count), band.irradiance.data(), band.direct.data(), nullptr);
        for (size_t i = 0; i < count; ++i)
            scale(first + i, band.irradiance[i], band.direct[i]);
        sh.tiles->write(to, 0, uint32_t(first), std::as_bytes(std::span(band.irradiance)));
        sh.tiles->write(to, 1, uint32_t(first), std::as_bytes(std::span(band.direct)));
    }
    return report;
}

} // namespace hemi::bake
