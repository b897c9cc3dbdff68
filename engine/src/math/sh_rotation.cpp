// SH rotation by recursion over bands: J. Ivanic, K. Ruedenberg, "Rotation Matrices for Real Spherical
// Harmonics. Direct Determination by Recursion", J. Phys. Chem. 100 (1996), with the corrections of
// J. Phys. Chem. A 102 (1998). The band-1 block is the 3x3 rotation in the (y, z, x) order of
// y1,-1, y1,0, y1,1, with the Condon-Shortley signs folded in (S R S, S = diag(-1, 1, -1)); the recursion
// is unchanged by that conjugation, so every band comes out in hemi's convention.
#include <hemi/math/sh.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::math
{
namespace
{

struct Bands
{
    const float* blocks;
    float at(int l, int m, int n) const
    {
        return blocks[ShRotation::block_offset(l) + (m + l) * (2 * l + 1) + (n + l)];
    }
};

// P of Ivanic-Ruedenberg Table 2: built from the band-1 block R and band l-1.
double p_term(const Bands& b, int i, int l, int a, int c)
{
    if (c == l)
        return b.at(1, i, 1) * b.at(l - 1, a, l - 1) - b.at(1, i, -1) * b.at(l - 1, a, -l + 1);
    if (c == -l)
        return b.at(1, i, 1) * b.at(l - 1, a, -l + 1) + b.at(1, i, -1) * b.at(l - 1, a, l - 1);
    return b.at(1, i, 0) * b.at(l - 1, a, c);
}

} // namespace

ShRotation::ShRotation(int order, const glm::mat3& r) : order_(order)
{
    if (order < 1 || order > kMaxShOrder)
        throw std::invalid_argument("hemi: ShRotation order " + std::to_string(order) + " is not in [1, " +
                                    std::to_string(kMaxShOrder) + "]");
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(r[c][k]))
                throw std::invalid_argument("hemi: ShRotation: the rotation matrix is not finite");
    blocks_[0] = 1.0f;
    if (order == 1)
        return;

    // Band 1. glm is column-major: r[col][row]. Index m = -1, 0, 1 <-> axis y, z, x.
    const int axis[3] = {1, 2, 0};
    const float sign[3] = {-1.0f, 1.0f, -1.0f};
    for (int m = -1; m <= 1; ++m)
        for (int n = -1; n <= 1; ++n)
            blocks_[block_offset(1) + (m + 1) * 3 + (n + 1)] =
                sign[m + 1] * sign[n + 1] * r[axis[n + 1]][axis[m + 1]];

    Bands b{blocks_.data()};
    for (int l = 2; l < order; ++l)
    {
        for (int m = -l; m <= l; ++m)
            for (int n = -l; n <= l; ++n)
            {
                const int am = std::abs(m);
                const double d = (m == 0) ? 1.0 : 0.0;
                const double denom =
                    (std::abs(n) == l) ? double(2 * l) * (2 * l - 1) : double(l + n) * (l - n);
                const double u = std::sqrt(double(l + m) * (l - m) / denom);
                const double v =
                    0.5 * std::sqrt((1.0 + d) * (l + am - 1.0) * (l + am) / denom) * (1.0 - 2.0 * d);
                const double w = -0.5 * std::sqrt(double(l - am - 1) * (l - am) / denom) * (1.0 - d);
                double value = 0.0;
                if (u != 0.0)
                    value += u * p_term(b, 0, l, m, n);
                if (v != 0.0)
                {
                    double vv;
                    if (m == 0)
                        vv = p_term(b, 1, l, 1, n) + p_term(b, -1, l, -1, n);
                    else if (m > 0)
                    {
                        double d1 = (m == 1) ? 1.0 : 0.0;
                        vv = p_term(b, 1, l, m - 1, n) * std::sqrt(1.0 + d1) -
                             p_term(b, -1, l, -m + 1, n) * (1.0 - d1);
                    }
                    else
                    {
                        double d1 = (m == -1) ? 1.0 : 0.0;
                        vv = p_term(b, 1, l, m + 1, n) * (1.0 - d1) +
                             p_term(b, -1, l, -m - 1, n) * std::sqrt(1.0 + d1);
                    }
                    value += v * vv;
                }
                if (w != 0.0)
                {
                    double ww = (m > 0) ? p_term(b, 1, l, m + 1, n) + p_term(b, -1, l, -m - 1, n)
                                        : p_term(b, 1, l, m - 1, n) - p_term(b, -1, l, -m + 1, n);
                    value += w * ww;
                }
                blocks_[block_offset(l) + (m + l) * (2 * l + 1) + (n + l)] = float(value);
            }
    }
}

float ShRotation::element(int l, int m, int n) const
{
    if (l < 0 || l >= order_ || std::abs(m) > l || std::abs(n) > l)
        throw std::out_of_range("hemi: ShRotation::element out of range");
    return blocks_[block_offset(l) + (m + l) * (2 * l + 1) + (n + l)];
}

template <typename T>
static void apply_blocks(int order, const float* blocks, std::span<const T> in, std::span<T> out)
{
    const size_t n = size_t(order) * order;
    if (in.size() != n || out.size() != n)
        throw std::invalid_argument("hemi: ShRotation::apply expects " + std::to_string(n) + " coefficients");
    for (int l = 0; l < order; ++l)
    {
        const int size = 2 * l + 1, base = l * l;
        const float* block = blocks + ShRotation::block_offset(l);
        for (int i = 0; i < size; ++i)
        {
            T sum = T(0);
            for (int j = 0; j < size; ++j)
                sum += block[i * size + j] * in[base + j];
            out[base + i] = sum;
        }
    }
}

void ShRotation::apply(std::span<const glm::vec3> in, std::span<glm::vec3> out) const
{
    apply_blocks(order_, blocks_.data(), in, out);
}

void ShRotation::apply(std::span<const float> in, std::span<float> out) const
{
    apply_blocks(order_, blocks_.data(), in, out);
}

} // namespace hemi::math
