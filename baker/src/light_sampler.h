#pragma once
// The lights of LightmapLights as the bakes sample them, shared by the lightmap bake and the reference
// tracer (hemi-bake reference) so that both see the same lights, with the same random numbers for the same
// (item, ray): an image environment importance-sampled by luminance, the sun's disc, and glTF's punctual
// lights with their falloff. Internal to hemi_baker. Directions are in the mesh's space.

#include <hemi/bake/lightmap_bake.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace hemi::bake::detail
{

// Directions distributed like an equirect environment's luminance times each pixel's solid angle: a row by
// the marginal distribution, a pixel of it by the conditional one, then uniformly in solid angle inside the
// pixel. pdf(d) = weight(pixel) / (sum of weights * solid angle(pixel)). Directions in world space.
class EnvironmentSampler
{
  public:
    explicit EnvironmentSampler(const io::ImageRgba& env);
    bool empty() const { return !(total_ > 0.0); }
    // A direction from four uniform numbers in [0, 1), with its pdf.
    glm::dvec3 sample(double u0, double u1, double u2, double u3, double& pdf) const;

  private:
    uint32_t w_, h_;
    std::vector<double> weight_, row_cdf_, column_cdf_;
    double total_ = 0.0;
};

// The largest radiance, irradiance or intensity a light may have: far beyond any physical light (the sun's
// disc is ~1.6e9 cd/m^2), and small enough that sums of millions of samples of it stay finite in float.
constexpr double kMaxLightValue = 1e20;

// Throws std::invalid_argument for lights with a value that is not finite, negative or above
// kMaxLightValue, a sun direction of zero length or a sun diameter outside [0, 90) degrees.
void check_lights(const LightmapLights& lights);

class LightSampler
{
  public:
    // `lights` must outlive the sampler; `seed` is the bake's (the sampler derives its own streams from it).
    LightSampler(const LightmapLights& lights, uint64_t seed);

    const LightmapLights& lights() const { return *lights_; }
    bool image_environment() const { return image_env_; }

    // Ray r (0 <= r < count) of `item`'s `count` rays towards the image environment, stratified along the
    // luminance CDF: its direction and its weight 1 / (pdf * count) (radiance times weight sums to the
    // integral). False when there is no image environment or the sample has no density.
    bool environment_ray(uint64_t item, int r, int count, glm::vec3& direction, double& weight) const;
    // Where along the CDF `item`'s environment rays start: ray r's stratum is frac((r + its jitter) / count
    // + this), so the pattern wraps from the last rows of the map to the first between two of its rays.
    double environment_offset(uint64_t item, int count) const;
    // Ray r of `item`'s rays towards the sun's disc, uniform in its solid angle.
    glm::vec3 sun_ray(uint64_t item, int r) const;
    // What punctual light `light` gives point `p` (mesh space): the direction towards it, the distance to it
    // (INFINITY for a directional light) and the irradiance on a surface facing it (I / d^2 with glTF's
    // range window and smooth spot cone, times the colour; zero outside the cone or the range).
    glm::vec3 punctual(const io::PunctualLight& light, const glm::vec3& p, glm::vec3& direction,
                       float& distance) const;

  private:
    const LightmapLights* lights_;
    bool image_env_;
    EnvironmentSampler env_;
    uint64_t env_seed_, sun_seed_;
    glm::vec3 sun_axis_{0, 0, 1}, sun_u_{1, 0, 0}, sun_v_{0, 1, 0};
    double cos_half_ = 1.0;
};

} // namespace hemi::bake::detail
