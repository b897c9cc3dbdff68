#include <hemi/math/brdf.h>
#include <hemi/math/luminance.h>
#include <hemi/math/paraboloid.h>
#include <hemi/math/quadrature.h>
#include <hemi/math/sh_environment.h>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::math
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

bool power_of_two(uint32_t v)
{
    return v != 0 && (v & (v - 1)) == 0;
}

// The integral over y in [y0, y1] of 4 / (a2 + y^2)^2, a2 = 1 + x^2.
double inner(double a2, double y0, double y1)
{
    const double a = std::sqrt(a2);
    auto f = [&](double y) { return 2.0 * y / (a2 * (a2 + y * y)) + 2.0 * std::atan(y / a) / (a2 * a); };
    return f(y1) - f(y0);
}

const QuadratureRule& rule24()
{
    static const QuadratureRule r = gauss_legendre(24, 0.0, 1.0);
    return r;
}

// The integral over x in [x0, x1] of inner(1 + x^2, lo(x), hi(x)), the y limits clipped to the circle when
// `circle`; smooth on the pieces between the points where the circle crosses y0 or y1.
double integrate(double x0, double x1, double y0, double y1, bool circle)
{
    std::vector<double> cuts{x0, x1};
    if (circle)
    {
        x0 = std::max(x0, -1.0);
        x1 = std::min(x1, 1.0);
        if (!(x1 > x0))
            return 0.0;
        cuts = {x0, x1};
        for (double y : {y0, y1})
            if (std::abs(y) < 1.0)
                for (double x : {-std::sqrt(1.0 - y * y), std::sqrt(1.0 - y * y)})
                    if (x > x0 && x < x1)
                        cuts.push_back(x);
        std::sort(cuts.begin(), cuts.end());
    }
    const QuadratureRule& r = rule24();
    double total = 0.0;
    for (size_t p = 0; p + 1 < cuts.size(); ++p)
    {
        const double a = cuts[p], b = cuts[p + 1];
        for (size_t i = 0; i < r.x.size(); ++i)
        {
            const double x = a + (b - a) * r.x[i];
            double lo = y0, hi = y1;
            if (circle)
            {
                const double c = std::sqrt(std::max(0.0, 1.0 - x * x));
                lo = std::max(lo, -c);
                hi = std::min(hi, c);
            }
            if (hi > lo)
                total += (b - a) * r.w[i] * inner(1.0 + x * x, lo, hi);
        }
    }
    return total;
}

void texel_bounds(uint32_t size, double extent, uint32_t col, uint32_t row, double& x0, double& y0,
                  double& x1, double& y1)
{
    const double step = 2.0 * extent / double(size);
    x0 = -extent + col * step;
    x1 = x0 + step;
    y1 = extent - row * step;
    y0 = y1 - step;
}

// Per-texel solid angles of one half at `size` (both halves are the same), whole or inside the circle.
std::vector<double> solid_angles(uint32_t size, double extent, bool circle)
{
    std::vector<double> out(size_t(size) * size);
    tbb::parallel_for(uint32_t(0), size,
                      [&](uint32_t row)
                      {
                          for (uint32_t col = 0; col < size; ++col)
                          {
                              double x0, y0, x1, y1;
                              texel_bounds(size, extent, col, row, x0, y0, x1, y1);
                              out[size_t(row) * size + col] =
                                  circle ? parabolic_solid_angle_in_circle(x0, y0, x1, y1)
                                         : parabolic_solid_angle(x0, y0, x1, y1);
                          }
                      });
    return out;
}
} // namespace

int parabolic_half(const glm::dvec3& d)
{
    return d.z >= 0.0 ? 0 : 1;
}

glm::dvec2 parabolic_xy(const glm::dvec3& d, int half)
{
    const double denom = 1.0 + (half == 0 ? d.z : -d.z);
    return glm::dvec2(d.x, d.y) / denom;
}

glm::dvec3 parabolic_direction(int half, double x, double y)
{
    const double r2 = x * x + y * y;
    const double z = (1.0 - r2) / (1.0 + r2);
    return glm::dvec3(2.0 * x / (1.0 + r2), 2.0 * y / (1.0 + r2), half == 0 ? z : -z);
}

double parabolic_solid_angle(double x0, double y0, double x1, double y1)
{
    return integrate(x0, x1, y0, y1, false);
}
double parabolic_solid_angle_in_circle(double x0, double y0, double x1, double y1)
{
    return integrate(x0, x1, y0, y1, true);
}

glm::dvec3 ParabolicImage::direction(int half, uint32_t col, uint32_t row) const
{
    const double step = 2.0 * extent / double(size);
    return parabolic_direction(half, -extent + (col + 0.5) * step, extent - (row + 0.5) * step);
}
double ParabolicImage::solid_angle(uint32_t col, uint32_t row) const
{
    double x0, y0, x1, y1;
    texel_bounds(size, extent, col, row, x0, y0, x1, y1);
    return parabolic_solid_angle(x0, y0, x1, y1);
}
double ParabolicImage::solid_angle_in_circle(uint32_t col, uint32_t row) const
{
    double x0, y0, x1, y1;
    texel_bounds(size, extent, col, row, x0, y0, x1, y1);
    return parabolic_solid_angle_in_circle(x0, y0, x1, y1);
}

glm::dvec3 ParabolicImage::sample(const glm::dvec3& d) const
{
    const int half = parabolic_half(d);
    const glm::dvec2 xy = parabolic_xy(d, half);
    const double px = std::clamp((xy.x / extent + 1.0) * 0.5 * size - 0.5, 0.0, double(size - 1));
    const double py = std::clamp((1.0 - xy.y / extent) * 0.5 * size - 0.5, 0.0, double(size - 1));
    const uint32_t c0 = std::min(uint32_t(px), size > 1 ? size - 2 : 0),
                   r0 = std::min(uint32_t(py), size > 1 ? size - 2 : 0);
    const uint32_t c1 = std::min(c0 + 1, size - 1), r1 = std::min(r0 + 1, size - 1);
    const double fx = px - c0, fy = py - r0;
    glm::dvec3 out(0.0);
    const double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    const float* t[4] = {at(half, c0, r0), at(half, c1, r0), at(half, c0, r1), at(half, c1, r1)};
    for (int k = 0; k < 4; ++k)
        out += w[k] * glm::dvec3(t[k][0], t[k][1], t[k][2]);
    return out;
}

ParabolicImage parabolic_from_equirect(uint32_t size, uint32_t width, uint32_t height,
                                       std::span<const float> rgba)
{
    if (!power_of_two(size) || size < 2 || size > 8192)
        throw std::invalid_argument("a parabolic map's size must be a power of two in [2, 8192], got " +
                                    std::to_string(size));
    if (width == 0 || height == 0 || rgba.size() != size_t(width) * height * 4)
        throw std::invalid_argument("the equirectangular environment's size does not match its pixels");
    for (float v : rgba)
        if (!std::isfinite(v))
            throw std::invalid_argument("the equirectangular environment has a pixel that is not finite");
    ParabolicImage out;
    out.size = size;
    out.extent = parabolic_extent(size);
    out.rgb.assign(size_t(2) * size * size * 3, 0.0f);
    // Enough points per texel that they are at most half an equirect pixel apart at the centre of a half,
    // where texels are largest (4 / size radians).
    const uint32_t n = std::clamp(uint32_t(std::ceil(4.0 * width / (kPi * size))), 2u, 16u);
    const double m = out.extent, step = 2.0 * m / double(size);
    tbb::parallel_for(uint32_t(0), 2 * size,
                      [&](uint32_t hr)
                      {
                          const int half = int(hr / size);
                          const uint32_t row = hr % size;
                          for (uint32_t col = 0; col < size; ++col)
                          {
                              glm::dvec3 sum(0.0);
                              double weight = 0.0;
                              for (uint32_t j = 0; j < n; ++j)
                                  for (uint32_t i = 0; i < n; ++i)
                                  {
                                      const double x = -m + (col + (i + 0.5) / n) * step;
                                      const double y = m - (row + (j + 0.5) / n) * step;
                                      const double r2 = 1.0 + x * x + y * y;
                                      const double w = 4.0 / (r2 * r2); // Eq. 6
                                      uint32_t px, py;
                                      equirect_pixel(parabolic_direction(half, x, y), width, height, px, py);
                                      const float* p = rgba.data() + (size_t(py) * width + px) * 4;
                                      sum += w * glm::dvec3(p[0], p[1], p[2]);
                                      weight += w;
                                  }
                              float* t = out.at(half, col, row);
                              for (int c = 0; c < 3; ++c)
                                  t[c] = float(sum[c] / weight);
                          }
                      });
    return out;
}

std::vector<ParabolicImage> parabolic_mip_chain(ParabolicImage level0)
{
    if (!power_of_two(level0.size) || level0.rgb.size() != size_t(2) * level0.size * level0.size * 3)
        throw std::invalid_argument("a parabolic map's size must be a power of two that matches its texels");
    std::vector<ParabolicImage> chain;
    chain.push_back(std::move(level0));
    while (chain.back().size > 1)
    {
        const ParabolicImage& fine = chain.back();
        const std::vector<double> omega = solid_angles(fine.size, fine.extent, false);
        ParabolicImage coarse;
        coarse.size = fine.size / 2;
        coarse.extent = fine.extent;
        coarse.rgb.assign(size_t(2) * coarse.size * coarse.size * 3, 0.0f);
        for (int half = 0; half < 2; ++half)
            for (uint32_t row = 0; row < coarse.size; ++row)
                for (uint32_t col = 0; col < coarse.size; ++col)
                {
                    glm::dvec3 sum(0.0);
                    double weight = 0.0;
                    for (uint32_t k = 0; k < 4; ++k)
                    {
                        const uint32_t c = 2 * col + (k & 1), r = 2 * row + (k >> 1);
                        const double w = omega[size_t(r) * fine.size + c];
                        const float* t = fine.at(half, c, r);
                        sum += w * glm::dvec3(t[0], t[1], t[2]);
                        weight += w;
                    }
                    float* t = coarse.at(half, col, row);
                    for (int c = 0; c < 3; ++c)
                        t[c] = float(sum[c] / weight);
                }
        chain.push_back(std::move(coarse));
    }
    return chain;
}

double parabolic_extent(uint32_t size)
{
    return size > 2 ? double(size) / double(size - 2) : 1.0;
}

uint32_t glossy_size(double exponent, uint32_t full_size)
{
    uint32_t s = 32;
    const double want = 16.0 * std::sqrt(std::max(exponent, 0.0));
    while (s < want && s < full_size)
        s *= 2;
    return std::min(s, full_size);
}

namespace
{

// The source of a lobe sum as structure of arrays: per texel a direction and its radiance times solid angle
// inside the circle. At shift 0, a level's texels at their centres. At shift k, each block of 2^k x 2^k
// texels of that level as one: the sum of its texels' radiance times their solid angle inside the circle
// (texels outside the circle, whose directions the other half owns, count for nothing, as at shift 0), at the
// radiance-weighted mean of their directions (luminance weights; the solid angle's mean where the block is
// black), so that a bright spot inside a block keeps its own direction.
struct SourceTexels
{
    uint32_t size = 0; // texels along a side of a half (the level's size >> shift)
    double extent = 1.0;
    std::vector<float> dx, dy, dz, wr, wg, wb;
};

SourceTexels source_texels(const ParabolicImage& level, uint32_t shift = 0)
{
    SourceTexels s;
    const uint32_t fine = level.size, block = 1u << shift;
    s.size = fine >> shift;
    s.extent = level.extent;
    const uint32_t size = s.size;
    const std::vector<double> omega = solid_angles(fine, level.extent, true);
    const size_t texels = size_t(2) * size * size;
    for (std::vector<float>* v : {&s.dx, &s.dy, &s.dz, &s.wr, &s.wg, &s.wb})
        v->resize(texels);
    tbb::parallel_for(uint32_t(0), 2 * size,
                      [&](uint32_t hr)
                      {
                          const int half = int(hr / size);
                          const uint32_t row = hr % size;
                          for (uint32_t col = 0; col < size; ++col)
                          {
                              glm::dvec3 sum(0.0), lit(0.0), plain(0.0);
                              double luminance = 0.0;
                              for (uint32_t j = 0; j < block; ++j)
                                  for (uint32_t i = 0; i < block; ++i)
                                  {
                                      const uint32_t fc = col * block + i, fr = row * block + j;
                                      const double w = omega[size_t(fr) * fine + fc];
                                      if (w <= 0.0)
                                          continue;
                                      const glm::dvec3 d = level.direction(half, fc, fr);
                                      const float* t = level.at(half, fc, fr);
                                      const glm::dvec3 radiance = w * glm::dvec3(t[0], t[1], t[2]);
                                      const double y = math::luminance(radiance);
                                      sum += radiance;
                                      lit += std::max(y, 0.0) * d; // negative pixels cannot pull it out
                                      luminance += std::max(y, 0.0);
                                      plain += w * d;
                                  }
                              const glm::dvec3 mean = luminance > 0.0 && glm::length(lit) > 0.0 ? lit : plain;
                              const glm::dvec3 d = glm::length(mean) > 0.0
                                                       ? glm::normalize(mean)
                                                       : level.direction(half, col * block, row * block);
                              const size_t k = (size_t(half) * size + row) * size + col;
                              s.dx[k] = float(d.x), s.dy[k] = float(d.y), s.dz[k] = float(d.z);
                              s.wr[k] = float(sum.x), s.wg[k] = float(sum.y), s.wb[k] = float(sum.z);
                          }
                      });
    return s;
}

// Eq. 9's sum at direction r over the source texels inside the lobe's cap (where it exceeds 1e-4 of its
// peak), found as the stereographic image of the cap in each half, each texel at its centre direction with
// its solid angle inside the circle; without the (e + 1) / 2 pi normalisation. Counts the texels visited.
glm::dvec3 lobe_sum(const SourceTexels& src, const PhongLobe& lobe, const glm::dvec3& r, uint64_t& pairs)
{
    const uint32_t size = src.size;
    const double m = src.extent;
    const double gamma = lobe.angle();
    const double cos_cut = std::cos(gamma);
    const float cut = lobe.cos_cut();
    const float rx = float(r.x), ry = float(r.y), rz = float(r.z);
    double acc[3] = {0, 0, 0};
    for (int half = 0; half < 2; ++half)
    {
        const double sigma = half == 0 ? 1.0 : -1.0;
        uint32_t c0 = 0, c1 = size - 1, r0 = 0, r1 = size - 1;
        bool disc = false;
        double cx = 0.0, cy = 0.0, reach = 0.0;
        // The cap's image in this half: a disc, unless the cap holds the half's projection pole (0, 0,
        // -sigma).
        if (-sigma * r.z < cos_cut)
        {
            const double theta = std::atan2(std::sqrt(r.x * r.x + r.y * r.y), r.z);
            const double phi = std::atan2(r.y, r.x);
            auto rho = [&](double t) { return std::sin(t) / (1.0 + sigma * std::cos(t)); };
            // Near the pole test's edge theta +- gamma can round past the pole: keep the whole square.
            const bool near_pole =
                1.0 + sigma * std::cos(theta - gamma) < 1e-9 || 1.0 + sigma * std::cos(theta + gamma) < 1e-9;
            if (!near_pole)
            {
                const double p0 = rho(theta - gamma), p1 = rho(theta + gamma);
                const double centre = 0.5 * (p0 + p1), radius = 0.5 * std::abs(p1 - p0);
                cx = centre * std::cos(phi), cy = centre * std::sin(phi);
                // Per row, the texels within the disc widened by one and a half texels: a texel's direction
                // may lie anywhere in its square (a block's, at shift > 0), and rounding.
                disc = true;
                reach = radius + 3.0 * m / size;
                // Texel centres within [cx - radius, cx + radius] (one texel of margin for rounding).
                auto to_col = [&](double x) { return (x / m + 1.0) * 0.5 * size - 0.5; };
                auto to_row = [&](double y) { return (1.0 - y / m) * 0.5 * size - 0.5; };
                const double lo_c = std::floor(to_col(cx - radius)) - 1,
                             hi_c = std::ceil(to_col(cx + radius)) + 1;
                const double lo_r = std::floor(to_row(cy + radius)) - 1,
                             hi_r = std::ceil(to_row(cy - radius)) + 1;
                if (hi_c < 0 || hi_r < 0 || lo_c > size - 1 || lo_r > size - 1)
                    continue;
                c0 = uint32_t(std::max(0.0, lo_c));
                c1 = uint32_t(std::min(double(size - 1), hi_c));
                r0 = uint32_t(std::max(0.0, lo_r));
                r1 = uint32_t(std::min(double(size - 1), hi_r));
            }
        }
        for (uint32_t row = r0; row <= r1; ++row)
        {
            uint32_t first = c0, last = c1;
            // Only the texels that own directions count (their solid angle inside the circle is not 0): the
            // circle's chord on this row, one texel wider.
            const double y = m * (1.0 - (row + 0.5) * 2.0 / size), texel = 2.0 * m / size;
            const double ring = 1.0 + 1.5 * texel;
            if (std::abs(y) > ring)
                continue;
            {
                const double w = std::sqrt(ring * ring - y * y);
                const double lo = std::floor((-w) / m * 0.5 * size + 0.5 * size - 0.5),
                             hi = std::ceil(w / m * 0.5 * size + 0.5 * size - 0.5);
                first = uint32_t(std::max(double(first), lo));
                last = uint32_t(std::min(double(last), hi));
                if (first > last)
                    continue;
            }
            if (disc)
            {
                const double dy = y - cy;
                if (std::abs(dy) > reach)
                    continue;
                const double w = std::sqrt(reach * reach - dy * dy);
                const double lo = std::floor((cx - w) / m * 0.5 * size + 0.5 * size - 0.5),
                             hi = std::ceil((cx + w) / m * 0.5 * size + 0.5 * size - 0.5);
                if (hi < double(first) || lo > double(last))
                    continue;
                first = uint32_t(std::max(double(first), lo));
                last = uint32_t(std::min(double(last), hi));
            }
            const size_t base = (size_t(half) * size + row) * size;
            float ar = 0, ag = 0, ab = 0;
            for (uint32_t col = first; col <= last; ++col)
            {
                const size_t k = base + col;
                const float c = src.dx[k] * rx + src.dy[k] * ry + src.dz[k] * rz;
                if (c > cut)
                {
                    const float w = lobe(c); // c may exceed 1 by a rounding step: the lobe clamps it
                    ar += w * src.wr[k];
                    ag += w * src.wg[k];
                    ab += w * src.wb[k];
                }
            }
            acc[0] += ar, acc[1] += ag, acc[2] += ab;
            pairs += last - first + 1;
        }
    }
    return {acc[0], acc[1], acc[2]};
}

const ParabolicImage& chain_level(const std::vector<ParabolicImage>& chain, uint32_t size)
{
    for (const ParabolicImage& level : chain)
        if (level.size == size)
            return level;
    throw std::invalid_argument("the mipmap chain has no level of size " + std::to_string(size));
}

void check_prefilter(const std::vector<ParabolicImage>& chain, double exponent)
{
    if (!std::isfinite(exponent) || !(exponent > 0.0) || exponent > kMaxPhongExponent)
        throw std::invalid_argument("a glossy map's Phong exponent must be in (0, " +
                                    std::to_string(int(kMaxPhongExponent)) + "], got " +
                                    std::to_string(exponent));
    if (chain.empty())
        throw std::invalid_argument("prefilter_phong needs a mipmap chain");
}

// Catmull-Rom at the midpoint of its middle interval: the cubic through four equally spaced samples.
inline float midpoint(float a, float b, float c, float d)
{
    return (9.0f * (b + c) - (a + d)) / 16.0f;
}

} // namespace

ParabolicImage prefilter_phong_exact(const std::vector<ParabolicImage>& chain, double exponent,
                                     PrefilterStats* stats)
{
    check_prefilter(chain, exponent);
    const auto start = std::chrono::steady_clock::now();
    const uint32_t size = glossy_size(exponent, chain[0].size);
    const SourceTexels src = source_texels(chain_level(chain, size));
    const PhongLobe lobe(exponent);
    const double norm = (exponent + 1.0) / (2.0 * kPi);
    ParabolicImage out;
    out.size = size;
    out.extent = parabolic_extent(size);
    out.rgb.assign(size_t(2) * size * size * 3, 0.0f);
    std::atomic<uint64_t> pairs{0};
    tbb::parallel_for(uint32_t(0), 2 * size,
                      [&](uint32_t hr)
                      {
                          const int out_half = int(hr / size);
                          const uint32_t out_row = hr % size;
                          uint64_t local_pairs = 0;
                          for (uint32_t out_col = 0; out_col < size; ++out_col)
                          {
                              const glm::dvec3 e =
                                  norm *
                                  lobe_sum(src, lobe, out.direction(out_half, out_col, out_row), local_pairs);
                              float* t = out.at(out_half, out_col, out_row);
                              t[0] = float(e.x), t[1] = float(e.y), t[2] = float(e.z);
                          }
                          pairs += local_pairs;
                      });
    if (stats)
    {
        stats->texel_pairs = pairs;
        stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return out;
}

ParabolicImage prefilter_phong(const std::vector<ParabolicImage>& chain, double exponent,
                               PrefilterStats* stats, const PrefilterOptions& options)
{
    check_prefilter(chain, exponent);
    const auto start = std::chrono::steady_clock::now();
    const uint32_t size = glossy_size(exponent, chain[0].size);
    // The source: the level of the output's size, its texels merged into blocks of 2^shift x 2^shift, the
    // largest at which the lobe still spans options.source_texels blocks (its width 1 / sqrt(e) against a
    // block's 4 m 2^shift / size radians at a half's centre).
    uint32_t shift = 0;
    while ((size >> (shift + 1)) >= 8 &&
           double(size >> (shift + 1)) / (4.0 * parabolic_extent(size) * std::sqrt(exponent)) >=
               options.source_texels)
        ++shift;
    const SourceTexels src = source_texels(chain_level(chain, size), shift);
    const PhongLobe lobe(exponent);
    const double norm = (exponent + 1.0) / (2.0 * kPi);
    ParabolicImage out;
    out.size = size;
    out.extent = parabolic_extent(size);
    out.rgb.assign(size_t(2) * size * size * 3, 0.0f);
    // The sums at the texels of even index and at 1, size - 3 and size - 1 along each axis; the others from
    // Catmull-Rom along rows, then along columns (the map is the lobe's blur of the environment: smooth over
    // the lobe's width, 4 texels where it is narrowest).
    // Interpolation needs the lobe at least 3.5 texels wide at a half's centre (glossy_size makes it 4 unless
    // the chain's size caps it).
    const bool sparse = size >= 64 && options.interpolate &&
                        double(size) / (4.0 * parabolic_extent(size) * std::sqrt(exponent)) >= 3.5;
    auto exact = [&](uint32_t i)
    { return !sparse || i % 2 == 0 || i == 1 || i + 3 == size || i + 1 == size; };
    std::atomic<uint64_t> pairs{0};
    tbb::parallel_for(uint32_t(0), 2 * size,
                      [&](uint32_t hr)
                      {
                          const int half = int(hr / size);
                          const uint32_t row = hr % size;
                          if (!exact(row))
                              return;
                          uint64_t local_pairs = 0;
                          for (uint32_t col = 0; col < size; ++col)
                              if (exact(col))
                              {
                                  const glm::dvec3 e =
                                      norm * lobe_sum(src, lobe, out.direction(half, col, row), local_pairs);
                                  float* t = out.at(half, col, row);
                                  t[0] = float(e.x), t[1] = float(e.y), t[2] = float(e.z);
                              }
                          if (sparse)
                              for (uint32_t col = 3; col + 3 < size; col += 2)
                                  if (!exact(col))
                                      for (int c = 0; c < 3; ++c)
                                          out.at(half, col, row)[c] = midpoint(
                                              out.at(half, col - 3, row)[c], out.at(half, col - 1, row)[c],
                                              out.at(half, col + 1, row)[c], out.at(half, col + 3, row)[c]);
                          pairs += local_pairs;
                      });
    if (sparse)
        tbb::parallel_for(uint32_t(0), 2 * size,
                          [&](uint32_t hr)
                          {
                              const int half = int(hr / size);
                              const uint32_t row = hr % size;
                              if (exact(row))
                                  return;
                              for (uint32_t col = 0; col < size; ++col)
                                  for (int c = 0; c < 3; ++c)
                                      out.at(half, col, row)[c] = midpoint(
                                          out.at(half, col, row - 3)[c], out.at(half, col, row - 1)[c],
                                          out.at(half, col, row + 1)[c], out.at(half, col, row + 3)[c]);
                          });
    if (stats)
    {
        stats->texel_pairs = pairs;
        stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return out;
}

PhongLobe::PhongLobe(double exponent, double cutoff)
{
    const double cos_cut = std::pow(cutoff, 1.0 / exponent);
    angle_ = std::acos(cos_cut);
    cut_ = float(cos_cut);
    scale_ = float(kIntervals / (1.0 - cos_cut));
    table_.resize(kIntervals + 2);
    for (int i = 0; i <= kIntervals + 1; ++i)
    {
        const double c = 1.0 - std::min(1.0, double(i) / kIntervals) * (1.0 - cos_cut);
        table_[i] = float(std::pow(c, exponent));
    }
}

std::vector<float> fresnel_table(double ior, uint32_t size)
{
    if (!std::isfinite(ior) || !(ior > 1.0))
        throw std::invalid_argument("the index of refraction must be a finite number > 1, got " +
                                    std::to_string(ior));
    if (size < 2)
        throw std::invalid_argument("a Fresnel table needs at least 2 samples");
    std::vector<float> out(size);
    for (uint32_t i = 0; i < size; ++i)
        out[i] = float(fresnel_dielectric(double(i) / double(size - 1), ior));
    return out;
}

} // namespace hemi::math
