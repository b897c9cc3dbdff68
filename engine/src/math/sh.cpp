#include <hemi/math/quadrature.h>
#include <hemi/math/sh.h>

#include "hemi/shared/sh_constants.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::math
{

namespace
{
void check_order(int order)
{
    if (order < 1 || order > kMaxShOrder)
        throw std::invalid_argument("hemi: SH order " + std::to_string(order) + " is not in [1, " +
                                    std::to_string(kMaxShOrder) + "]");
}

// K_lm * sqrt(2) (m != 0) or K_l0: the normalisation of the real SH, sqrt((2l+1)/(4pi) (l-|m|)!/(l+|m|)!),
// and the Legendre recurrence's factors (2l - 1) / (l - m) and (l + m - 1) / (l - m) for l > m + 1: sh_eval
// runs for every ray of a PRT bake, and a division costs as much as the rest of a step.
struct ShNormalisation
{
    double k[kMaxShOrder][kMaxShOrder];
    double a[kMaxShOrder][kMaxShOrder] = {}, b[kMaxShOrder][kMaxShOrder] = {};
    ShNormalisation()
    {
        for (int l = 0; l < kMaxShOrder; ++l)
            for (int m = 0; m < l; ++m)
            {
                a[l][m] = (2.0 * l - 1.0) / double(l - m);
                b[l][m] = (l + m - 1.0) / double(l - m);
            }
        for (int l = 0; l < kMaxShOrder; ++l)
            for (int m = 0; m <= l; ++m)
            {
                double ratio = 1.0; // (l-m)!/(l+m)!
                for (int i = l - m + 1; i <= l + m; ++i)
                    ratio /= i;
                k[l][m] = std::sqrt((2.0 * l + 1.0) / (4.0 * M_PI) * ratio) * (m ? std::sqrt(2.0) : 1.0);
            }
    }
};
const ShNormalisation kNorm;
} // namespace

void sh_eval(int order, const glm::vec3& d, std::span<float> out)
{
    check_order(order);
    if (out.size() < size_t(sh_count(order)))
        throw std::invalid_argument("hemi: sh_eval output too short");
    const double x = d.x, y = d.y, z = d.z;
    // P~_l^m(z) = P_l^m(z) / sin^m(theta) (Condon-Shortley phase included), and
    // (x + i y)^m = sin^m(theta) (cos m phi + i sin m phi), so y_lm = K P~_l^m * Re/Im (x + iy)^m.
    double cm = 1.0, sm = 0.0; // Re, Im of (x + iy)^m
    double pmm = 1.0;          // P~_m^m = (-1)^m (2m-1)!!
    for (int m = 0; m < order; ++m)
    {
        double p_prev = 0.0, p = pmm; // P~_{l-1}^m, P~_l^m starting at l = m
        for (int l = m; l < order; ++l)
        {
            if (l > m)
            {
                double next =
                    (l == m + 1) ? z * (2.0 * m + 1.0) * pmm : kNorm.a[l][m] * z * p - kNorm.b[l][m] * p_prev;
                p_prev = p;
                p = next;
            }
            double base = kNorm.k[l][m] * p;
            if (m == 0)
                out[sh_index(l, 0)] = float(base);
            else
            {
                out[sh_index(l, m)] = float(base * cm);
                out[sh_index(l, -m)] = float(base * sm);
            }
        }
        double c = cm * x - sm * y, s = cm * y + sm * x;
        cm = c;
        sm = s;
        pmm *= -(2.0 * m + 1.0);
    }
}

Sh9 sh9_eval(const glm::vec3& d)
{
    Sh9 y;
    sh9_basis(d.x, d.y, d.z, y.data());
    return y;
}

std::vector<glm::vec3> project_sh(int order, const std::function<glm::vec3(const glm::vec3&)>& radiance,
                                  int theta_steps)
{
    check_order(order);
    if (theta_steps < 4)
        throw std::invalid_argument("hemi: project_sh needs at least 4 theta steps");
    // Gauss-Legendre in z = cos(theta) (exact for polynomials in z of degree < 2 * theta_steps) times a
    // uniform rule in phi (exact for trigonometric polynomials of degree < 2 * theta_steps).
    const int n = sh_count(order), phi_steps = 2 * theta_steps;
    const double dphi = 2.0 * M_PI / phi_steps;
    const QuadratureRule rule = gauss_legendre(theta_steps);
    const std::vector<double>&zs = rule.x, &ws = rule.w;
    std::vector<glm::dvec3> acc(n, glm::dvec3(0.0));
    std::vector<float> y(n);
    for (int t = 0; t < theta_steps; ++t)
    {
        double z = zs[t], r = std::sqrt(std::max(0.0, 1.0 - z * z));
        double w = ws[t] * dphi; // solid angle of the sample
        for (int p = 0; p < phi_steps; ++p)
        {
            double phi = (p + 0.5) * dphi;
            glm::vec3 d(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
            glm::vec3 l = radiance(d);
            if (!std::isfinite(l.x) || !std::isfinite(l.y) || !std::isfinite(l.z))
                throw std::invalid_argument("hemi: project_sh: radiance is not finite");
            sh_eval(order, d, y);
            for (int i = 0; i < n; ++i)
                acc[i] += glm::dvec3(l) * (double(y[i]) * w);
        }
    }
    std::vector<glm::vec3> out(n);
    for (int i = 0; i < n; ++i)
        out[i] = glm::vec3(acc[i]);
    return out;
}

Sh9Rgb project_sh9(const std::function<glm::vec3(const glm::vec3&)>& radiance, int theta_steps)
{
    std::vector<glm::vec3> c = project_sh(3, radiance, theta_steps);
    Sh9Rgb out;
    std::copy(c.begin(), c.end(), out.begin());
    return out;
}

double clamped_cosine_factor(int l)
{
    if (l < 0)
        throw std::invalid_argument("hemi: negative SH band");
    if (l == 0)
        return M_PI;
    if (l == 1)
        return 2.0 * M_PI / 3.0;
    if (l % 2)
        return 0.0;
    // Ramamoorthi & Hanrahan 2001, Eq. (8): A_l = 2 pi (-1)^(l/2-1) / ((l+2)(l-1)) * l! / (2^l ((l/2)!)^2).
    double ratio = 1.0; // l! / (2^l ((l/2)!)^2), built as a product to stay exact for large l
    for (int i = 1; i <= l / 2; ++i)
        ratio *= double(l / 2 + i) / (4.0 * i);
    double sign = ((l / 2 - 1) % 2) ? -1.0 : 1.0;
    return 2.0 * M_PI * sign / double((l + 2) * (l - 1)) * ratio;
}

static int order_of(size_t count)
{
    int order = int(std::lround(std::sqrt(double(count))));
    if (order < 1 || size_t(order * order) != count || order > kMaxShOrder)
        throw std::invalid_argument("hemi: " + std::to_string(count) + " is not an SH coefficient count");
    return order;
}

void convolve_cosine(std::span<glm::vec3> c)
{
    int order = order_of(c.size());
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m)
            c[sh_index(l, m)] *= float(clamped_cosine_factor(l));
}

Sh9Rgb convolve_cosine(const Sh9Rgb& radiance)
{
    Sh9Rgb out = radiance;
    convolve_cosine(std::span<glm::vec3>(out));
    return out;
}

double sh_window_weight(ShWindow window, int l, int order, double strength)
{
    switch (window)
    {
    case ShWindow::None:
        return 1.0;
    case ShWindow::Hanning:
        return 0.5 * (1.0 + std::cos(M_PI * l / order));
    case ShWindow::Lanczos:
        return l == 0 ? 1.0 : std::sin(M_PI * l / order) / (M_PI * l / order);
    case ShWindow::Laplacian:
        return 1.0 / (1.0 + strength * double(l) * l * (l + 1.0) * (l + 1.0));
    }
    return 1.0;
}

void apply_window(std::span<glm::vec3> c, ShWindow window, double strength)
{
    int order = order_of(c.size());
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m)
            c[sh_index(l, m)] *= float(sh_window_weight(window, l, order, strength));
}

glm::vec3 sh_eval_rgb(std::span<const glm::vec3> c, const glm::vec3& d)
{
    int order = order_of(c.size());
    float y[kMaxShOrder * kMaxShOrder];
    sh_eval(order, d, std::span<float>(y, size_t(sh_count(order))));
    glm::vec3 sum(0.0f);
    for (size_t i = 0; i < c.size(); ++i)
        sum += c[i] * y[i];
    return sum;
}

glm::vec3 sh9_eval_rgb(const Sh9Rgb& c, const glm::vec3& d)
{
    Sh9 y = sh9_eval(d);
    glm::vec3 sum(0.0f);
    for (int i = 0; i < 9; ++i)
        sum += c[i] * y[i];
    return sum;
}

glm::vec3 AnalyticSky::radiance(const glm::vec3& d) const
{
    glm::vec3 base;
    if (d.z >= 0.0f)
    {
        float t = std::sqrt(d.z);
        base = horizon + (zenith - horizon) * t;
    }
    else
    {
        float t = std::min(1.0f, -d.z * 4.0f);
        base = horizon * 0.5f + (ground - horizon * 0.5f) * t;
    }
    float s = std::max(0.0f, glm::dot(d, glm::normalize(sun)));
    return base + sun_color * std::pow(s, sun_exponent);
}

} // namespace hemi::math
