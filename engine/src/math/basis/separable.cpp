// Sloan 2006 Sec. 3.2: the separable (SVD) basis; see hemi/math/separable_basis.h.
#include <hemi/math/basis.h>
#include <hemi/math/separable_basis.h>
#include <hemi/math/sh.h>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

namespace hemi::math
{

glm::vec3 concentric_hemisphere(glm::vec2 p)
{
    // Shirley & Chiu 1997: square -> disk, area-preserving.
    float r, phi;
    const float a = p.x, b = p.y;
    if (a == 0.0f && b == 0.0f)
        return glm::vec3(0.0f, 0.0f, 1.0f);
    if (std::abs(a) > std::abs(b))
    {
        r = a;
        phi = float(M_PI / 4) * (b / a);
    }
    else
    {
        r = b;
        phi = float(M_PI / 2) - float(M_PI / 4) * (a / b);
    }
    // Disk -> hemisphere, equal-area: z = 1 - r^2, |xy| = r sqrt(2 - r^2).
    const float s = r * std::sqrt(std::max(0.0f, 2.0f - r * r));
    return glm::vec3(s * std::cos(phi), s * std::sin(phi), 1.0f - r * r);
}

std::vector<double> SeparableSvd::weights(int m) const
{
    std::vector<double> w(size_t(9) * m);
    for (int j = 0; j < 9; ++j)
    {
        int l = j == 0 ? 0 : (j < 4 ? 1 : 2);
        double c = convolution_folded ? clamped_cosine_factor(l) : 1.0;
        for (int k = 0; k < m; ++k)
            w[size_t(j) * m + k] = c * v[size_t(j) * 9 + k] / singular_values[k];
    }
    return w;
}

SeparableSvd separable_svd(bool fold_convolution)
{
    const int n = kSeparableGrid * kSeparableGrid;
    Eigen::MatrixXd a(n, 9);
    for (int i = 0; i < kSeparableGrid; ++i)
        for (int k = 0; k < kSeparableGrid; ++k)
        {
            glm::vec2 sq((k + 0.5f) / kSeparableGrid * 2.0f - 1.0f,
                         (i + 0.5f) / kSeparableGrid * 2.0f - 1.0f);
            Sh9 y = sh9_eval(concentric_hemisphere(sq));
            for (int j = 0; j < 9; ++j)
            {
                int l = j == 0 ? 0 : (j < 4 ? 1 : 2);
                a(i * kSeparableGrid + k, j) =
                    double(y[j]) * (fold_convolution ? clamped_cosine_factor(l) : 1.0);
            }
        }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    SeparableSvd out;
    out.convolution_folded = fold_convolution;
    Eigen::MatrixXd v = svd.matrixV();
    for (int k = 0; k < 9; ++k)
    {
        out.singular_values[k] = svd.singularValues()(k);
        // Fix each vector's sign (SVD leaves it free) so results are reproducible: largest entry positive.
        int big = 0;
        for (int j = 1; j < 9; ++j)
            if (std::abs(v(j, k)) > std::abs(v(big, k)))
                big = j;
        double sign = v(big, k) < 0 ? -1.0 : 1.0;
        for (int j = 0; j < 9; ++j)
            out.v[size_t(j) * 9 + k] = sign * v(j, k);
    }
    return out;
}

const std::array<float, 36>& sep4_weights()
{
    static const std::array<float, 36> weights = []
    {
        std::vector<double> w = separable_svd(true).weights(4);
        std::array<float, 36> f{};
        for (int i = 0; i < 36; ++i)
            f[i] = float(w[i]);
        return f;
    }();
    return weights;
}

std::vector<float> separable_texture(int size)
{
    std::vector<float> tex(size_t(size) * size * 4);
    float b[HEMI_BASIS_MAX_SIZE];
    for (int i = 0; i < size; ++i)
        for (int k = 0; k < size; ++k)
        {
            glm::vec2 xy((k + 0.5f) / size * 2.0f - 1.0f, (i + 0.5f) / size * 2.0f - 1.0f);
            float r2 = xy.x * xy.x + xy.y * xy.y;
            glm::vec3 nrm =
                r2 < 1.0f ? glm::vec3(xy, std::sqrt(1.0f - r2)) : glm::vec3(xy / std::sqrt(r2), 0.0f);
            basis("sep4").eval(nrm, b);
            std::copy(b, b + 4, tex.begin() + (size_t(i) * size + k) * 4);
        }
    return tex;
}

namespace basis_detail
{
static void eval_sep4(const glm::vec3& n, float* out)
{
    const std::array<float, 36>& w = sep4_weights();
    Sh9 y = sh9_eval(n);
    for (int m = 0; m < 4; ++m)
    {
        float s = 0.0f;
        for (int j = 0; j < 9; ++j)
            s += y[j] * w[j * 4 + m];
        out[m] = s;
    }
}
extern const BasisDesc k_sep4{HEMI_BASIS_SEP4, "sep4", HEMI_BASIS_SIZE_SEP4, false, eval_sep4};
} // namespace basis_detail

} // namespace hemi::math
