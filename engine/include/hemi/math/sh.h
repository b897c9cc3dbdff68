#pragma once
// Real spherical harmonics in hemi's convention (DESIGN.md Sec. 3): Condon-Shortley phase, index
// i = l(l+1)+m, so y1,-1 = -0.488603 y, y1,0 = 0.488603 z, y1,1 = -0.488603 x, y2,-2 = 1.092548 xy, ...
// "Order n" means bands 0..n-1, i.e. n^2 coefficients (order 3 = SH9, order 5 = 25, order 6 = 36).
//
// Based on: R. Ramamoorthi, P. Hanrahan, "An Efficient Representation for Irradiance Environment Maps",
// SIGGRAPH 2001 (irradiance = A_l L_lm); P.-P. Sloan, "Stupid Spherical Harmonics (SH) Tricks", GDC 2008
// (windowing); J. Ivanic, K. Ruedenberg, "Rotation Matrices for Real Spherical Harmonics. Direct
// Determination by Recursion", J. Phys. Chem. 1996, with the 1998 additions and corrections.

#include "hemi/shared/sh_constants.h"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <functional>
#include <span>
#include <vector>

namespace hemi::math
{

constexpr int kMaxShOrder = 10; // bands 0..9, 100 coefficients
constexpr int sh_count(int order)
{
    return order * order;
}
constexpr int sh_index(int l, int m)
{
    return l * (l + 1) + m;
}

using Sh9 = std::array<float, 9>;
using Sh9Rgb = std::array<glm::vec3, 9>;

// The order^2 basis functions at unit direction `d` into out[0 .. order^2). Throws std::invalid_argument
// for order outside [1, kMaxShOrder] or a short `out`.
void sh_eval(int order, const glm::vec3& d, std::span<float> out);
// The 9 functions of bands 0-2 in closed form (the same values as sh_eval(3, ...)).
Sh9 sh9_eval(const glm::vec3& d);
// sh9_eval's closed form on three floats, inline: what a loop over many directions calls so that the
// compiler can vectorise it (the bake's per-texel sums). The same values as sh9_eval, which calls it.
inline void sh9_basis(float x, float y, float z, float* out)
{
    out[0] = float(HEMI_SH_Y00);
    out[1] = -float(HEMI_SH_Y1) * y;
    out[2] = float(HEMI_SH_Y1) * z;
    out[3] = -float(HEMI_SH_Y1) * x;
    out[4] = float(HEMI_SH_Y2) * x * y;
    out[5] = -float(HEMI_SH_Y2) * y * z;
    out[6] = float(HEMI_SH_Y20) * (3.0f * z * z - 1.0f);
    out[7] = -float(HEMI_SH_Y2) * x * z;
    out[8] = float(HEMI_SH_Y22) * (x * x - y * y);
}

// Projects a radiance function over the sphere onto SH of `order` by quadrature: `theta_steps`
// Gauss-Legendre nodes in cos(theta) times 2*`theta_steps` uniform steps in phi (exact for band-limited
// radiance up to band 2*theta_steps - order). Throws std::invalid_argument when the function returns a
// non-finite value.
std::vector<glm::vec3> project_sh(int order, const std::function<glm::vec3(const glm::vec3&)>& radiance,
                                  int theta_steps = 128);
Sh9Rgb project_sh9(const std::function<glm::vec3(const glm::vec3&)>& radiance, int theta_steps = 128);

// Funk-Hecke factor of the clamped cosine max(0, cos) for band l: A_0 = pi, A_1 = 2pi/3, A_2 = pi/4,
// A_3 = 0, A_4 = -pi/24, odd l > 1: 0.
double clamped_cosine_factor(int l);
// Radiance coefficients L_lm -> irradiance coefficients A_l L_lm (any order; sh9 overload for SH9).
void convolve_cosine(std::span<glm::vec3> coefficients);
Sh9Rgb convolve_cosine(const Sh9Rgb& radiance);

// Windows against ringing, applied per band as c_lm *= w_l.
enum class ShWindow
{
    None,
    Hanning,   // w_l = (1 + cos(pi l / (order))) / 2
    Lanczos,   // w_l = sinc(pi l / order)
    Laplacian, // w_l = 1 / (1 + lambda l^2 (l+1)^2): Sloan 2008, minimises the Laplacian (lambda = strength)
};
double sh_window_weight(ShWindow window, int l, int order, double strength = 0.0);
void apply_window(std::span<glm::vec3> coefficients, ShWindow window, double strength = 0.0);

// sum_i c_i y_i(d): with irradiance coefficients, E(d) at unit normal d.
glm::vec3 sh_eval_rgb(std::span<const glm::vec3> coefficients, const glm::vec3& d);
glm::vec3 sh9_eval_rgb(const Sh9Rgb& coefficients, const glm::vec3& d);

// Rotation of SH coefficient vectors by a 3x3 rotation, band by band (Ivanic-Ruedenberg recursion).
// If f has coefficients c, the rotated function g(d) = f(R^T d) has coefficients D c: rotating then
// evaluating at d equals evaluating the original at R^-1 d.
class ShRotation
{
  public:
    // Throws std::invalid_argument for an order outside [1, kMaxShOrder] or a rotation that is not finite.
    ShRotation(int order, const glm::mat3& rotation);
    int order() const { return order_; }
    // out = D in; in and out have order^2 entries and may not alias.
    void apply(std::span<const glm::vec3> in, std::span<glm::vec3> out) const;
    void apply(std::span<const float> in, std::span<float> out) const;
    // Element (m, n) of band l's (2l+1)^2 block, m, n in [-l, l].
    float element(int l, int m, int n) const;

    // Where band l's block starts: sum_{k<l} (2k+1)^2 = l (4l^2 - 1) / 3.
    static constexpr int block_offset(int l) { return l * (4 * l * l - 1) / 3; }
    static constexpr int kBlockFloats = kMaxShOrder * (4 * kMaxShOrder * kMaxShOrder - 1) / 3;

  private:
    int order_;
    // Band l's block at block_offset(l), row-major; fixed storage, so that a rotation made per object and
    // frame allocates nothing.
    std::array<float, kBlockFloats> blocks_{};
};

// An analytic sky with z up, in linear RGB radiance: a zenith-to-horizon gradient over a darker ground
// and a soft sun lobe. Smooth, so SH9 represents its irradiance well. `sun` is a unit direction.
struct AnalyticSky
{
    glm::vec3 zenith{0.25f, 0.45f, 0.95f};
    glm::vec3 horizon{0.85f, 0.85f, 0.9f};
    glm::vec3 ground{0.25f, 0.2f, 0.15f};
    glm::vec3 sun_color{6.0f, 5.2f, 4.0f};
    glm::vec3 sun{0.48f, -0.6f, 0.64f};
    float sun_exponent = 32.0f;

    glm::vec3 radiance(const glm::vec3& d) const;
};

} // namespace hemi::math
