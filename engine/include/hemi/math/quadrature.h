#pragma once
// Gauss-Legendre quadrature, the one rule behind hemi's spherical and hemispherical integrals.

#include <vector>

namespace hemi::math
{

struct QuadratureRule
{
    std::vector<double> x; // nodes, ascending
    std::vector<double> w; // weights
};

// n-point Gauss-Legendre on [a, b]: exact for polynomials of degree < 2n. Throws for n < 1.
QuadratureRule gauss_legendre(int n, double a = -1.0, double b = 1.0);

} // namespace hemi::math
