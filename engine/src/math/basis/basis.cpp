// The single table of hemispherical bases and the quadrature that derives their projections from SH9.
#include <hemi/math/basis.h>
#include <hemi/math/quadrature.h>
#include <hemi/math/sh.h>

#include <Eigen/Dense>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::math
{
namespace basis_detail
{
#include "hemi_bases_decl.inc"
}

std::span<const BasisDesc> bases()
{
    // The generated list (cmake/HemiBases.cmake), in id order; each entry's id must be its index.
    static const std::vector<BasisDesc> table = []
    {
        const BasisDesc* entries[] = {
#include "hemi_bases_table.inc"
        };
        static_assert(sizeof(entries) / sizeof(entries[0]) == HEMI_BASIS_COUNT);
        std::vector<BasisDesc> t;
        for (const BasisDesc* e : entries)
        {
            if (e->id != int(t.size()))
                throw std::logic_error("hemi: basis '" + std::string(e->name) + "' has id " +
                                       std::to_string(e->id) + " at position " + std::to_string(t.size()) +
                                       " of the table");
            t.push_back(*e);
        }
        return t;
    }();
    return table;
}

const BasisDesc& basis(std::string_view name)
{
    std::string known;
    for (const BasisDesc& b : bases())
    {
        if (b.name == name)
            return b;
        known += (known.empty() ? "" : ", ") + std::string(b.name);
    }
    throw std::invalid_argument("hemi: unknown basis '" + std::string(name) + "' (known: " + known + ")");
}

const BasisDesc& vertex_irradiance_basis()
{
    static const BasisDesc prt{HEMI_BASIS_VERTEX_IRRADIANCE, "prt", 1, false,
                               [](const glm::vec3&, float* out) { out[0] = 1.0f; }};
    return prt;
}

const BasisDesc& technique(std::string_view name)
{
    if (name == "gs")
        return basis("sh9");
    if (name == "prt")
        return vertex_irradiance_basis();
    for (const BasisDesc& b : bases())
        if (b.name == name)
            return b;
    std::string known = "gs, prt";
    for (const BasisDesc& b : bases())
        known += ", " + std::string(b.name);
    throw std::invalid_argument("hemi: unknown technique '" + std::string(name) + "' (known: " + known + ")");
}

std::vector<HemisphereSample> hemisphere_quadrature(int steps)
{
    if (steps < 2)
        throw std::invalid_argument("hemi: hemisphere quadrature needs at least 2 steps");
    // z = t^2, dz = 2t dt: the sqrt(z) factors of the shifted bases become polynomial in t.
    const QuadratureRule rule = gauss_legendre(steps, 0.0, 1.0);
    const int phi_steps = 2 * steps;
    const double dphi = 2.0 * M_PI / phi_steps;
    std::vector<HemisphereSample> samples;
    samples.reserve(size_t(steps) * phi_steps);
    for (int i = 0; i < steps; ++i)
    {
        double t = rule.x[i], z = t * t, s = std::sqrt(std::max(0.0, 1.0 - z * z));
        double w = rule.w[i] * 2.0 * t * dphi;
        for (int p = 0; p < phi_steps; ++p)
        {
            double phi = (p + 0.5) * dphi;
            samples.push_back({glm::dvec3(s * std::cos(phi), s * std::sin(phi), z), w});
        }
    }
    return samples;
}

double integrate_hemisphere(const std::function<double(const glm::dvec3&)>& f, int steps)
{
    double sum = 0.0;
    for (const HemisphereSample& s : hemisphere_quadrature(steps))
        sum += s.weight * f(s.n);
    return sum;
}

namespace
{
// One pass over the quadrature nodes, accumulating G and B together.
void gram_and_cross(const BasisDesc& b, Eigen::MatrixXd& g, Eigen::MatrixXd& c)
{
    const int k = b.size;
    g = Eigen::MatrixXd::Zero(k, k);
    c = Eigen::MatrixXd::Zero(k, 9);
    float v[HEMI_BASIS_MAX_SIZE];
    for (const HemisphereSample& q : hemisphere_quadrature(96))
    {
        glm::vec3 n(q.n);
        b.eval(n, v);
        Sh9 y = sh9_eval(n);
        for (int a = 0; a < k; ++a)
        {
            for (int e = 0; e < k; ++e)
                g(a, e) += q.weight * double(v[a]) * v[e];
            for (int j = 0; j < 9; ++j)
                c(a, j) += q.weight * double(v[a]) * y[j];
        }
    }
}
} // namespace

std::vector<double> gram_matrix(const BasisDesc& b)
{
    Eigen::MatrixXd g, c;
    gram_and_cross(b, g, c);
    std::vector<double> out(size_t(b.size) * b.size);
    for (int i = 0; i < b.size; ++i)
        for (int k = 0; k < b.size; ++k)
            out[size_t(i) * b.size + k] = g(i, k);
    return out;
}

std::vector<double> projection_from_sh9(const BasisDesc& b)
{
    Eigen::MatrixXd g, c;
    gram_and_cross(b, g, c);
    Eigen::MatrixXd p = g.ldlt().solve(c);
    std::vector<double> out(size_t(b.size) * 9);
    for (int i = 0; i < b.size; ++i)
        for (int j = 0; j < 9; ++j)
            out[size_t(i) * 9 + j] = p(i, j);
    return out;
}

double projection_error_of_sh9_function(const BasisDesc& b, int j)
{
    if (j < 0 || j >= 9)
        throw std::invalid_argument("hemi: SH9 index " + std::to_string(j) + " out of range");
    std::vector<double> p = projection_from_sh9(b);
    return integrate_hemisphere(
        [&](const glm::dvec3& n)
        {
            float v[HEMI_BASIS_MAX_SIZE];
            b.eval(glm::vec3(n), v);
            double fit = 0.0;
            for (int i = 0; i < b.size; ++i)
                fit += p[size_t(i) * 9 + j] * v[i];
            double d = double(sh9_eval(glm::vec3(n))[j]) - fit;
            return d * d;
        },
        96);
}

} // namespace hemi::math
