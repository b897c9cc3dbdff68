// An upper bound on the direct irradiance of a bake's lights (light_bound.h).
#include <hemi/bake/light_bound.h>

#include "light_sampler.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hemi::bake
{
namespace
{

double max3(const glm::dvec3& v)
{
    return std::max({v.x, v.y, v.z});
}

// The direction of equirect coordinates (u across, t = theta from +z), math/sh_environment.h's convention:
// phi = pi - 2 pi u.
glm::dvec3 equirect_direction(double u, double theta)
{
    const double phi = M_PI - 2.0 * M_PI * u;
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// The environment's largest irradiance over normals, bounded from above (light_bound.h).
double environment_bound(const LightmapLights& l)
{
    if (l.environment.pixels.empty())
        return M_PI * max3(glm::dvec3(l.uniform));
    // The image as a grid of at least 128 x 64 parts: each pixel split into kx x ky parts (of exact solid
    // angle: azimuth in equal parts, theta in equal parts of its rows) when the image is smaller, so that
    // the cells below are small on a coarse image too. Part (x, y) covers theta in [pi y / H, pi (y + 1) / H)
    // and 2 pi / W of azimuth, with the radiance of its pixel.
    constexpr uint32_t kCellsX = 128, kCellsY = 64;
    const uint32_t kx = (kCellsX + l.environment.width - 1) / l.environment.width;
    const uint32_t ky = (kCellsY + l.environment.height - 1) / l.environment.height;
    const uint32_t W = l.environment.width * kx, H = l.environment.height * ky;
    const uint32_t cw = std::min(W, kCellsX), ch = std::min(H, kCellsY);
    // Each cell's power per channel, sum L omega over its parts.
    std::vector<glm::dvec3> power(size_t(cw) * ch, glm::dvec3(0.0));
    for (uint32_t y = 0; y < H; ++y)
    {
        const double omega = (2.0 * M_PI / W) * (std::cos(M_PI * y / H) - std::cos(M_PI * (y + 1) / H));
        const uint32_t cy = uint32_t(uint64_t(y) * ch / H);
        for (uint32_t x = 0; x < W; ++x)
        {
            const float* p = l.environment.at(x / kx, y / ky);
            power[size_t(cy) * cw + uint64_t(x) * cw / W] += glm::dvec3(p[0], p[1], p[2]) * omega;
        }
    }
    // Cell (cx, cy) covers parts [first_x(cx), first_x(cx + 1)) x [first_y(cy), first_y(cy + 1)).
    auto first_x = [&](uint32_t cx) { return (uint64_t(cx) * W + cw - 1) / cw; };
    auto first_y = [&](uint32_t cy) { return (uint64_t(cy) * H + ch - 1) / ch; };
    // 4096 normals on a Fibonacci spiral; alpha bounds the angle from any unit vector to the nearest of them
    // (their covering radius is about 1.1 sqrt(4 / N); 1.5 sqrt(4 / N) leaves room).
    constexpr int kNormals = 4096;
    const double alpha = 1.5 * std::sqrt(4.0 / kNormals);
    struct Cell
    {
        glm::dvec3 centre, power;
        double cos_b, sin_b; // of the cell's angular radius plus alpha
    };
    std::vector<Cell> cells;
    for (uint32_t cy = 0; cy < ch; ++cy)
        for (uint32_t cx = 0; cx < cw; ++cx)
        {
            const glm::dvec3 pw = power[size_t(cy) * cw + cx];
            if (max3(pw) <= 0.0)
                continue;
            const double u0 = double(first_x(cx)) / W, u1 = double(first_x(cx + 1)) / W;
            const double t0 = M_PI * double(first_y(cy)) / H, t1 = M_PI * double(first_y(cy + 1)) / H;
            const glm::dvec3 c = equirect_direction(0.5 * (u0 + u1), 0.5 * (t0 + t1));
            // The farthest point of a cell (at most 1/128 of the azimuth) from its centre is on its boundary:
            // its corners or its edges' midpoints.
            double radius = 0.0;
            for (double u : {u0, 0.5 * (u0 + u1), u1})
                for (double t : {t0, 0.5 * (t0 + t1), t1})
                    radius = std::max(
                        radius, std::acos(std::clamp(glm::dot(c, equirect_direction(u, t)), -1.0, 1.0)));
            const double b = std::min(M_PI, radius + alpha);
            cells.push_back({c, pw, std::cos(b), std::sin(b)});
        }
    // At a sampled normal n, a cell within angle a of n gives at most cos(max(0, a - b)) of its power:
    // 1 when n . c >= cos b, else (n . c) cos b + sin(a) sin b, 0 when that is negative.
    double most = 0.0;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < kNormals; ++i)
    {
        const double z = 1.0 - (2.0 * i + 1.0) / kNormals, r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const glm::dvec3 n(r * std::cos(golden * i), r * std::sin(golden * i), z);
        glm::dvec3 e(0.0);
        for (const Cell& c : cells)
        {
            const double x = glm::dot(n, c.centre);
            const double f =
                x >= c.cos_b ? 1.0
                             : std::max(0.0, x * c.cos_b + std::sqrt(std::max(0.0, 1.0 - x * x)) * c.sin_b);
            e += c.power * f;
        }
        most = std::max(most, max3(e));
    }
    return most * double(l.environment_scale);
}

// The distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
double point_triangle_distance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                               const glm::dvec3& c)
{
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0)
        return glm::length(ap);
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3)
        return glm::length(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
        return glm::length(p - (a + ab * (d1 / (d1 - d3))));
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6)
        return glm::length(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
        return glm::length(p - (a + ac * (d2 / (d2 - d6))));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const double denom = va + vb + vc;
    if (!(std::abs(denom) > 0.0)) // a degenerate triangle: its edges' nearest points are above
        return std::min({glm::length(ap), glm::length(bp), glm::length(cp)});
    return glm::length(p - (a + ab * (vb / denom) + ac * (vc / denom)));
}

} // namespace

const LightBoundSource* LightBound::largest() const
{
    const LightBoundSource* best = nullptr;
    for (const LightBoundSource& s : sources)
        if (!best || s.irradiance > best->irradiance)
            best = &s;
    return best;
}

LightBound lightmap_light_bound(const LightmapLights& l, const std::vector<io::Material>& materials,
                                const io::Mesh& mesh)
{
    detail::check_lights(l);
    LightBound bound;
    if (l.sun)
        bound.sources.push_back({"the sun (--sun)", max3(glm::dvec3(l.sun_irradiance))});
    for (const io::PunctualLight& p : l.punctual)
    {
        const double intensity = double(p.intensity) * max3(glm::dvec3(p.color));
        if (p.type == io::PunctualLight::Type::Directional)
        {
            bound.sources.push_back({"the glTF directional light '" + p.name + "' (lux)", intensity});
            continue;
        }
        double d = std::numeric_limits<double>::infinity();
        const glm::dvec3 at(p.position);
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
            d = std::min(d, point_triangle_distance(at, glm::dvec3(mesh.positions[mesh.indices[t]]),
                                                    glm::dvec3(mesh.positions[mesh.indices[t + 1]]),
                                                    glm::dvec3(mesh.positions[mesh.indices[t + 2]])));
        double e = intensity / (d * d); // infinite for a light on a surface (or 0 / 0: a dark one)
        if (!(intensity > 0.0) || !std::isfinite(d))
            e = 0.0;
        else if (p.range > 0.0f)
            e *= std::clamp(1.0 - std::pow(d / double(p.range), 4.0), 0.0, 1.0);
        char at_distance[64];
        std::snprintf(at_distance, sizeof at_distance, " (candela), %.3g from the nearest surface", d);
        bound.sources.push_back({"the glTF " +
                                     std::string(p.type == io::PunctualLight::Type::Spot ? "spot" : "point") +
                                     " light '" + p.name + "'" + at_distance,
                                 e});
    }
    bound.sources.push_back({l.environment.pixels.empty()
                                 ? std::string("the environment (--env uniform, --env-scale)")
                                 : "the environment image " + l.environment_name + " (--env, --env-scale)",
                             environment_bound(l)});
    for (const io::Material& m : materials)
        if (max3(glm::dvec3(m.emissive_factor)) > 0.0)
            bound.sources.push_back(
                {"the emissive material '" + m.name + "'", M_PI * max3(glm::dvec3(m.emissive_factor))});
    for (const LightBoundSource& s : bound.sources)
        bound.total += s.irradiance;
    return bound;
}

} // namespace hemi::bake
