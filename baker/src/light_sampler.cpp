// The bakes' light sampling (light_sampler.h).
#include "light_sampler.h"

#include <hemi/bake/ray_generator.h>
#include <hemi/math/luminance.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace hemi::bake::detail
{

EnvironmentSampler::EnvironmentSampler(const io::ImageRgba& env) : w_(env.width), h_(env.height)
{
    weight_.resize(size_t(w_) * h_);
    row_cdf_.assign(h_ + 1, 0.0);
    column_cdf_.assign(size_t(h_) * (w_ + 1), 0.0);
    for (uint32_t y = 0; y < h_; ++y)
    {
        const double solid = (2.0 * M_PI / w_) * (std::cos(M_PI * y / h_) - std::cos(M_PI * (y + 1) / h_));
        double row = 0.0;
        for (uint32_t x = 0; x < w_; ++x)
        {
            const float* p = env.at(x, y);
            const double lum = math::luminance(glm::dvec3(p[0], p[1], p[2]));
            const double mean = (double(p[0]) + p[1] + p[2]) / 3.0;
            // Luminance, kept above zero wherever any channel shines (a pure blue pixel is still sampled).
            const double wgt = std::max(0.0, std::max(lum, 0.01 * mean)) * solid;
            weight_[size_t(y) * w_ + x] = wgt;
            row += wgt;
            column_cdf_[size_t(y) * (w_ + 1) + x + 1] = row;
        }
        row_cdf_[y + 1] = row_cdf_[y] + row;
    }
    total_ = row_cdf_[h_];
}

glm::dvec3 EnvironmentSampler::sample(double u0, double u1, double u2, double u3, double& pdf) const
{
    const double target_row = u0 * total_;
    const uint32_t y = uint32_t(std::min<ptrdiff_t>(
        h_ - 1, std::upper_bound(row_cdf_.begin() + 1, row_cdf_.end(), target_row) - (row_cdf_.begin() + 1)));
    const double* cdf = &column_cdf_[size_t(y) * (w_ + 1)];
    const double target = u1 * cdf[w_];
    const uint32_t x =
        uint32_t(std::min<ptrdiff_t>(w_ - 1, std::upper_bound(cdf + 1, cdf + w_ + 1, target) - (cdf + 1)));
    const double z0 = std::cos(M_PI * y / h_), z1 = std::cos(M_PI * (y + 1) / h_);
    const double z = z0 + (z1 - z0) * u2;
    const double phi = M_PI - 2.0 * M_PI * (x + u3) / w_; // u = 0.5 - phi / 2 pi
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double solid = (2.0 * M_PI / w_) * (z0 - z1);
    pdf = weight_[size_t(y) * w_ + x] / (total_ * solid);
    return {s * std::cos(phi), s * std::sin(phi), z};
}

namespace
{
bool finite3(const glm::vec3& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool non_negative3(const glm::vec3& v)
{
    return v.x >= 0.0f && v.y >= 0.0f && v.z >= 0.0f;
}
} // namespace

void check_lights(const LightmapLights& l)
{
    if (!finite3(l.uniform) || !std::isfinite(l.environment_scale))
        throw std::invalid_argument("the environment's radiance must be finite");
    if (!non_negative3(l.uniform) || !(l.environment_scale >= 0.0f))
        throw std::invalid_argument("the environment's radiance must not be negative (--env-scale " +
                                    std::to_string(l.environment_scale) + ")");
    float env_max = std::max({l.uniform.x, l.uniform.y, l.uniform.z});
    if (!l.environment.pixels.empty())
    {
        if (l.environment.width == 0 || l.environment.height == 0 ||
            l.environment.pixels.size() != size_t(l.environment.width) * l.environment.height * 4)
            throw std::invalid_argument("the environment image's pixels do not match its size");
        env_max = 0.0f;
        for (size_t i = 0; i < l.environment.pixels.size(); ++i)
        {
            const float v = l.environment.pixels[i];
            if (!std::isfinite(v))
                throw std::invalid_argument("the environment image holds a value that is not finite");
            if (i % 4 != 3 && v < 0.0f)
                throw std::invalid_argument("the environment image holds a negative radiance (pixel " +
                                            std::to_string(i / 4 % l.environment.width) + ", " +
                                            std::to_string(i / 4 / l.environment.width) + ")");
            if (i % 4 != 3)
                env_max = std::max(env_max, v);
        }
        env_max *= l.environment_scale;
    }
    // Sums of many samples of such radiance must stay finite in float: far beyond any physical light.
    if (!(double(env_max) <= kMaxLightValue))
    {
        char text[160];
        std::snprintf(text, sizeof text,
                      "'s radiance reaches %.4g (times --env-scale): above %.4g, beyond what a bake can sum "
                      "in floats",
                      double(env_max), kMaxLightValue);
        throw std::invalid_argument(
            (l.environment_name.empty() ? std::string("the environment") : l.environment_name) + text);
    }
    for (const io::PunctualLight& p : l.punctual)
    {
        if (!finite3(p.color) || !std::isfinite(p.intensity) || !finite3(p.position) ||
            !finite3(p.direction) || glm::length(p.direction) < 1e-6f || !std::isfinite(p.range) ||
            !std::isfinite(p.inner_cone) || !std::isfinite(p.outer_cone))
            throw std::invalid_argument("punctual light '" + p.name +
                                        "' has a value that is not finite or a direction of zero length");
        if (!non_negative3(p.color) || p.intensity < 0.0f)
            throw std::invalid_argument("punctual light '" + p.name + "' has a negative colour or intensity");
        if (double(p.intensity) * std::max({p.color.x, p.color.y, p.color.z}) > kMaxLightValue)
            throw std::invalid_argument("punctual light '" + p.name + "' has an intensity above " +
                                        std::to_string(kMaxLightValue));
    }
    if (l.sun)
    {
        if (!finite3(l.sun_direction) || glm::length(l.sun_direction) < 1e-6f)
            throw std::invalid_argument("the sun's direction must be a finite vector of non-zero length");
        if (!finite3(l.sun_irradiance))
            throw std::invalid_argument("the sun's irradiance must be finite");
        if (!non_negative3(l.sun_irradiance))
            throw std::invalid_argument("the sun's irradiance must not be negative");
        if (double(std::max({l.sun_irradiance.x, l.sun_irradiance.y, l.sun_irradiance.z})) > kMaxLightValue)
            throw std::invalid_argument("the sun's irradiance is above " + std::to_string(kMaxLightValue));
        if (!(l.sun_diameter_degrees >= 0.0f) || !(l.sun_diameter_degrees < 90.0f))
            throw std::invalid_argument("the sun's diameter must be in [0, 90) degrees");
    }
}

LightSampler::LightSampler(const LightmapLights& lights, uint64_t seed)
    : lights_(&lights), image_env_(!lights.environment.pixels.empty()),
      env_(image_env_ ? lights.environment : io::ImageRgba{1, 1, {0, 0, 0, 0}}),
      env_seed_(mix64(seed ^ 0x454e565f5241ull)), sun_seed_(mix64(seed ^ 0x53554e5f5241ull))
{
    if (lights.sun)
    {
        // The sun's disc in the mesh's space: directions within half its angular diameter of the axis.
        sun_axis_ = glm::normalize(glm::transpose(lights.scene_to_world) * lights.sun_direction);
        cos_half_ = std::cos(0.5 * double(lights.sun_diameter_degrees) * M_PI / 180.0);
        glm::vec3 u = std::abs(sun_axis_.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        sun_u_ = glm::normalize(u - sun_axis_ * glm::dot(sun_axis_, u));
        sun_v_ = glm::cross(sun_axis_, sun_u_);
    }
}

bool LightSampler::environment_ray(uint64_t item, int r, int count, glm::vec3& direction,
                                   double& weight) const
{
    if (!image_env_ || env_.empty())
        return false;
    // Stratified along the distribution's CDF (turned by a random offset per item): the split between a
    // bright sun and the rest of the sky is then nearly exact for every item.
    double stratum = (double(r) + double(uniform01(env_seed_, item, uint64_t(4 * r)))) / double(count) +
                     environment_offset(item, count);
    stratum -= std::floor(stratum);
    // The second dimension on a golden-ratio lattice against the first: low discrepancy in both.
    double across =
        double(r) * 0.6180339887498949 + double(uniform01(env_seed_, item, uint64_t(4 * count + 1)));
    across -= std::floor(across);
    double pdf = 0.0;
    const glm::dvec3 world = env_.sample(stratum, across, uniform01(env_seed_, item, uint64_t(4 * r + 2)),
                                         uniform01(env_seed_, item, uint64_t(4 * r + 3)), pdf);
    if (!(pdf > 0.0))
        return false;
    direction = glm::normalize(glm::transpose(lights_->scene_to_world) * glm::vec3(world));
    weight = 1.0 / (pdf * double(count));
    return true;
}

double LightSampler::environment_offset(uint64_t item, int count) const
{
    return double(uniform01(env_seed_, item, uint64_t(4 * count)));
}

glm::vec3 LightSampler::sun_ray(uint64_t item, int r) const
{
    const double z = 1.0 - (1.0 - cos_half_) * double(uniform01(sun_seed_, item, uint64_t(2 * r)));
    const double phi = 2.0 * M_PI * double(uniform01(sun_seed_, item, uint64_t(2 * r + 1)));
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return glm::normalize(float(z) * sun_axis_ + float(s * std::cos(phi)) * sun_u_ +
                          float(s * std::sin(phi)) * sun_v_);
}

glm::vec3 LightSampler::punctual(const io::PunctualLight& p, const glm::vec3& at, glm::vec3& d,
                                 float& distance) const
{
    distance = INFINITY;
    glm::vec3 e = p.color * p.intensity;
    if (p.type == io::PunctualLight::Type::Directional)
    {
        d = -glm::normalize(p.direction);
        return e;
    }
    const glm::vec3 to = p.position - at;
    distance = glm::length(to);
    if (!(distance > 0.0f))
        return glm::vec3(0.0f);
    d = to / distance;
    float falloff = 1.0f / (distance * distance);
    if (p.range > 0.0f)
        falloff *= std::clamp(1.0f - std::pow(distance / p.range, 4.0f), 0.0f, 1.0f);
    if (p.type == io::PunctualLight::Type::Spot)
    {
        const float scale = 1.0f / std::max(0.001f, std::cos(p.inner_cone) - std::cos(p.outer_cone));
        const float cd = glm::dot(glm::normalize(p.direction), -d);
        const float a = std::clamp((cd - std::cos(p.outer_cone)) * scale, 0.0f, 1.0f);
        falloff *= a * a;
    }
    return e * falloff;
}

} // namespace hemi::bake::detail
