#include <hemi/math/quadrature.h>

#include <cmath>
#include <stdexcept>

namespace hemi::math
{

QuadratureRule gauss_legendre(int n, double a, double b)
{
    if (n < 1)
        throw std::invalid_argument("hemi: Gauss-Legendre needs at least one node");
    QuadratureRule r;
    r.x.resize(n);
    r.w.resize(n);
    const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
    for (int i = 0; i < (n + 1) / 2; ++i)
    {
        // Newton on P_n from Tricomi's initial guess (Numerical Recipes' gauleg).
        double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), pp = 1.0;
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
        const double w = 2.0 / ((1.0 - z * z) * pp * pp);
        r.x[i] = mid - half * z;
        r.x[n - 1 - i] = mid + half * z;
        r.w[i] = r.w[n - 1 - i] = half * w;
    }
    return r;
}

} // namespace hemi::math
