#pragma once
// The reflection models of Heidrich & Seidel 1999 (§3) and their factorisation into 2D lookup tables.
//
// Every model is written as f_r cos(alpha), the factor that multiplies a light's irradiance on a surface
// facing it, as a function of cosines between the normal n, the light direction l, the view direction v (both
// pointing away from the surface), the halfway vector h = normalize(l + v) and, for Banks, the tangent t:
//   cos_alpha = n.l, cos_beta = n.v, cos_theta = l.h, cos_delta = n.h.
//
// Torrance-Sparrow (Eq. 1):  f_r = F(cos_theta) G(cos_alpha, cos_beta) D(cos_delta) / (pi cos_alpha
// cos_beta), factored as f_r cos_alpha = [F(cos_theta) D(cos_delta)] * [G(cos_alpha, cos_beta) / (pi
// cos_beta)].
//   D is normalised so that Eq. 1 is the microfacet BRDF: integral of D(h) (n.h) over the hemisphere = pi / 4
//   (Eq. 1's pi in place of the modern 4 in the denominator is absorbed into D, so nothing is lost or gained:
//   with F = G = 1 the model reflects what a mirror facet distribution does).
//   - Beckmann: D = exp(-tan^2 delta / m^2) / (4 m^2 cos^4 delta), m = roughness (RMS slope);
//   - Gaussian: D = c exp(-(delta / m)^2), m = roughness (radians), c from the normalisation (quadrature).
//   G is Smith's (uncorrelated masking and shadowing, G = G1(cos_alpha) G1(cos_beta)) for Gaussian slopes of
//   RMS m: G1(c) = 2 / (1 + erf(a) + exp(-a^2) / (a sqrt(pi))), a = c / (m sqrt(1 - c^2)); the same m serves
//   the Gaussian distribution. G1(c) / c stays finite as c -> 0 (2 sqrt(pi) / m): with Smith's term the
//   "singularity" at grazing view that the paper notes is a steep but finite ridge.
//   F is the exact unpolarised Fresnel reflectance of a dielectric of relative index ior > 1.
//
// Banks (Eq. 4), in Stalling's form (the reflected cone about the tangent): with a = t.l, b = t.v,
//   f_r cos_alpha = cos_alpha * (kd sqrt(1 - a^2) + ks max(0, sqrt(1 - a^2) sqrt(1 - b^2) - a b)^exponent);
//   the table holds the two terms in brackets without kd and ks, as functions of (a, b) in [-1, 1]^2.
//
// Single-table models (§3.1's last paragraph), specular lobes normalised so that ks = 1 reflects all of a
// lobe (exactly for Phong, the same normalisation as the prefiltered glossy environment maps, Eq. 9;
// Blinn-Phong's (e + 8) / 8 pi is the usual approximation, about 1 + 2/e at normal incidence), with x = n.l:
//   phong:        f_r cos_alpha = ((e + 1) / 2 pi) max(0, r_v.l)^e                 y = r_v.l (r_v = reflected
//   v) blinn-phong:  f_r cos_alpha = x ((e + 8) / 8 pi) max(0, n.h)^e                 y = n.h cosine-lobe:
//   f_r cos_alpha = x ((e + 2) / 2 pi) max(0, r_v.l)^e               y = r_v.l (a diffuse term kd x / pi is
//   added by the material, not stored).
//
// Table axes (io/brdf_table.h writes them with this description in the file's metadata): a table of N x N
// samples has sample i of an axis at coordinate i / (N - 1) (endpoints included; a shader samples it at
// (u (N - 1) + 0.5) / N). Axes that carry a narrow peak at cosine 1 (cos_delta, n.h, r_v.l) are stored
// against s = sqrt(1 - cosine), which spreads the peak over many samples (Beckmann is Gaussian in s); the
// others are linear in the cosine. Banks' axes are the angles acos(t.l) / pi and acos(t.v) / pi: its
// highlight is a ridge along acos(t.l) + acos(t.v) = pi (the specular term is max(0, -cos(A + B))^e), which
// the angles keep evenly sampled up to the tangent.

#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hemi::math
{

// Exact Fresnel reflectance of unpolarised light for the cosine c in [0, 1] of the angle of incidence, from
// index 1 into relative index ior > 1 (Cook & Torrance 1982): with g = sqrt(ior^2 - 1 + c^2),
// F = (g - c)^2 / (2 (g + c)^2) (1 + ((c (g + c) - 1) / (c (g - c) + 1))^2). F(1) = ((ior - 1) / (ior +
// 1))^2, F(0) = 1. c is clamped to [0, 1].
double fresnel_dielectric(double cos_theta, double ior);

enum class FacetDistribution
{
    Beckmann,
    Gaussian,
};

// Parses "beckmann" | "gaussian"; throws std::invalid_argument naming the value.
FacetDistribution parse_facet_distribution(const std::string& name);
const char* facet_distribution_name(FacetDistribution d);

class TorranceSparrow
{
  public:
    // Throws std::invalid_argument for roughness outside [0.001, 10] or not finite, ior <= 1 or not finite.
    TorranceSparrow(FacetDistribution distribution, double roughness, double ior);

    FacetDistribution distribution() const { return distribution_; }
    double roughness() const { return m_; }
    double ior() const { return ior_; }

    double fresnel(double cos_theta) const { return fresnel_dielectric(cos_theta, ior_); }
    // The facet distribution, normalised as above; 0 for cos_delta <= 0.
    double distribution_term(double cos_delta) const;
    // Smith's G1 and G1(c) / c (finite at c = 0).
    double smith_g1(double c) const;
    double smith_g1_over_cos(double c) const;

    // The two factors: F(cos_theta) D(cos_delta) and G(cos_alpha, cos_beta) / (pi cos_beta).
    double factor_fd(double cos_theta, double cos_delta) const
    {
        return fresnel(cos_theta) * distribution_term(cos_delta);
    }
    double factor_g(double cos_alpha, double cos_beta) const;

    // f_r cos_alpha evaluated directly from Eq. 1 (not through the factors); 0 when l or v is below the
    // surface. n, l, v unit vectors.
    double eval_cos(const glm::dvec3& n, const glm::dvec3& l, const glm::dvec3& v) const;

  private:
    FacetDistribution distribution_;
    double m_, ior_;
    double gaussian_c_ = 0.0; // the Gaussian distribution's normalisation
};

// Banks' two table terms for a = t.l, b = t.v in [-1, 1]: diffuse sqrt(1 - a^2), specular
// max(0, sqrt(1 - a^2) sqrt(1 - b^2) - a b)^exponent.
double banks_diffuse(double a);
double banks_specular(double a, double b, double exponent);
// The whole of Eq. 4 directly from vectors (n, t, l, v unit, t perpendicular to n): f_r cos_alpha, 0 below
// the surface.
double banks_eval_cos(const glm::dvec3& n, const glm::dvec3& t, const glm::dvec3& l, const glm::dvec3& v,
                      double kd, double ks, double exponent);

enum class LobeModel
{
    Phong,
    BlinnPhong,
    CosineLobe,
};
LobeModel parse_lobe_model(const std::string& name); // "phong" | "blinn-phong" | "cosine-lobe"
const char* lobe_model_name(LobeModel m);
// The specular f_r cos_alpha of a single-table model from its table coordinates x = n.l, y (see above).
double lobe_table_value(LobeModel model, double exponent, double x, double y);
// The same directly from vectors (n, l, v unit).
double lobe_eval_cos(LobeModel model, double exponent, const glm::dvec3& n, const glm::dvec3& l,
                     const glm::dvec3& v);

// A 2D lookup table of `channels` values per sample, size x size samples, sample (i along u, j along v) of
// channel c at (j * size + i) * channels + c; axis u is the first argument of the model's factor.
struct BrdfTable
{
    uint32_t size = 0;
    uint32_t channels = 0;
    std::vector<std::string> channel_names;
    std::vector<float> values;
    std::string axis_u, axis_v; // what each axis holds, e.g. "cos_theta", "sqrt(1-cos_delta)", "acos(t.l)/pi"
    // How an axis maps its cosine c (or t.l) to the coordinate 0..1 of samples 0..size - 1.
    enum class Axis
    {
        Cosine,       // c
        SqrtOneMinus, // sqrt(1 - c): for a narrow peak at c = 1
        Angle,        // acos(c) / pi: Banks' t.l and t.v over [-1, 1]
    };
    Axis u_axis = Axis::Cosine, v_axis = Axis::Cosine;

    // The table's coordinate of a cosine (or t.l) on each axis, and the bilinear lookup a GPU's sampler makes
    // (clamped to the edge samples).
    double coord_u(double value) const;
    double coord_v(double value) const;
    double lookup(uint32_t channel, double u_value, double v_value) const;
};

// The tables of each model, all of size x size samples, size >= 2. Throws std::invalid_argument for a bad
// size or exponent (<= 0, above 1e6 or not finite).
// Torrance-Sparrow: two tables, "FD" (u = cos_theta, v = sqrt(1 - cos_delta)) and "G" (u = cos_alpha,
// v = cos_beta); f_r cos_alpha = FD * G.
std::vector<BrdfTable> torrance_sparrow_tables(const TorranceSparrow& model, uint32_t size);
// Banks: one table, channels "diffuse" and "specular"; u = t.l, v = t.v, both over [-1, 1].
BrdfTable banks_table(double exponent, uint32_t size);
// Phong, Blinn-Phong, cosine lobe: one table, channel "specular"; u = n.l, v = sqrt(1 - y).
BrdfTable lobe_table(LobeModel model, double exponent, uint32_t size);

} // namespace hemi::math
