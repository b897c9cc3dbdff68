#pragma once
// The separable basis of Sloan 2006, Sec. 3.2: SVD of the 1024 x 9 matrix A whose row i is SH9 evaluated at
// normal i of a 32 x 32 grid on the unit square, mapped to the hemisphere with the Shirley-Chiu concentric
// map lifted to the hemisphere by the equal-area map z = 1 - r^2 (every cell covers 2pi/1024 sr, so the
// plain SVD is the hemispherical least-squares factorisation). Optionally the clamped-cosine convolution C
// (diag of A_l) is folded in, A' = A C, as the paper suggests; hemi's "sep4" basis is that variant with
// M = 4.
//
// With A = U S V^T, the truncated basis functions are the columns of U_M; they extend to any normal as
// u_m(n) = sum_j y_j(n) W_jm with W = (C) V_M S_M^-1, exact at the grid normals. Based on: P. Shirley,
// K. Chiu, "A Low Distortion Map Between Disk and Square", JGT 1997.

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <vector>

namespace hemi::math
{

constexpr int kSeparableGrid = 32;

// The concentric map of (a, b) in [-1, 1]^2 onto the unit disk, lifted to the hemisphere (z = 1 - r^2).
glm::vec3 concentric_hemisphere(glm::vec2 square);

struct SeparableSvd
{
    bool convolution_folded = false;
    std::array<double, 9> singular_values{}; // descending
    std::array<double, 81> v{};              // V, 9 x 9 row-major (column m = right singular vector m)
    // W for M terms, 9 x M row-major: u_m(n) = sum_j y_j(n) W[j * M + m].
    std::vector<double> weights(int m) const;
};

// Deterministic; cheap (a 1024 x 9 SVD with Eigen).
SeparableSvd separable_svd(bool fold_convolution);
// The sep4 weights (folded, M = 4), computed once. Row-major 9 x 4.
const std::array<float, 36>& sep4_weights();

// Sloan's runtime lookup: the M = 4 functions resampled into a size x size RGBA float texture indexed by
// the orthographic projection of the normal, texel (i, j) at n.xy = ((i + 0.5) / size * 2 - 1, ...), rows
// from n.y = -1 upward; outside the unit disk the rim normal (n.xy normalised, z = 0) is used.
std::vector<float> separable_texture(int size = 64);

} // namespace hemi::math
