#include <hemi/math/ggx.h>
#include <hemi/math/quadrature.h>
#include <hemi/math/sh.h>

#include <Eigen/Dense>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace hemi::math
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

double alpha_of(double roughness)
{
    const double r = std::clamp(std::isfinite(roughness) ? roughness : 1.0, kGgxMinRoughness, 1.0);
    return r * r;
}

// D V (n.l) for the cosines (both > 0) and n.h.
double dv_cos(double nl, double nv, double nh, double a2)
{
    const double t = nh * nh * (a2 - 1.0) + 1.0;
    const double d = a2 / (kPi * t * t);
    const double v =
        0.5 / (nl * std::sqrt(nv * nv * (1.0 - a2) + a2) + nv * std::sqrt(nl * nl * (1.0 - a2) + a2));
    return d * v * nl;
}

// A unit frame about n.
void frame_about(const glm::dvec3& n, glm::dvec3& t, glm::dvec3& b)
{
    const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    t = glm::normalize(a - n * glm::dot(n, a));
    b = glm::cross(n, t);
}

// The half vector for (u0, u1) from D(h) (n.h): tan^2 theta = alpha^2 u0 / (1 - u0).
glm::dvec3 half_vector(const glm::dvec3& n, double a2, double u0, double u1)
{
    const double cos2 = (1.0 - u0) / (1.0 + (a2 - 1.0) * u0);
    const double c = std::sqrt(std::max(0.0, cos2)), s = std::sqrt(std::max(0.0, 1.0 - cos2));
    const double phi = 2.0 * kPi * u1;
    glm::dvec3 t, b;
    frame_about(n, t, b);
    return glm::normalize(t * (s * std::cos(phi)) + b * (s * std::sin(phi)) + n * c);
}
} // namespace

glm::dvec3 ggx_eval_cos(const glm::dvec3& n, const glm::dvec3& l, const glm::dvec3& v, double roughness,
                        const glm::dvec3& f0)
{
    const double nl = glm::dot(n, l), nv = glm::dot(n, v);
    const glm::dvec3 lv = l + v;
    if (!(nl > 0.0) || !(nv > 0.0) || glm::dot(lv, lv) < 1e-24)
        return glm::dvec3(0.0);
    const glm::dvec3 h = glm::normalize(lv);
    const double fc = std::pow(1.0 - std::clamp(glm::dot(v, h), 0.0, 1.0), 5.0);
    return (f0 + (glm::dvec3(1.0) - f0) * fc) *
           dv_cos(nl, nv, glm::dot(n, h), std::pow(alpha_of(roughness), 2));
}

glm::dvec3 ggx_sample(const glm::dvec3& n, const glm::dvec3& v, double roughness, double u0, double u1,
                      double& pdf)
{
    const double a2 = std::pow(alpha_of(roughness), 2);
    const glm::dvec3 h = half_vector(n, a2, u0, u1);
    const double vh = glm::dot(v, h), nh = glm::dot(n, h);
    const glm::dvec3 l = 2.0 * vh * h - v;
    pdf = 0.0;
    if (!(glm::dot(n, l) > 0.0) || !(vh > 0.0))
        return l;
    const double t = nh * nh * (a2 - 1.0) + 1.0;
    pdf = a2 / (kPi * t * t) * nh / (4.0 * vh);
    return l;
}

std::pair<double, double> ggx_albedo(double cos_v, double roughness)
{
    const double nv = std::clamp(cos_v, 1e-4, 1.0);
    const double a2 = std::pow(alpha_of(roughness), 2);
    const glm::dvec3 n(0, 0, 1), v(std::sqrt(1.0 - nv * nv), 0.0, nv);
    // Over the half vectors, distributed as D(h) (n.h): the integrand f_r (n.l) / pdf(l) is
    // V (n.l) 4 (v.h) / (n.h), smooth but where l crosses the horizon.
    const QuadratureRule q0 = gauss_legendre(192, 0.0, 1.0), q1 = gauss_legendre(96, 0.0, 1.0);
    double a = 0.0, b = 0.0;
    for (size_t i = 0; i < q0.x.size(); ++i)
        for (size_t j = 0; j < q1.x.size(); ++j)
        {
            const glm::dvec3 h = half_vector(n, a2, q0.x[i], q1.x[j]);
            const double vh = glm::dot(v, h), nh = h.z;
            const glm::dvec3 l = 2.0 * vh * h - v;
            if (!(l.z > 0.0) || !(vh > 0.0))
                continue;
            const double t = nh * nh * (a2 - 1.0) + 1.0;
            const double pdf = a2 / (kPi * t * t) * nh / (4.0 * vh);
            const double value = dv_cos(l.z, nv, nh, a2) / pdf * q0.w[i] * q1.w[j];
            const double fc = std::pow(1.0 - vh, 5.0);
            a += value * (1.0 - fc);
            b += value * fc;
        }
    return {a, b};
}

std::vector<std::pair<double, double>> ggx_albedo_fit()
{
    const int grid = 24, degree = kGgxAlbedoFitDegree, terms = (degree + 1) * (degree + 2) / 2;
    const double s0 = std::sqrt(0.05);
    Eigen::MatrixXd f(grid * grid, terms);
    Eigen::MatrixXd y(grid * grid, 2);
    for (int a = 0; a < grid; ++a)
        for (int b = 0; b < grid; ++b)
        {
            const double s = s0 + (1.0 - s0) * a / (grid - 1), roughness = 0.03 + 0.97 * b / (grid - 1);
            const auto [x, z] = ggx_albedo(s * s, roughness);
            const int row = a * grid + b;
            y(row, 0) = x;
            y(row, 1) = z;
            int term = 0;
            for (int i = 0; i <= degree; ++i)
                for (int j = 0; j <= degree - i; ++j)
                    f(row, term++) = std::pow(s, i) * std::pow(roughness, j);
        }
    const Eigen::MatrixXd c = f.colPivHouseholderQr().solve(y);
    std::vector<std::pair<double, double>> out;
    for (int t = 0; t < terms; ++t)
        out.emplace_back(c(t, 0), c(t, 1));
    return out;
}

std::vector<double> sh9_from_basis(const BasisDesc& basis)
{
    const int k = basis.size;
    std::vector<double> out(size_t(9) * size_t(k), 0.0);
    if (basis.id == HEMI_BASIS_SH9)
    {
        for (int j = 0; j < 9; ++j)
            out[size_t(j) * size_t(k) + size_t(j)] = 1.0;
        return out;
    }
    // The prior: suns of irradiance 1 spread evenly over the hemisphere (hemisphere_quadrature's nodes and
    // weights, symmetric under the rotations about z that bands 0-2 see), together as likely as a uniform
    // sky of irradiance 1 at the zenith (radiance 1 / pi: int_H y_j = 2 pi y00, pi y1 for j = 0, 2, zero
    // otherwise).
    Eigen::MatrixXd sigma = Eigen::MatrixXd::Zero(9, 9);
    const double a[9] = {kPi,     2 * kPi / 3, 2 * kPi / 3, 2 * kPi / 3, kPi / 4,
                         kPi / 4, kPi / 4,     kPi / 4,     kPi / 4};
    for (const HemisphereSample& q : hemisphere_quadrature(32))
    {
        const Sh9 y = sh9_eval(glm::vec3(q.n));
        Eigen::VectorXd e(9);
        for (int j = 0; j < 9; ++j)
            e[j] = a[j] * double(y[size_t(j)]);
        sigma += e * e.transpose() * (q.weight / (2.0 * kPi));
    }
    Eigen::VectorXd sky = Eigen::VectorXd::Zero(9);
    sky[0] = a[0] * 2.0 * kPi * 0.28209479177387814 / kPi;
    sky[2] = a[2] * kPi * 0.4886025119029199 / kPi;
    sigma += sky * sky.transpose();
    const std::vector<double> p = projection_from_sh9(basis);
    const Eigen::MatrixXd pm =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor>>(p.data(), k, 9);
    Eigen::MatrixXd c = pm * sigma * pm.transpose();
    c += Eigen::MatrixXd::Identity(k, k) * (1e-12 * c.trace());
    const Eigen::MatrixXd r = (sigma * pm.transpose()) * c.inverse(); // 9 x K
    for (int j = 0; j < 9; ++j)
        for (int i = 0; i < k; ++i)
            out[size_t(j) * size_t(k) + size_t(i)] = r(j, i);
    return out;
}

} // namespace hemi::math
