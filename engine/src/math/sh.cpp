#include <hemi/math/sh.h>

#include "hemi/shared/sh_constants.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace hemi::math
{

Sh9 sh9_eval(const glm::vec3& d)
{
    const float x = d.x, y = d.y, z = d.z;
    return {float(HEMI_SH_Y00),
            -float(HEMI_SH_Y1) * y,
            float(HEMI_SH_Y1) * z,
            -float(HEMI_SH_Y1) * x,
            float(HEMI_SH_Y2) * x * y,
            -float(HEMI_SH_Y2) * y * z,
            float(HEMI_SH_Y20) * (3.0f * z * z - 1.0f),
            -float(HEMI_SH_Y2) * x * z,
            float(HEMI_SH_Y22) * (x * x - y * y)};
}

namespace
{
// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n; Numerical Recipes' gauleg).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w)
{
    x.resize(n);
    w.resize(n);
    for (int i = 0; i < (n + 1) / 2; ++i)
    {
        double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), pp = 0.0;
        for (int iter = 0; iter < 100; ++iter)
        {
            double p1 = 1.0, p2 = 0.0;
            for (int j = 1; j <= n; ++j)
            {
                double p3 = p2;
                p2 = p1;
                p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
            }
            pp = n * (z * p1 - p2) / (z * z - 1.0);
            double z1 = z;
            z = z1 - p1 / pp;
            if (std::abs(z - z1) < 1e-15)
                break;
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * pp * pp);
    }
}
} // namespace

Sh9Rgb project_sh9(const std::function<glm::vec3(const glm::vec3&)>& radiance, int theta_steps)
{
    if (theta_steps < 4)
        throw std::invalid_argument("hemi: project_sh9 needs at least 4 theta steps");
    // Gauss-Legendre in z = cos(theta) (exact for polynomials in z of degree < 2 * theta_steps) times a
    // uniform rule in phi (exact for trigonometric polynomials of degree < 2 * theta_steps).
    const int phi_steps = 2 * theta_steps;
    const double dphi = 2.0 * M_PI / phi_steps;
    std::vector<double> zs, ws;
    gauss_legendre(theta_steps, zs, ws);
    std::array<glm::dvec3, 9> acc{};
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
                throw std::invalid_argument("hemi: project_sh9: radiance is not finite");
            Sh9 y = sh9_eval(d);
            for (int i = 0; i < 9; ++i)
                acc[i] += glm::dvec3(l) * (double(y[i]) * w);
        }
    }
    Sh9Rgb out;
    for (int i = 0; i < 9; ++i)
        out[i] = glm::vec3(acc[i]);
    return out;
}

Sh9Rgb convolve_cosine(const Sh9Rgb& radiance)
{
    const float a[3] = {float(HEMI_SH_A0), float(HEMI_SH_A1), float(HEMI_SH_A2)};
    Sh9Rgb out;
    for (int i = 0; i < 9; ++i)
        out[i] = radiance[i] * a[i == 0 ? 0 : (i < 4 ? 1 : 2)];
    return out;
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
