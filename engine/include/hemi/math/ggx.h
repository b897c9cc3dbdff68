#pragma once
// The glossy layer of hemi's directional-lightmap specular (docs/specular.md): the GGX microfacet BRDF an
// engine's PBR material has, and what the GLSL library (hemi/lib/specular.glsl) needs from the bases to
// estimate specular light from a lightmap's coefficients.
//
// The BRDF, written as f_r cos(theta_l), the factor that multiplies a light's irradiance on a surface facing
// it (directions unit, pointing away from the surface, alpha = roughness^2, glTF's perceptual roughness):
//   f_r (n.l) = D(n.h) V(n.l, n.v) F(v.h) (n.l),
//   D = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2)                                (Trowbridge-Reitz, GGX)
//   V = 0.5 / ((n.l) sqrt((n.v)^2 (1 - alpha^2) + alpha^2) + (n.v) sqrt((n.l)^2 (1 - alpha^2) + alpha^2))
//       (Smith's height-correlated masking-shadowing G2 / (4 (n.l) (n.v)), Heitz 2014)
//   F = f0 + (1 - f0) (1 - v.h)^5                                                     (Schlick)
// 0 where n.l <= 0 or n.v <= 0. The GLSL twin is hemi_ggx (a GPU test holds them equal).
//
// Based on: B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet Models for Refraction through Rough
// Surfaces", EGSR 2007; E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs",
// JCGT 2014; B. Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course (the split sum).

#include <hemi/math/basis.h>

#include <glm/vec3.hpp>

#include <utility>
#include <vector>

namespace hemi::math
{

// Roughness is clamped to [kGgxMinRoughness, 1] (alpha^2 >= 8.1e-7 keeps D finite in float): the same clamp
// as the GLSL.
constexpr double kGgxMinRoughness = 0.03;

// f_r (n.l) of the BRDF above, per channel of f0.
glm::dvec3 ggx_eval_cos(const glm::dvec3& n, const glm::dvec3& l, const glm::dvec3& v, double roughness,
                        const glm::dvec3& f0);

// A direction l reflected about a half vector h drawn from D(h) (n.h) (Walter 2007): u0, u1 uniform in
// [0, 1). `pdf` is l's density in solid angle, D (n.h) / (4 v.h); 0 (and any l) where l falls below n.
glm::dvec3 ggx_sample(const glm::dvec3& n, const glm::dvec3& v, double roughness, double u0, double u1,
                      double& pdf);

// The split sum's directional albedo, the integral of f_r (n.l) over the hemisphere for n.v = cos_v and a
// white environment, as f0 * a + b (Karis 2013): {a, b} by quadrature (Gauss-Legendre, converged to 2e-3).
// What the GLSL's hemi_ggx_albedo approximates in closed form.
std::pair<double, double> ggx_albedo(double cos_v, double roughness);

// The closed form the GLSL evaluates (hemi_ggx_albedo): {a, b} as polynomials of total degree
// kGgxAlbedoFitDegree in s = sqrt(n.v) and the roughness, least-squares fitted to ggx_albedo on a 24 x 24
// grid over s in [sqrt(0.05), 1] (n.v below 0.05 is clamped there) and roughness in [0.03, 1]. Coefficients
// in the order i = 0..degree (power of s), j = 0..degree - i (power of the roughness).
constexpr int kGgxAlbedoFitDegree = 6;
std::vector<std::pair<double, double>> ggx_albedo_fit();

// The SH9 irradiance coefficients (A_l y_lm, in the basis's tangent frame) that `basis`'s K coefficients
// most likely came from: the 9 x K linear least-squares estimator (row-major) E[e c^T] E[c c^T]^-1 over a
// prior of lightings a lightmap holds (suns over the hemisphere, each of irradiance 1, and a uniform sky
// over it, each projected onto the basis as the bake projects: math::projection_from_sh9). For SH9 the
// identity. The GLSL library's tables (hemi/lib/specular_generated.glsl) are these.
std::vector<double> sh9_from_basis(const BasisDesc& basis);

} // namespace hemi::math
