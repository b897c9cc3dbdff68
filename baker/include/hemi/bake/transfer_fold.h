#pragma once
// Folding a vertex's transfer into the matrix the runtime multiplies (Sloan 2006, Eq. 3.1):
//   T = P_basis * C * R * M
// M maps distant lighting (order n, L = n^2 SH coefficients, object space) to incident radiance in SH9 at
// the vertex (object space); R rotates SH9 from object space into the vertex's tangent frame; C is the
// clamped-cosine convolution (A_l); P_basis projects SH9 irradiance into the pixel basis (K x 9, identity
// for the gold standard "sh9"). The product is K x L, the T_v of render::TransferMatrices.
//
// For unshadowed diffuse transfer M is the identity restricted to bands 0-2, so R * M is the first 9 rows
// of the order-n rotation itself: unshadowed_transfer() builds it without any ray casting.

#include <hemi/math/basis.h>

#include <glm/mat3x3.hpp>

#include <span>
#include <vector>

namespace hemi::bake
{

// The rotation taking object-space directions into the tangent frame (rows T, B, N). T and N must be unit
// and orthogonal; w is the glTF handedness (B = cross(N, T) * w).
glm::mat3 object_to_tangent(const glm::vec3& normal, const glm::vec3& tangent, float w);

// R * M for unshadowed transfer: 9 x L row-major, L = lighting_order^2 (lighting_order in [3, 10]).
std::vector<float> unshadowed_transfer(const glm::mat3& object_to_tangent, int lighting_order);

// P_basis * C for one basis, computed once (the projection is a quadrature) and applied per vertex.
class TransferFold
{
  public:
    explicit TransferFold(const math::BasisDesc& basis);
    // T = P_basis * C * rm for `rm` = R * M (9 x L row-major, already in the tangent frame). K x L row-major.
    // Throws std::invalid_argument when rm.size() is not 9 * L.
    std::vector<float> apply(std::span<const float> rm, int l) const;
    int k() const { return k_; }

  private:
    int k_;
    std::vector<double> pc_; // K x 9
};

// TransferFold(basis).apply(rm, l): for one-off use; bakes keep a TransferFold per basis.
std::vector<float> fold_transfer(std::span<const float> rm, int l, const math::BasisDesc& basis);

} // namespace hemi::bake
