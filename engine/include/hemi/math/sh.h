#pragma once
// Real spherical harmonics, bands 0-2 (SH9), in hemi's convention (DESIGN.md Sec. 3): Condon-Shortley
// phase, index i = l(l+1)+m, y1,-1 = -0.488603 y, y1,0 = 0.488603 z, y1,1 = -0.488603 x, ...
// The math core of later issues extends this to any order; this is what the foundation needs:
// evaluation, numerical projection of a radiance function, and the clamped-cosine convolution.
//
// Based on: R. Ramamoorthi, P. Hanrahan, "An Efficient Representation for Irradiance Environment Maps",
// SIGGRAPH 2001 (irradiance = A_l L_lm); P.-P. Sloan, "Stupid Spherical Harmonics (SH) Tricks", GDC 2008.

#include <glm/vec3.hpp>

#include <array>
#include <functional>

namespace hemi::math
{

using Sh9 = std::array<float, 9>;
using Sh9Rgb = std::array<glm::vec3, 9>;

// The 9 basis functions at unit direction `d` (any frame; the caller's).
Sh9 sh9_eval(const glm::vec3& d);

// Projects a radiance function over the sphere onto SH9 by quadrature: `theta_steps` Gauss-Legendre nodes in
// cos(theta) times 2*`theta_steps` uniform steps in phi (exact for band-limited radiance up to band
// 2*theta_steps - 3). Throws std::invalid_argument when the function returns a non-finite value.
Sh9Rgb project_sh9(const std::function<glm::vec3(const glm::vec3&)>& radiance, int theta_steps = 128);

// Clamped-cosine convolution: radiance coefficients L_lm -> irradiance coefficients A_l L_lm.
Sh9Rgb convolve_cosine(const Sh9Rgb& radiance);

// sum_i c_i y_i(d): with irradiance coefficients, E(d) at unit normal d.
glm::vec3 sh9_eval_rgb(const Sh9Rgb& coefficients, const glm::vec3& d);

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
