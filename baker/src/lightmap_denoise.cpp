#include <hemi/bake/float4.h>
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

// A texel's window in the filter (5 x 5 texels at most) as arrays over its neighbours, laid out for loops of
// kLanes: the entries past the neighbours, up to a multiple of kLanes, are zeros (weights of 0).
constexpr int kLanes = 4;
constexpr int kWindow = 28; // 25, rounded up to kLanes
struct Window
{
    alignas(32) float dx[kWindow], dy[kWindow]; // offsets, in texels of the pass's spacing
    alignas(32) float base[kWindow];            // the weight without the light's term
    alignas(32) float w[kWindow];               // the weight
    alignas(32) float guide[4][kWindow], smooth[4][kWindow];
    uint32_t j[kWindow]; // the neighbour's index in the range
    // What the weight without the light's term is made of: the spline's weight, the distance in texels of
    // the offset, and the neighbour's point, shading normal and world size (read once, before `base`).
    alignas(32) float spline[kWindow], distance[kWindow];
    alignas(32) float position[3][kWindow], normal[3][kWindow], size[kWindow];

    // Zeros from entry `count` to the next multiple of kLanes, at the centre's point and normal (flat, so
    // that they ask for no exp or log).
    void clear(int count, const glm::vec3& centre, const glm::vec3& centre_normal)
    {
        for (int k = count; k % kLanes; ++k)
        {
            dx[k] = dy[k] = base[k] = w[k] = 0.0f;
            j[k] = 0;
            for (size_t c = 0; c < 4; ++c)
                guide[c][k] = smooth[c][k] = 0.0f;
            spline[k] = distance[k] = size[k] = 0.0f;
            for (int c = 0; c < 3; ++c)
            {
                position[c][k] = centre[c];
                normal[c][k] = centre_normal[c];
            }
        }
    }
    // N sums over entries [0, padded) (a multiple of kLanes) of what f(k) gives for entries [k, k + kLanes):
    // kLanes partial sums each, added in a fixed order (the same result on any machine and thread).
    template <size_t N, class F> static std::array<float, N> sums(int padded, F&& f)
    {
        std::array<f32x4, N> acc{};
        for (int k = 0; k < padded; k += kLanes)
        {
            const std::array<f32x4, N> x = f(k);
            for (size_t c = 0; c < N; ++c)
                acc[c] += x[c];
        }
        std::array<float, N> s;
        for (size_t c = 0; c < N; ++c)
            s[c] = (acc[c][0] + acc[c][1]) + (acc[c][2] + acc[c][3]);
        return s;
    }
};

// Filters texels [first, first + n) of the atlas, `values`, in place, with `noise` the variance of each
// texel's guides (LightmapSh::noise); texels outside the range count as absent. The passes alternate between
// `values` and a second copy of them; everything is allocated before `values` is written, so that on a
// failure to allocate it is as it was. Plain and rnm come out >= 0; each chart's light is restored by the
// caller. chart(i): texel i's chart.
template <typename Chart>
void filter_range(const LightmapAtlas& atlas, const Chart& chart, const std::vector<uint8_t>& valid,
                  size_t first, size_t n, Values& values, const LightmapSh::Noise* noise,
                  const LightmapDenoiseOptions& o)
{
    // What a window reads of each texel, in one cache line (the atlas's record is 96 bytes, and the guides
    // are arrays of their own): its sample point, its world size (at least 1e-30), its shading normal, its
    // chart (kNone where it is invalid), and this pass's guides and smoothed variances.
    struct alignas(64) Site
    {
        glm::vec3 position;
        float size;
        glm::vec3 normal;
        uint32_t chart;
        Guide guide, smooth;
    };
    static constexpr uint32_t kNone = UINT32_MAX;
    std::vector<Site> site(n);
    for (size_t i = 0; i < n; ++i)
    {
        const LightmapTexel& t = atlas.texels[first + i];
        site[i] = {t.position, std::max(t.world_size, 1e-30f),
                   t.normal,   valid[first + i] ? chart(first + i) : kNone,
                   {},         {}};
    }
    // f(i) for every texel of the range, in parallel.
    const auto each_texel = [&](auto&& f) { tbb::parallel_for(size_t(0), n, [&](size_t i) { f(i); }); };
    // Calls f(j, dx, dy) for each valid texel j of i's chart in the range at (dx, dy) texels of `step` from
    // it (i and j: indices in the range).
    const auto each_in_chart = [&](size_t i, int radius, int step, auto&& f)
    {
        const glm::uvec2 t = atlas.texels.place(first + i);
        const uint32_t own = site[i].chart;
        for (int dy = -radius; dy <= radius; ++dy)
            for (int dx = -radius; dx <= radius; ++dx)
            {
                const int64_t j =
                    atlas.texel_of(int64_t(t.x) + dx * step, int64_t(t.y) + dy * step) - int64_t(first);
                if (j >= 0 && j < int64_t(n) && site[size_t(j)].chart == own)
                    f(size_t(j), dx, dy);
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
        each_texel(
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
    static const std::array<float, 25> kDistance = [] // sqrt(dx^2 + dy^2) over the 5 x 5 offsets
    {
        std::array<float, 25> d;
        for (int k = 0; k < 25; ++k)
            d[size_t(k)] = std::sqrt(float((k % 5 - 2) * (k % 5 - 2) + (k / 5 - 2) * (k / 5 - 2)));
        return d;
    }();
    const float k2 = o.sigma_light * o.sigma_light;
    for (int pass = 0; pass < o.iterations; ++pass)
    {
        const int step = 1 << pass;
        // The variance the light's term divides by: each texel's, averaged over its 3 x 3 neighbours.
        each_texel([&](size_t i) { smooth[i] = valid[first + i] ? binomial(variance, i, 1) : Guide{}; });
        for (size_t i = 0; i < n; ++i)
        {
            site[i].guide = guide[i];
            site[i].smooth = smooth[i];
        }
        each_texel(
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
                const glm::vec3 geometric_normal = atlas.texels.geometric_normal(first + i);
                const Site& centre = site[i];
                const float size = centre.size;
                // The window: the neighbours that weigh anything, their offsets (in texels of this pass's
                // spacing), their weight without the light's term (`base`), and their guides and smoothed
                // variances, as arrays over the window, so that the light's term, the fit and the sums are
                // loops over it that the compiler vectorises. Past `count`, up to a multiple of kLanes,
                // weights of 0.
                Window win;
                int count = 0, centre_k = 0;
                each_in_chart(i, 2, step,
                              [&](size_t j, int dx, int dy)
                              {
                                  if (j == i)
                                      centre_k = count;
                                  const Site& u = site[j];
                                  win.j[count] = uint32_t(j);
                                  win.dx[count] = float(dx);
                                  win.dy[count] = float(dy);
                                  win.spline[count] = kSpline[dx + 2] * kSpline[dy + 2];
                                  win.distance[count] = kDistance[size_t((dy + 2) * 5 + dx + 2)];
                                  win.size[count] = u.size;
                                  for (int c = 0; c < 3; ++c)
                                  {
                                      win.position[c][count] = u.position[c];
                                      win.normal[c][count] = u.normal[c];
                                  }
                                  for (size_t c = 0; c < 4; ++c)
                                  {
                                      win.guide[c][count] = u.guide[c];
                                      win.smooth[c][count] = u.smooth[c];
                                  }
                                  ++count;
                              });
                win.clear(count, centre.position, centre.normal);
                const int padded = (count + kLanes - 1) / kLanes * kLanes;
                // The weight without the light's term: 0 for a neighbour that is not where the chart's
                // surface continues, else the spline's times the step off the centre's plane and the turn
                // of the shading normals (lightmap_denoise.h); the centre's, the spline's.
                for (int k = 0; k < padded; k += kLanes)
                {
                    f32x4 d[3], along = {}, turn = {}, off = {};
                    const f32x4 spline = load4(&win.spline[k]);
                    for (int c = 0; c < 3; ++c)
                    {
                        d[c] = load4(&win.position[c][k]) - centre.position[c];
                        along += d[c] * d[c];
                        off += d[c] * geometric_normal[c];
                        turn += load4(&win.normal[c][k]) * centre.normal[c];
                    }
                    const f32x4 other_size = load4(&win.size[k]);
                    const f32x4 reach = 1.5f * float(step) * load4(&win.distance[k]) *
                                            (other_size > size ? other_size : size) +
                                        size;
                    off = off < 0.0f ? -off : off;
                    f32x4 weight = spline;
                    // (Each factor is exactly 1 on a flat chart: no exp or log for it.)
                    const i32x4 curved = (off > 0.0f) | (turn < 1.0f);
                    if (curved[0] | curved[1] | curved[2] | curved[3])
                    {
                        const f32x4 positive = turn > 0.0f ? turn : splat(1.0f);
                        const f32x4 bend = turn < 1.0f
                                               ? exp_nonpositive(o.sigma_normal * log_positive(positive))
                                               : splat(1.0f);
                        weight = weight * exp_nonpositive(-off / (o.sigma_plane * size)) *
                                 (turn > 0.0f ? bend : f32x4{});
                    }
                    store4(&win.base[k], along > reach * reach ? f32x4{} : weight);
                }
                win.base[centre_k] = win.spline[centre_k];
                // The light's term for each neighbour whose guides differ from the centre's (or from the
                // fitted planes) by difference(c, k): exp(-max(0, D)), D the mean over the guides of the
                // squared difference less what the two texels' noise explains, in units of that noise (the
                // non-local means distance of Rousselle, Knaus and Zwicker 2012): about 0 for a neighbour
                // whose light differs from the centre's by noise only, growing with the square of a real
                // difference. A guide without variance at the centre (its samples agreed, as in a sealed room
                // where none saw light) admits only neighbours with exactly its value. Into `out`, times
                // `base`.
                int counted = 0;
                for (size_t c = 0; c < 4; ++c)
                    counted += variance[i][c] > 0.0f;
                const float per_guide = counted ? 1.0f / float(counted) : 0.0f;
                const auto light = [&](auto&& difference, float* out)
                {
                    for (int k = 0; k < padded; k += kLanes)
                    {
                        f32x4 distance = {}, admitted = splat(1.0f);
                        for (size_t c = 0; c < 4; ++c)
                        {
                            if (variance[i][c] > 0.0f)
                            {
                                const f32x4 d = difference(c, k), vi = splat(smooth[i][c]),
                                            vj = load4(&win.smooth[c][k]);
                                distance += (d * d - (vi + (vj < vi ? vj : vi))) / (k2 * (vi + vj) + 1e-30f);
                            }
                            else
                                admitted = load4(&win.guide[c][k]) == guide[i][c] ? admitted : f32x4{};
                        }
                        distance = distance > 0.0f ? distance : f32x4{};
                        store4(out + k,
                               load4(&win.base[k]) * admitted * exp_nonpositive(-distance * per_guide));
                    }
                };
                light([&](size_t c, int k) { return load4(&win.guide[c][k]) - guide[i][c]; }, win.w);
                win.w[centre_k] = win.base[centre_k];
                // Only those that weigh anything take part from here on (the centre always).
                for (int k = 0; k < padded; k += kLanes)
                    store4(&win.base[k], load4(&win.w[k]) > 0.0f ? load4(&win.base[k]) : f32x4{});
                // A weighted first-order fit v ~ b0 + b1 dx + b2 dy; the texel takes b0 = sum l_j v_j
                // (lightmap_denoise.h), and where the centre's noise is known, the light's term is taken
                // again against the guides' fitted planes and the fit repeated.
                const bool refit = variance[i] != Guide{};
                alignas(32) float l[kWindow];
                for (int fit = 0; fit < (refit ? 2 : 1); ++fit)
                {
                    const std::array<float, 6> s =
                        Window::sums<6>(padded,
                                        [&](int k)
                                        {
                                            const f32x4 w = load4(&win.w[k]), dx = load4(&win.dx[k]),
                                                        dy = load4(&win.dy[k]), wx = w * dx, wy = w * dy;
                                            return std::array<f32x4, 6>{w, wx, wy, wx * dx, wx * dy, wy * dy};
                                        });
                    double m[3][3] = {{s[0], s[1], s[2]}, {s[1], s[3], s[4]}, {s[2], s[4], s[5]}};
                    m[1][1] += 1e-2 * m[0][0];
                    m[2][2] += 1e-2 * m[0][0];
                    // m's inverse (symmetric: cofactors over the determinant).
                    const double i00 = m[1][1] * m[2][2] - m[1][2] * m[2][1],
                                 i01 = m[0][2] * m[2][1] - m[0][1] * m[2][2],
                                 i02 = m[0][1] * m[1][2] - m[0][2] * m[1][1],
                                 i11 = m[0][0] * m[2][2] - m[0][2] * m[2][0],
                                 i12 = m[0][2] * m[1][0] - m[0][0] * m[1][2],
                                 i22 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
                    const double inverse = 1.0 / (m[0][0] * i00 + m[0][1] * i01 + m[0][2] * i02);
                    const float a0 = float(i00 * inverse), a1 = float(i01 * inverse),
                                a2 = float(i02 * inverse);
                    for (int k = 0; k < padded; ++k)
                        l[k] = win.w[k] * (a0 + a1 * win.dx[k] + a2 * win.dy[k]);
                    const float total =
                        Window::sums<1>(padded, [&](int k) { return std::array<f32x4, 1>{load4(&l[k])}; })[0];
                    for (int k = 0; k < padded; ++k)
                        l[k] /= total;
                    if (fit == 1 || !refit)
                        break;
                    float plane[4][3];
                    for (size_t c = 0; c < 4; ++c)
                    {
                        const std::array<float, 3> r = Window::sums<3>(
                            padded,
                            [&](int k)
                            {
                                const f32x4 y = load4(&win.w[k]) * load4(&win.guide[c][k]);
                                return std::array<f32x4, 3>{y, y * load4(&win.dx[k]), y * load4(&win.dy[k])};
                            });
                        plane[c][0] = float((i00 * r[0] + i01 * r[1] + i02 * r[2]) * inverse);
                        plane[c][1] = float((i01 * r[0] + i11 * r[1] + i12 * r[2]) * inverse);
                        plane[c][2] = float((i02 * r[0] + i12 * r[1] + i22 * r[2]) * inverse);
                    }
                    light(
                        [&](size_t c, int k)
                        {
                            return load4(&win.guide[c][k]) - plane[c][0] - plane[c][1] * load4(&win.dx[k]) -
                                   plane[c][2] * load4(&win.dy[k]);
                        },
                        win.w);
                    win.w[centre_k] = win.base[centre_k];
                }
                // The values, the guides and what is left of their variance (sum l_j^2 v_j) go through the
                // same l_j.
                // (The values in float: 4 to a vector, and every texel's sums in the same order.)
                std::array<float, 27> sum_sh{};
                std::array<float, 12> sum_direct{};
                Guide g{}, v{};
                for (int k = 0; k < count; ++k)
                {
                    if (l[k] == 0.0f)
                        continue; // (no neighbour's light may be infinite or NaN: nothing to add)
                    const uint32_t j = win.j[k];
                    const float* x = &current->irradiance[j][0].x;
                    const float* y = &current->direct[j][0].x;
                    const float lk = l[k];
                    for (size_t c = 0; c < 27; ++c)
                        sum_sh[c] += lk * x[c];
                    for (size_t c = 0; c < 12; ++c)
                        sum_direct[c] += lk * y[c];
                    for (size_t c = 0; c < 4; ++c)
                    {
                        g[c] += lk * win.guide[c][k];
                        v[c] += lk * lk * variance[j][c];
                    }
                }
                std::memcpy(&other->irradiance[i][0].x, sum_sh.data(), sizeof sum_sh);
                std::memcpy(&other->direct[i][0].x, sum_direct.data(), sizeof sum_direct);
                next_guide[i] = g;
                next_variance[i] = v;
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
    // Each texel's chart from its record (in memory, or in pages of a file for a bake out of core: no
    // per-texel copy).
    const std::vector<uint32_t> chart_of_triangle = lightmap_charts(mesh, &report.charts);
    const auto chart = [&](size_t i) { return chart_of_triangle[atlas.texels.triangle(i)]; };
    for (size_t i = 0; i < n; ++i)
        report.texels += sh.valid[i] != 0;
    // Each chart keeps the light it was baked with: the filter moves light within a chart (a texel's weights
    // sum to 1, its neighbours' weights on it need not: a flat, dim region takes more from a bright feature
    // than the feature takes from it), so the filtered chart is scaled, per colour channel, until its plain
    // sums to what the bake's did (an unbiased estimate of the chart's light; a chart with none stays as it
    // is). sums: per chart, plain as baked (0..2) and as filtered (3..5), added in texel order.
    std::vector<std::array<double, 6>> sums(report.charts);
    const auto add_baked = [&](size_t i, const glm::vec3& baked)
    {
        for (size_t c = 0; c < 3 && sh.valid[i]; ++c)
            sums[chart(i)][c] += double(baked[int(c)]);
    };
    const auto add_filtered = [&](size_t i, const glm::vec3& filtered)
    {
        for (size_t c = 0; c < 3 && sh.valid[i]; ++c)
            sums[chart(i)][3 + c] += double(filtered[int(c)]);
    };
    // Every value of texel i times its chart's factors, channel by channel.
    const auto scale = [&](size_t i, ShArray& irradiance, DirectArray& direct)
    {
        if (!sh.valid[i])
            return;
        const std::array<double, 6>& s = sums[chart(i)];
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
        size_t lo = 0, hi = n;
        while (lo < hi)
        {
            const size_t mid = lo + (hi - lo) / 2;
            if (int64_t(atlas.texels.place(mid).y) < y)
                lo = mid + 1;
            else
                hi = mid;
        }
        return lo;
    };
    const int from = sh.tiles_copy, to = 1 - from;
    Values band;
    for (size_t out_first = 0; out_first < n;)
    {
        const int64_t y0 = atlas.texels.place(out_first).y;
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
