#include <hemi/bake/transfer_fold.h>

#include <hemi/math/sh.h>

#include <glm/geometric.hpp>

#include <stdexcept>
#include <string>

namespace hemi::bake
{

glm::mat3 object_to_tangent(const glm::vec3& n, const glm::vec3& t, float w)
{
    glm::vec3 b = glm::cross(n, t) * (w < 0.0f ? -1.0f : 1.0f);
    // glm is column-major: the matrix whose rows are T, B, N is the transpose of mat3(T, B, N).
    return glm::transpose(glm::mat3(t, b, n));
}

std::vector<float> unshadowed_transfer(const glm::mat3& object_to_tangent, int lighting_order)
{
    if (lighting_order < 3 || lighting_order > math::kMaxShOrder)
        throw std::invalid_argument("hemi: lighting order " + std::to_string(lighting_order) +
                                    " is not in [3, " + std::to_string(math::kMaxShOrder) + "]");
    // Lighting f(w) in object space; in tangent space the same radiance is g(w_t) = f(R^T w_t), i.e. f
    // rotated by R: its coefficients are D(R) l (math::ShRotation's contract). Bands 0-2 of D l are rows
    // 0-8 of the block-diagonal D.
    const int L = lighting_order * lighting_order;
    math::ShRotation rotation(lighting_order, object_to_tangent);
    std::vector<float> rm(size_t(9) * L, 0.0f);
    for (int l = 0; l < 3; ++l)
        for (int m = -l; m <= l; ++m)
            for (int n = -l; n <= l; ++n)
                rm[size_t(math::sh_index(l, m)) * L + math::sh_index(l, n)] = rotation.element(l, m, n);
    return rm;
}

TransferFold::TransferFold(const math::BasisDesc& basis)
    : k_(basis.size), pc_(math::projection_from_sh9(basis))
{
    for (int i = 0; i < k_; ++i)
        for (int j = 0; j < 9; ++j)
            pc_[size_t(i) * 9 + j] *= math::clamped_cosine_factor(j == 0 ? 0 : (j < 4 ? 1 : 2));
}

std::vector<float> TransferFold::apply(std::span<const float> rm, int l) const
{
    if (l <= 0 || rm.size() != size_t(9) * l)
        throw std::invalid_argument("hemi: fold_transfer expects a 9 x " + std::to_string(l) +
                                    " matrix, got " + std::to_string(rm.size()) + " values");
    std::vector<float> t(size_t(k_) * l, 0.0f);
    for (int i = 0; i < k_; ++i)
        for (int j = 0; j < 9; ++j)
        {
            const double pc = pc_[size_t(i) * 9 + j];
            if (pc == 0.0)
                continue;
            for (int c = 0; c < l; ++c)
                t[size_t(i) * l + c] += float(pc * rm[size_t(j) * l + c]);
        }
    return t;
}

std::vector<float> fold_transfer(std::span<const float> rm, int l, const math::BasisDesc& basis)
{
    return TransferFold(basis).apply(rm, l);
}

} // namespace hemi::bake
