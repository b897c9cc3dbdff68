#pragma once
// Hemispherical bases: each evaluates K functions at a unit normal in tangent space (z >= 0 is the
// hemisphere; functions are evaluated unclamped) and has a projection matrix from SH9 irradiance.
//
// One table holds every basis (engine/src/math/basis/*.cpp, one description each); techniques and tests
// loop over it. Projection matrices are the hemispherical least-squares fit, P = G^-1 B with
// G_ik = int_H b_i b_k and B_ij = int_H b_i y_j, computed by quadrature (exact for the polynomial bases;
// converged to < 1e-9 for the others), so sum_k (P s)_k b_k(n) is the best fit of sum_j s_j y_j(n) on
// the hemisphere.
//
// Based on: P.-P. Sloan, "Normal Mapping for Precomputed Radiance Transfer", I3D 2006 (HL2, SAL, Table 2);
// R. Habel, M. Wimmer, "Efficient Irradiance Normal Mapping", I3D 2010 (H-basis, T_h, Fig. 3);
// J. Koenderink, A. van Doorn, M. Stavridi, "Bidirectional Reflection Distribution Function Expressed in
// Terms of Surface Scattering Modes", ECCV 1996 (Zernike polynomials on the hemisphere).

#include "hemi/shared/bases.h"

#include <glm/vec3.hpp>

#include <array>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

namespace hemi::math
{

struct BasisDesc
{
    int id;                // HEMI_BASIS_*
    std::string_view name; // "hl2", "h6", ...
    int size;              // K
    bool orthonormal;      // orthonormal over the hemisphere
    // Writes the `size` functions at unit normal n (tangent space).
    void (*eval)(const glm::vec3& n, float* out);
};

// Every basis, in id order.
std::span<const BasisDesc> bases();
// Throws std::invalid_argument naming the unknown basis and listing the known ones.
const BasisDesc& basis(std::string_view name);

// Classic diffuse PRT without normal mapping (Sloan et al. 2002), the comparison of Sloan 2006: one
// constant function; its single coefficient is the irradiance at the vertex normal. Not a hemispherical
// basis of bases() (it represents nothing of the normal map), but the PRT material draws it like one.
const BasisDesc& vertex_irradiance_basis();

// The names pipelines use for PRT techniques: "gs" (the gold standard, = "sh9"), "prt" (classic PRT,
// vertex_irradiance_basis()) or any name of bases(). Throws std::invalid_argument listing the known names.
const BasisDesc& technique(std::string_view name);

struct HemisphereSample
{
    glm::dvec3 n;  // unit direction, z >= 0
    double weight; // solid angle it stands for; the weights sum to 2 pi
};
// The quadrature rule behind integrate_hemisphere: `steps` Gauss-Legendre nodes in t = sqrt(z) times
// 2 * `steps` uniform steps in phi.
std::vector<HemisphereSample> hemisphere_quadrature(int steps);

// Integrates f over the hemisphere z >= 0 (Gauss-Legendre in t with z = t^2, which also integrates the
// sqrt(z) behaviour of the shifted bases exactly, times a uniform rule in phi).
double integrate_hemisphere(const std::function<double(const glm::dvec3&)>& f, int steps = 64);

// K x 9 row-major least-squares projection from SH9 coefficients.
std::vector<double> projection_from_sh9(const BasisDesc& basis);
// K x K Gram matrix int_H b_i b_k.
std::vector<double> gram_matrix(const BasisDesc& basis);
// int_H (f - fit(f))^2 for f = the SH9 function y_j: Sloan 2006 Table 2's measure.
double projection_error_of_sh9_function(const BasisDesc& basis, int j);

} // namespace hemi::math
