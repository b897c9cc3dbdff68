#pragma once
// Heidrich & Seidel's parabolic environment maps (1999, §4): the whole sphere of directions in two square
// images, their solid-angle-weighted mipmaps (§4.2) and the prefiltered glossy (Phong, Eq. 9) and diffuse
// maps (§4.3, §4.5).
//
// Conventions (z up, hemi's world and tangent space):
//  - half 0 (front) holds the directions with z >= 0, half 1 (back) those with z < 0. A direction d maps to
//    (x, y) = (d.x, d.y) / (1 + |d.z|) in its own half: the reflection off the paraboloid f = 1/2 - (x^2 +
//    y^2)/2 of Eq. 5 (a stereographic projection, so circles on the sphere stay circles). The inverse is d =
//    (2x, 2y, ±(1 - x^2 - y^2)) / (1 + x^2 + y^2).
//  - each half covers the square [-m, m]^2, m = extent >= 1: outside the unit circle it continues into the
//  other
//    hemisphere (the extended paraboloid of the paper's Fig. 6), so that mipmapping and bilinear filtering
//    see the right neighbours and the two halves agree along the circle |(x, y)| = 1 (the seam, d.z = 0). The
//    paper's square is m = 1; hemi's maps take m = size / (size - 2) at their level 0, one texel beyond the
//    circle where it meets the square's edges, so that a bilinear lookup on the seam has texels on both sides
//    there too (with m = 1 the sampler clamps at those four points and the halves disagree by half a texel's
//    change).
//  - texel (col, row) of a size x size half has its centre at x = m (-1 + (col + 0.5) 2 / size) and
//    y = m (1 - (row + 0.5) 2 / size) (rows from the top, y up the image); a shader samples half h at
//    u = (x / m + 1) / 2, v = (1 - y / m) / 2, layer h.
//  - the solid angle of a region is the integral of d_omega = 4 dA / (1 + x^2 + y^2)^2 (Eq. 6): 4 per unit
//  area
//    at the centre, 1 on the circle, a ratio of 4 inside the circle.

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace hemi::math
{

// The half a direction lies in (0 for z >= 0) and its (x, y) there.
int parabolic_half(const glm::dvec3& d);
glm::dvec2 parabolic_xy(const glm::dvec3& d, int half);
// The unit direction at (x, y) of `half`, for any (x, y) (outside the circle: the other hemisphere).
glm::dvec3 parabolic_direction(int half, double x, double y);

// Solid angle of the rectangle [x0, x1] x [y0, y1] of a half (the integral of Eq. 6; regions outside the unit
// circle count too; exact to ~1e-12), and of its part inside the unit circle (the directions the half owns;
// to ~1e-7 for rectangles where the circle meets x = +-1, ~1e-12 elsewhere).
double parabolic_solid_angle(double x0, double y0, double x1, double y1);
double parabolic_solid_angle_in_circle(double x0, double y0, double x1, double y1);

// Both halves of a parabolic map at one resolution: RGB floats, half h, row, col at
// ((h * size + row) * size + col) * 3.
struct ParabolicImage
{
    uint32_t size = 0;
    double extent = 1.0; // m: the half covers [-m, m]^2
    std::vector<float> rgb;

    const float* at(int half, uint32_t col, uint32_t row) const
    {
        return rgb.data() + ((size_t(half) * size + row) * size + col) * 3;
    }
    float* at(int half, uint32_t col, uint32_t row)
    {
        return rgb.data() + ((size_t(half) * size + row) * size + col) * 3;
    }
    // The direction through a texel's centre, and the texel's solid angle (whole, and inside the circle).
    glm::dvec3 direction(int half, uint32_t col, uint32_t row) const;
    double solid_angle(uint32_t col, uint32_t row) const;
    double solid_angle_in_circle(uint32_t col, uint32_t row) const;
    // Bilinear lookup in the half the direction lies in, clamped to the square's edge: what a GPU's sampler
    // returns for (u, v) of the convention above.
    glm::dvec3 sample(const glm::dvec3& d) const;
};

// Resamples an equirectangular environment (sh_environment.h's convention, width x height RGBA floats,
// constant over each pixel) into both halves at `size` with extent parabolic_extent(size) (a power of
// two, 2..8192): each texel is the solid-angle-weighted average of a grid of n x n points over its whole
// square, n = 4 width / (pi size) clamped to [2, 16] (two points per equirect pixel at a half's centre). An
// environment wider than about 12 size is point-sampled by that grid: downsample it first. Throws
// std::invalid_argument for inconsistent sizes, a size that is not a power of two, or a non-finite pixel.
ParabolicImage parabolic_from_equirect(uint32_t size, uint32_t width, uint32_t height,
                                       std::span<const float> rgba);

// The mipmap chain of §4.2, level 0 first, down to 1 x 1: each texel of level k + 1 is the
// solid-angle-weighted mean of its 2 x 2 texels at level k (weights: each texel's whole solid angle, Eq. 6).
std::vector<ParabolicImage> parabolic_mip_chain(ParabolicImage level0);

// The extent hemi gives a map whose level 0 is size x size: size / (size - 2) (1 for size <= 2).
double parabolic_extent(uint32_t size);

// The size at which a glossy map of Phong exponent e is stored: the lobe's width (about 1 / sqrt(e) radians)
// spans at least 4 texels at the centre of a half (8 at its circle): the power of two >= 16 sqrt(e), at least
// 32 and at most `full_size`.
uint32_t glossy_size(double exponent, uint32_t full_size);

struct PrefilterStats
{
    uint64_t texel_pairs = 0; // lobe evaluations
    double seconds = 0.0;
};

// The prefiltered glossy map of Eq. 9 for Phong exponent e (> 0), at glossy_size(e, chain[0].size):
//   L_o(r) = ((e + 1) / 2 pi) * integral over the sphere of max(0, r.l)^e L_i(l) d_omega(l)
// (normalised so that a constant environment stays constant; multiply by ks), for the direction r of every
// texel of both whole squares (extent parabolic_extent of its size). e = 1 gives the diffuse map: (1 / pi) *
// integral of max(0, n.l) L_i = E(n) / pi. Throws std::invalid_argument for e <= 0, not finite or above
// kMaxPhongExponent (a lobe far narrower than any texel: a mirror).
//
// prefilter_phong_exact sums, for every texel, over the texels of the chain's level of the same size, each at
// its centre direction with its solid angle inside the circle, over the texels where the lobe exceeds 1e-4
// of its peak (found as the stereographic image of that cap): the brute force (hemi-bake envmap --exact).
//
// prefilter_phong makes the same map faster: the sum over blocks of 2^k x 2^k texels of that level where the
// lobe is wide enough (it spans options.source_texels blocks), each at the luminance-weighted mean of its
// texels' directions with their radiance times solid angle inside the circle summed, and only at every
// other texel along each axis (and
// the texels next to the squares' edges), the rest interpolated (Catmull-Rom: the map is the environment
// blurred by the lobe, smooth over its width, which glossy_size makes at least 4 texels). Its difference from
// the exact map is measured in tests/math/factored_test.cpp and docs/factored.md.
constexpr double kMaxPhongExponent = 1e6;
struct PrefilterOptions
{
    double source_texels = 2.0; // the lobe's width (1 / sqrt(e) radians) in texels of the source level
    bool interpolate = true;    // sums at every other texel, the rest interpolated
};
ParabolicImage prefilter_phong(const std::vector<ParabolicImage>& chain, double exponent,
                               PrefilterStats* stats = nullptr, const PrefilterOptions& options = {});
ParabolicImage prefilter_phong_exact(const std::vector<ParabolicImage>& chain, double exponent,
                                     PrefilterStats* stats = nullptr);

// max(0, c)^e over the cap where it exceeds `cutoff` of its peak, tabulated (4096 intervals against
// (1 - c) / (1 - cos_cut): linear interpolation exact to ~1e-6 of the peak): what prefilter_phong sums,
// shared with the cube-map implementation of the same filter the envmap report compares against.
class PhongLobe
{
  public:
    PhongLobe(double exponent, double cutoff = 1e-4);
    float cos_cut() const { return cut_; }
    double angle() const { return angle_; } // acos(cos_cut)
    // The lobe at c (> cos_cut; c may exceed 1 by rounding).
    float operator()(float c) const
    {
        const float s = std::clamp((1.0f - c) * scale_, 0.0f, float(kIntervals));
        const int i = int(s);
        const float f = s - float(i);
        return table_[i] + f * (table_[i + 1] - table_[i]);
    }

  private:
    static constexpr int kIntervals = 4096;
    std::vector<float> table_;
    float cut_ = 0.0f, scale_ = 0.0f;
    double angle_ = 0.0;
};

// The Fresnel term of §4.4 as a 1D table: sample i of `size` (>= 2) at cos = i / (size - 1). Throws
// std::invalid_argument for ior <= 1 or not finite.
std::vector<float> fresnel_table(double ior, uint32_t size);

} // namespace hemi::math
