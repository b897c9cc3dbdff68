#include <hemi/math/sh.h>
#include <hemi/math/sh_environment.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::math
{
namespace
{
void accumulate(int order, const glm::vec3& d, double solid_angle, const float* texel,
                std::vector<glm::dvec3>& acc)
{
    if (!std::isfinite(texel[0]) || !std::isfinite(texel[1]) || !std::isfinite(texel[2]))
        throw std::invalid_argument("hemi: environment map texel is not finite");
    float y[kMaxShOrder * kMaxShOrder];
    sh_eval(order, d, std::span<float>(y, size_t(sh_count(order))));
    glm::dvec3 l(texel[0], texel[1], texel[2]);
    for (int i = 0; i < sh_count(order); ++i)
        acc[i] += l * (double(y[i]) * solid_angle);
}

std::vector<glm::vec3> to_float(const std::vector<glm::dvec3>& acc)
{
    std::vector<glm::vec3> out(acc.size());
    for (size_t i = 0; i < acc.size(); ++i)
        out[i] = glm::vec3(acc[i]);
    return out;
}
} // namespace

std::vector<glm::vec3> project_equirect(int order, uint32_t width, uint32_t height,
                                        std::span<const float> rgba)
{
    if (width == 0 || height == 0 || rgba.size() != size_t(width) * height * 4)
        throw std::invalid_argument("hemi: project_equirect: " + std::to_string(rgba.size()) +
                                    " floats for a " + std::to_string(width) + "x" + std::to_string(height) +
                                    " RGBA image");
    std::vector<glm::dvec3> acc(size_t(sh_count(order)), glm::dvec3(0.0));
    const double dphi = 2.0 * M_PI / width;
    for (uint32_t y = 0; y < height; ++y)
    {
        double theta0 = M_PI * y / height, theta1 = M_PI * (y + 1) / height, theta = 0.5 * (theta0 + theta1);
        double solid_angle = dphi * (std::cos(theta0) - std::cos(theta1));
        for (uint32_t x = 0; x < width; ++x)
        {
            double phi = M_PI - (x + 0.5) * dphi; // Blender's azimuth (sh_environment.h)
            glm::vec3 d(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                        float(std::cos(theta)));
            accumulate(order, d, solid_angle, &rgba[(size_t(y) * width + x) * 4], acc);
        }
    }
    return to_float(acc);
}

void equirect_pixel(const glm::dvec3& d, uint32_t width, uint32_t height, uint32_t& x, uint32_t& y)
{
    const double phi = std::atan2(d.y, d.x);
    const double theta = std::acos(std::clamp(d.z, -1.0, 1.0));
    double u = 0.5 - phi / (2.0 * M_PI);
    u -= std::floor(u);
    x = std::min(width - 1, uint32_t(u * width));
    y = std::min(height - 1, uint32_t(theta / M_PI * height));
}

glm::vec3 cubemap_direction(int face, float s, float t)
{
    glm::vec3 d;
    switch (face)
    {
    case 0:
        d = {1.0f, -t, -s};
        break;
    case 1:
        d = {-1.0f, -t, s};
        break;
    case 2:
        d = {s, 1.0f, t};
        break;
    case 3:
        d = {s, -1.0f, -t};
        break;
    case 4:
        d = {s, -t, 1.0f};
        break;
    case 5:
        d = {-s, -t, -1.0f};
        break;
    default:
        throw std::invalid_argument("hemi: cube face " + std::to_string(face) + " is not in [0, 5]");
    }
    return glm::normalize(d);
}

double cubemap_solid_angle(double s0, double t0, double s1, double t1)
{
    auto area = [](double x, double y) { return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0)); };
    return area(s0, t0) - area(s0, t1) - area(s1, t0) + area(s1, t1);
}

std::vector<glm::vec3> project_cubemap(int order, uint32_t size, std::span<const float> faces)
{
    if (size == 0 || faces.size() != size_t(6) * size * size * 4)
        throw std::invalid_argument("hemi: project_cubemap: " + std::to_string(faces.size()) +
                                    " floats for six " + std::to_string(size) + "x" + std::to_string(size) +
                                    " RGBA faces");
    std::vector<glm::dvec3> acc(size_t(sh_count(order)), glm::dvec3(0.0));
    const double step = 2.0 / size;
    for (int f = 0; f < 6; ++f)
        for (uint32_t y = 0; y < size; ++y)
            for (uint32_t x = 0; x < size; ++x)
            {
                double s0 = -1.0 + x * step, t0 = -1.0 + y * step;
                glm::vec3 d = cubemap_direction(f, float(s0 + 0.5 * step), float(t0 + 0.5 * step));
                accumulate(order, d, cubemap_solid_angle(s0, t0, s0 + step, t0 + step),
                           &faces[((size_t(f) * size + y) * size + x) * 4], acc);
            }
    return to_float(acc);
}

} // namespace hemi::math
