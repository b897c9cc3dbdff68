#include <hemi/math/brdf.h>
#include <hemi/math/quadrature.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hemi::math
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

void check_exponent(double exponent)
{
    if (!std::isfinite(exponent) || !(exponent > 0.0) || exponent > 1e6)
        throw std::invalid_argument("the exponent must be in (0, 1e6], got " + std::to_string(exponent));
}
void check_size(uint32_t size)
{
    if (size < 2 || size > 8192)
        throw std::invalid_argument("a BRDF table's size must be in [2, 8192], got " + std::to_string(size));
}
double clamp01(double c)
{
    return std::clamp(c, 0.0, 1.0);
}

BrdfTable make_table(uint32_t size, std::vector<std::string> names, std::string axis_u, std::string axis_v)
{
    BrdfTable t;
    t.size = size;
    t.channels = uint32_t(names.size());
    t.channel_names = std::move(names);
    t.axis_u = std::move(axis_u);
    t.axis_v = std::move(axis_v);
    t.values.assign(size_t(size) * size * t.channels, 0.0f);
    return t;
}
using Axis = BrdfTable::Axis;
// The value an axis holds at sample i of size (the inverse of axis_coord).
double axis_value(Axis axis, uint32_t i, uint32_t size)
{
    const double s = double(i) / double(size - 1);
    switch (axis)
    {
    case Axis::Cosine:
        return s;
    case Axis::SqrtOneMinus:
        return 1.0 - s * s;
    case Axis::Angle:
        return std::cos(kPi * s);
    }
    return s;
}
double axis_coord(Axis axis, double value)
{
    switch (axis)
    {
    case Axis::Cosine:
        return value;
    case Axis::SqrtOneMinus:
        return std::sqrt(std::max(0.0, 1.0 - value));
    case Axis::Angle:
        return std::acos(std::clamp(value, -1.0, 1.0)) / kPi;
    }
    return value;
}
} // namespace

double fresnel_dielectric(double cos_theta, double ior)
{
    const double c = clamp01(cos_theta);
    const double g = std::sqrt(ior * ior - 1.0 + c * c);
    const double a = (g - c) / (g + c);
    const double b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

FacetDistribution parse_facet_distribution(const std::string& name)
{
    if (name == "beckmann")
        return FacetDistribution::Beckmann;
    if (name == "gaussian")
        return FacetDistribution::Gaussian;
    throw std::invalid_argument("unknown facet distribution '" + name + "' (beckmann or gaussian)");
}
const char* facet_distribution_name(FacetDistribution d)
{
    return d == FacetDistribution::Beckmann ? "beckmann" : "gaussian";
}

TorranceSparrow::TorranceSparrow(FacetDistribution distribution, double roughness, double ior)
    : distribution_(distribution), m_(roughness), ior_(ior)
{
    if (!std::isfinite(roughness) || !(roughness > 0.0))
        throw std::invalid_argument("the roughness must be a finite number > 0, got " +
                                    std::to_string(roughness));
    if (roughness < 1e-3 || roughness > 10.0)
        throw std::invalid_argument(
            "the roughness must be in [0.001, 10] (a smoother surface is a mirror), got " +
            std::to_string(roughness));
    if (!std::isfinite(ior) || !(ior > 1.0))
        throw std::invalid_argument("the index of refraction must be a finite number > 1, got " +
                                    std::to_string(ior));
    if (distribution_ == FacetDistribution::Gaussian)
    {
        // c such that 2 pi c * integral_0^{pi/2} exp(-(d/m)^2) cos d sin d dd = pi / 4; the peak is resolved
        // by a rule of its own over [0, min(pi/2, 8m)].
        const double split = std::min(kPi / 2.0, 8.0 * m_);
        double integral = 0.0;
        for (auto [a, b] : {std::pair{0.0, split}, std::pair{split, kPi / 2.0}})
        {
            if (b <= a)
                continue;
            const QuadratureRule rule = gauss_legendre(128, a, b);
            for (size_t i = 0; i < rule.x.size(); ++i)
            {
                const double d = rule.x[i];
                integral += rule.w[i] * std::exp(-(d / m_) * (d / m_)) * std::cos(d) * std::sin(d);
            }
        }
        gaussian_c_ = (kPi / 4.0) / (2.0 * kPi * integral);
    }
}

double TorranceSparrow::distribution_term(double cos_delta) const
{
    if (!(cos_delta > 0.0))
        return 0.0;
    const double c = std::min(cos_delta, 1.0);
    if (distribution_ == FacetDistribution::Beckmann)
    {
        const double c2 = c * c;
        const double tan2 = (1.0 - c2) / c2;
        if (tan2 > 700.0 * m_ * m_)
            return 0.0; // exp underflows long before c^4 does
        return std::exp(-tan2 / (m_ * m_)) / (4.0 * m_ * m_ * c2 * c2);
    }
    const double d = std::acos(c);
    return gaussian_c_ * std::exp(-(d / m_) * (d / m_));
}

double TorranceSparrow::smith_g1_over_cos(double c) const
{
    c = clamp01(c);
    const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
    if (s < 1e-12)
        return 1.0;
    // G1 = 2 / (1 + erf(a) + exp(-a^2) / (a sqrt(pi))) = 2 a sqrt(pi) / (a sqrt(pi) (1 + erf a) + exp(-a^2)),
    // and a / c = 1 / (m s).
    const double a = c / (m_ * s);
    const double sqrt_pi = std::sqrt(kPi);
    return 2.0 * sqrt_pi / (m_ * s) / (a * sqrt_pi * (1.0 + std::erf(a)) + std::exp(-a * a));
}

double TorranceSparrow::smith_g1(double c) const
{
    return clamp01(c) * smith_g1_over_cos(c);
}

double TorranceSparrow::factor_g(double cos_alpha, double cos_beta) const
{
    return smith_g1(cos_alpha) * smith_g1_over_cos(cos_beta) / kPi;
}

double TorranceSparrow::eval_cos(const glm::dvec3& n, const glm::dvec3& l, const glm::dvec3& v) const
{
    const double ca = glm::dot(n, l), cb = glm::dot(n, v);
    if (!(ca > 0.0) || !(cb > 0.0))
        return 0.0;
    const glm::dvec3 sum = l + v;
    const double len = glm::length(sum);
    if (!(len > 1e-12))
        return 0.0;
    const glm::dvec3 h = sum / len;
    const double f = fresnel(glm::dot(l, h));
    const double g = smith_g1(ca) * smith_g1(cb);
    const double d = distribution_term(glm::dot(n, h));
    return f * g * d / (kPi * ca * cb) * ca;
}

double banks_diffuse(double a)
{
    return std::sqrt(std::max(0.0, 1.0 - a * a));
}

double banks_specular(double a, double b, double exponent)
{
    const double c = std::sqrt(std::max(0.0, 1.0 - a * a)) * std::sqrt(std::max(0.0, 1.0 - b * b)) - a * b;
    return c > 0.0 ? std::pow(c, exponent) : 0.0;
}

double banks_eval_cos(const glm::dvec3& n, const glm::dvec3& t, const glm::dvec3& l, const glm::dvec3& v,
                      double kd, double ks, double exponent)
{
    const double ca = glm::dot(n, l);
    if (!(ca > 0.0) || !(glm::dot(n, v) > 0.0))
        return 0.0;
    // The shading normal n' is l projected into the plane perpendicular to t; the reflected directions of l
    // off the fibre form a cone about t, and the one nearest v sets the highlight.
    const glm::dvec3 l_perp = l - glm::dot(l, t) * t;
    const glm::dvec3 v_perp = v - glm::dot(v, t) * t;
    const double lp = glm::length(l_perp), vp = glm::length(v_perp);
    const double diffuse = lp; // n'.l with n' = l_perp / |l_perp|
    double specular = 0.0;
    if (lp > 1e-12 && vp > 1e-12)
    {
        const glm::dvec3 r = -glm::dot(l, t) * t + lp * (v_perp / vp); // on the cone, towards v
        const double c = glm::dot(v, r);
        specular = c > 0.0 ? std::pow(c, exponent) : 0.0;
    }
    return ca * (kd * diffuse + ks * specular);
}

LobeModel parse_lobe_model(const std::string& name)
{
    if (name == "phong")
        return LobeModel::Phong;
    if (name == "blinn-phong")
        return LobeModel::BlinnPhong;
    if (name == "cosine-lobe")
        return LobeModel::CosineLobe;
    throw std::invalid_argument("unknown lobe model '" + name + "' (phong, blinn-phong or cosine-lobe)");
}
const char* lobe_model_name(LobeModel m)
{
    switch (m)
    {
    case LobeModel::Phong:
        return "phong";
    case LobeModel::BlinnPhong:
        return "blinn-phong";
    case LobeModel::CosineLobe:
        return "cosine-lobe";
    }
    return "?";
}

double lobe_table_value(LobeModel model, double exponent, double x, double y)
{
    x = clamp01(x);
    const double lobe = y > 0.0 ? std::pow(std::min(y, 1.0), exponent) : 0.0;
    switch (model)
    {
    case LobeModel::Phong:
        return (exponent + 1.0) / (2.0 * kPi) * lobe;
    case LobeModel::BlinnPhong:
        return x * (exponent + 8.0) / (8.0 * kPi) * lobe;
    case LobeModel::CosineLobe:
        return x * (exponent + 2.0) / (2.0 * kPi) * lobe;
    }
    return 0.0;
}

double lobe_eval_cos(LobeModel model, double exponent, const glm::dvec3& n, const glm::dvec3& l,
                     const glm::dvec3& v)
{
    const double x = glm::dot(n, l), nv = glm::dot(n, v);
    if (!(x > 0.0) || !(nv > 0.0))
        return 0.0;
    if (model == LobeModel::BlinnPhong)
    {
        const glm::dvec3 h = glm::normalize(l + v);
        return x * (exponent + 8.0) / (8.0 * kPi) * std::pow(std::max(0.0, glm::dot(n, h)), exponent);
    }
    const glm::dvec3 r = 2.0 * nv * n - v;
    const double lobe = std::pow(std::max(0.0, glm::dot(r, l)), exponent);
    return model == LobeModel::Phong ? (exponent + 1.0) / (2.0 * kPi) * lobe
                                     : x * (exponent + 2.0) / (2.0 * kPi) * lobe;
}

double BrdfTable::coord_u(double value) const
{
    return axis_coord(u_axis, value);
}
double BrdfTable::coord_v(double value) const
{
    return axis_coord(v_axis, value);
}

double BrdfTable::lookup(uint32_t channel, double u_value, double v_value) const
{
    const double pu = std::clamp(coord_u(u_value), 0.0, 1.0) * double(size - 1);
    const double pv = std::clamp(coord_v(v_value), 0.0, 1.0) * double(size - 1);
    const uint32_t i0 = std::min(uint32_t(pu), size - 2), j0 = std::min(uint32_t(pv), size - 2);
    const double fu = pu - i0, fv = pv - j0;
    auto at = [&](uint32_t i, uint32_t j)
    { return double(values[(size_t(j) * size + i) * channels + channel]); };
    return (1.0 - fv) * ((1.0 - fu) * at(i0, j0) + fu * at(i0 + 1, j0)) +
           fv * ((1.0 - fu) * at(i0, j0 + 1) + fu * at(i0 + 1, j0 + 1));
}

std::vector<BrdfTable> torrance_sparrow_tables(const TorranceSparrow& model, uint32_t size)
{
    check_size(size);
    BrdfTable fd = make_table(size, {"FD"}, "cos_theta", "sqrt(1-cos_delta)");
    fd.v_axis = Axis::SqrtOneMinus;
    BrdfTable g = make_table(size, {"G"}, "cos_alpha", "cos_beta");
    for (uint32_t j = 0; j < size; ++j)
        for (uint32_t i = 0; i < size; ++i)
        {
            const size_t k = size_t(j) * size + i;
            fd.values[k] =
                float(model.factor_fd(axis_value(fd.u_axis, i, size), axis_value(fd.v_axis, j, size)));
            g.values[k] = float(model.factor_g(axis_value(g.u_axis, i, size), axis_value(g.v_axis, j, size)));
        }
    return {std::move(fd), std::move(g)};
}

BrdfTable banks_table(double exponent, uint32_t size)
{
    check_exponent(exponent);
    check_size(size);
    BrdfTable t = make_table(size, {"diffuse", "specular"}, "acos(t.l)/pi", "acos(t.v)/pi");
    t.u_axis = t.v_axis = Axis::Angle;
    for (uint32_t j = 0; j < size; ++j)
        for (uint32_t i = 0; i < size; ++i)
        {
            const double a = axis_value(t.u_axis, i, size), b = axis_value(t.v_axis, j, size);
            const size_t k = (size_t(j) * size + i) * 2;
            t.values[k] = float(banks_diffuse(a));
            t.values[k + 1] = float(banks_specular(a, b, exponent));
        }
    return t;
}

BrdfTable lobe_table(LobeModel model, double exponent, uint32_t size)
{
    check_exponent(exponent);
    check_size(size);
    BrdfTable t = make_table(size, {"specular"}, "n.l",
                             model == LobeModel::BlinnPhong ? "sqrt(1-n.h)" : "sqrt(1-r_v.l)");
    t.v_axis = Axis::SqrtOneMinus;
    for (uint32_t j = 0; j < size; ++j)
        for (uint32_t i = 0; i < size; ++i)
            t.values[size_t(j) * size + i] = float(lobe_table_value(
                model, exponent, axis_value(t.u_axis, i, size), axis_value(t.v_axis, j, size)));
    return t;
}

} // namespace hemi::math
