// hemi-bake envmap --report: parabolic maps against a cube-map implementation of the same filter
// (factored.h).
#include <hemi/bake/factored.h>
#include <hemi/math/paraboloid.h>
#include <hemi/math/sh_environment.h>

#include <glm/geometric.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace hemi::bake
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

// Six faces (sh_environment.h's order and orientation), size x size RGB each: face f, row y (t down), column
// x.
struct CubeMap
{
    uint32_t size = 0;
    std::vector<float> rgb;
    float* at(int f, uint32_t x, uint32_t y) { return rgb.data() + ((size_t(f) * size + y) * size + x) * 3; }
    const float* at(int f, uint32_t x, uint32_t y) const
    {
        return rgb.data() + ((size_t(f) * size + y) * size + x) * 3;
    }
};

const glm::dvec3 kAxis[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// The face a direction falls on and its (s, t) there: the inverse of math::cubemap_direction.
int cube_face(const glm::dvec3& d, double& s, double& t)
{
    const glm::dvec3 a = glm::abs(d);
    if (a.x >= a.y && a.x >= a.z)
    {
        s = (d.x > 0 ? -d.z : d.z) / a.x;
        t = -d.y / a.x;
        return d.x > 0 ? 0 : 1;
    }
    if (a.y >= a.z)
    {
        s = d.x / a.y;
        t = (d.y > 0 ? d.z : -d.z) / a.y;
        return d.y > 0 ? 2 : 3;
    }
    s = (d.z > 0 ? d.x : -d.x) / a.z;
    t = -d.y / a.z;
    return d.z > 0 ? 4 : 5;
}
// (s, t) on a face's plane, inside the square or not, to a direction.
glm::dvec3 face_direction(int f, double s, double t)
{
    switch (f)
    {
    case 0:
        return glm::normalize(glm::dvec3(1, -t, -s));
    case 1:
        return glm::normalize(glm::dvec3(-1, -t, s));
    case 2:
        return glm::normalize(glm::dvec3(s, 1, t));
    case 3:
        return glm::normalize(glm::dvec3(s, -1, -t));
    case 4:
        return glm::normalize(glm::dvec3(s, -t, 1));
    default:
        return glm::normalize(glm::dvec3(-s, -t, -1));
    }
}

CubeMap cube_from_equirect(uint32_t size, const io::ImageRgba& env)
{
    CubeMap c;
    c.size = size;
    c.rgb.assign(size_t(6) * size * size * 3, 0.0f);
    const uint32_t n = std::clamp(uint32_t(std::ceil(2.0 * env.width / (kPi * size))), 2u, 16u);
    tbb::parallel_for(
        uint32_t(0), 6 * size,
        [&](uint32_t fy)
        {
            const int f = int(fy / size);
            const uint32_t y = fy % size;
            for (uint32_t x = 0; x < size; ++x)
            {
                glm::dvec3 sum(0.0);
                double weight = 0.0;
                for (uint32_t j = 0; j < n; ++j)
                    for (uint32_t i = 0; i < n; ++i)
                    {
                        const double s = -1.0 + 2.0 * (x + (i + 0.5) / n) / size,
                                     t = -1.0 + 2.0 * (y + (j + 0.5) / n) / size;
                        const double w =
                            1.0 / std::pow(1.0 + s * s + t * t, 1.5); // solid angle per unit area
                        uint32_t px, py;
                        math::equirect_pixel(face_direction(f, s, t), env.width, env.height, px, py);
                        const float* p = env.at(px, py);
                        sum += w * glm::dvec3(p[0], p[1], p[2]);
                        weight += w;
                    }
                float* o = c.at(f, x, y);
                for (int k = 0; k < 3; ++k)
                    o[k] = float(sum[k] / weight);
            }
        });
    return c;
}

// The same windowed sum as math::prefilter_phong, over the cube's texels: each at its centre with its exact
// solid angle, over the texels of each face inside the bounding box of the lobe cap's gnomonic image.
CubeMap prefilter_cube(const CubeMap& src, double exponent)
{
    const uint32_t m = src.size;
    const size_t texels = size_t(6) * m * m;
    std::vector<float> dir(texels * 3), wl(texels * 3);
    for (int f = 0; f < 6; ++f)
        for (uint32_t y = 0; y < m; ++y)
            for (uint32_t x = 0; x < m; ++x)
            {
                const size_t k = (size_t(f) * m + y) * m + x;
                const double s0 = -1.0 + 2.0 * x / m, t0 = -1.0 + 2.0 * y / m, step = 2.0 / m;
                const glm::dvec3 d = face_direction(f, s0 + 0.5 * step, t0 + 0.5 * step);
                const double w = math::cubemap_solid_angle(s0, t0, s0 + step, t0 + step);
                for (int c = 0; c < 3; ++c)
                {
                    dir[k * 3 + c] = float(d[c]);
                    wl[k * 3 + c] = float(w * src.at(f, x, y)[c]);
                }
            }
    const math::PhongLobe lobe(exponent);
    const double gamma = lobe.angle();
    const double norm = (exponent + 1.0) / (2.0 * kPi);
    CubeMap out;
    out.size = m;
    out.rgb.assign(texels * 3, 0.0f);
    tbb::parallel_for(
        uint32_t(0), 6 * m,
        [&](uint32_t fy)
        {
            const int of = int(fy / m);
            const uint32_t oy = fy % m;
            for (uint32_t ox = 0; ox < m; ++ox)
            {
                const glm::dvec3 r =
                    face_direction(of, -1.0 + (2.0 * ox + 1.0) / m, -1.0 + (2.0 * oy + 1.0) / m);
                // The cap's boundary: 64 points at angle gamma from r.
                const glm::dvec3 u = glm::normalize(std::abs(r.x) < 0.9 ? glm::cross(r, glm::dvec3(1, 0, 0))
                                                                        : glm::cross(r, glm::dvec3(0, 1, 0)));
                const glm::dvec3 w = glm::cross(r, u);
                glm::dvec3 boundary[64];
                for (int k = 0; k < 64; ++k)
                {
                    const double a = 2.0 * kPi * k / 64;
                    boundary[k] = std::cos(gamma) * r + std::sin(gamma) * (std::cos(a) * u + std::sin(a) * w);
                }
                double acc[3] = {0, 0, 0};
                for (int f = 0; f < 6; ++f)
                {
                    double s_lo = -1, s_hi = 1, t_lo = -1, t_hi = 1;
                    if (gamma < 0.5 * kPi)
                    {
                        bool any_front = glm::dot(r, kAxis[f]) > 0.0, near_plane = false;
                        double lo_s = 1e30, hi_s = -1e30, lo_t = 1e30, hi_t = -1e30;
                        for (const glm::dvec3& b : boundary)
                        {
                            const double along = glm::dot(b, kAxis[f]);
                            any_front = any_front || along > 0.0;
                            near_plane = near_plane || along < 0.02;
                            if (along > 0.0)
                            {
                                double s, t;
                                const glm::dvec3 p =
                                    b / along; // on the face's plane (outside its square or not)
                                switch (f)
                                {
                                case 0:
                                    s = -p.z, t = -p.y;
                                    break;
                                case 1:
                                    s = p.z, t = -p.y;
                                    break;
                                case 2:
                                    s = p.x, t = p.z;
                                    break;
                                case 3:
                                    s = p.x, t = -p.z;
                                    break;
                                case 4:
                                    s = p.x, t = -p.y;
                                    break;
                                default:
                                    s = -p.x, t = -p.y;
                                    break;
                                }
                                lo_s = std::min(lo_s, s), hi_s = std::max(hi_s, s);
                                lo_t = std::min(lo_t, t), hi_t = std::max(hi_t, t);
                            }
                        }
                        if (!any_front)
                            continue;
                        if (!near_plane)
                        {
                            const double margin_s = 0.02 * (hi_s - lo_s) + 2.0 / m,
                                         margin_t = 0.02 * (hi_t - lo_t) + 2.0 / m;
                            s_lo = std::max(-1.0, lo_s - margin_s), s_hi = std::min(1.0, hi_s + margin_s);
                            t_lo = std::max(-1.0, lo_t - margin_t), t_hi = std::min(1.0, hi_t + margin_t);
                            if (s_lo > s_hi || t_lo > t_hi)
                                continue;
                        }
                    }
                    const uint32_t x0 = uint32_t(std::max(0.0, std::floor((s_lo + 1.0) * 0.5 * m)));
                    const uint32_t x1 = uint32_t(std::min(double(m - 1), std::floor((s_hi + 1.0) * 0.5 * m)));
                    const uint32_t y0 = uint32_t(std::max(0.0, std::floor((t_lo + 1.0) * 0.5 * m)));
                    const uint32_t y1 = uint32_t(std::min(double(m - 1), std::floor((t_hi + 1.0) * 0.5 * m)));
                    const float rx = float(r.x), ry = float(r.y), rz = float(r.z);
                    for (uint32_t y = y0; y <= y1; ++y)
                        for (uint32_t x = x0; x <= x1; ++x)
                        {
                            const size_t k = ((size_t(f) * m + y) * m + x) * 3;
                            const float c = dir[k] * rx + dir[k + 1] * ry + dir[k + 2] * rz;
                            if (c > lobe.cos_cut())
                            {
                                const float l = lobe(c);
                                acc[0] += l * wl[k], acc[1] += l * wl[k + 1], acc[2] += l * wl[k + 2];
                            }
                        }
                }
                float* o = out.at(of, ox, oy);
                for (int c = 0; c < 3; ++c)
                    o[c] = float(norm * acc[c]);
            }
        });
    return out;
}

// Bilinear, seamless: a tap past a face's edge reads the texel of the neighbouring face that its centre's
// direction falls in.
glm::dvec3 cube_sample(const CubeMap& c, const glm::dvec3& d)
{
    double s, t;
    const int f = cube_face(d, s, t);
    const uint32_t m = c.size;
    const double px = (s + 1.0) * 0.5 * m - 0.5, py = (t + 1.0) * 0.5 * m - 0.5;
    const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
    const double fx = px - x0, fy = py - y0;
    glm::dvec3 sum(0.0);
    for (int k = 0; k < 4; ++k)
    {
        const int x = x0 + (k & 1), y = y0 + (k >> 1);
        const double w = ((k & 1) ? fx : 1.0 - fx) * ((k >> 1) ? fy : 1.0 - fy);
        const float* texel;
        if (x >= 0 && y >= 0 && x < int(m) && y < int(m))
            texel = c.at(f, uint32_t(x), uint32_t(y));
        else
        {
            double s2, t2;
            const int f2 =
                cube_face(face_direction(f, -1.0 + (2.0 * x + 1.0) / m, -1.0 + (2.0 * y + 1.0) / m), s2, t2);
            const uint32_t x2 = std::min(m - 1, uint32_t(std::max(0.0, (s2 + 1.0) * 0.5 * m)));
            const uint32_t y2 = std::min(m - 1, uint32_t(std::max(0.0, (t2 + 1.0) * 0.5 * m)));
            texel = c.at(f2, x2, y2);
        }
        sum += w * glm::dvec3(texel[0], texel[1], texel[2]);
    }
    return sum;
}

// Eq. 9 over the equirect's pixels where the lobe exceeds its cutoff (rows within gamma of r's, and in each
// the columns within the cap's azimuth span).
struct Columns
{
    std::vector<double> cos_phi, sin_phi; // of each column's centre
    explicit Columns(uint32_t w) : cos_phi(w), sin_phi(w)
    {
        for (uint32_t x = 0; x < w; ++x)
        {
            const double phi = kPi - 2.0 * kPi * (x + 0.5) / w;
            cos_phi[x] = std::cos(phi), sin_phi[x] = std::sin(phi);
        }
    }
};

glm::dvec3 reference(const io::ImageRgba& env, const Columns& columns, const math::PhongLobe& lobe,
                     double exponent, const glm::dvec3& r)
{
    const uint32_t w = env.width, h = env.height;
    const double theta_r = std::acos(std::clamp(r.z, -1.0, 1.0)), phi_r = std::atan2(r.y, r.x);
    const double gamma = lobe.angle(), cos_gamma = std::cos(gamma);
    const int y0 = std::max(0, int(std::floor((theta_r - gamma) / kPi * h)) - 1);
    const int y1 = std::min(int(h) - 1, int(std::ceil((theta_r + gamma) / kPi * h)) + 1);
    glm::dvec3 sum(0.0);
    for (int y = y0; y <= y1; ++y)
    {
        const double t0 = kPi * y / h, t1 = kPi * (y + 1) / h, theta = 0.5 * (t0 + t1);
        const double omega = 2.0 * kPi / w * (std::cos(t0) - std::cos(t1));
        const double st = std::sin(theta), ct = std::cos(theta);
        // Columns: all, or those within the azimuth span (plus a pixel of margin either side).
        int half_span = int(w);
        const double denom = st * std::sin(theta_r);
        if (denom > 1e-9)
        {
            const double c = (cos_gamma - ct * std::cos(theta_r)) / denom;
            if (c > 1.0)
                continue;
            if (c > -1.0)
                half_span = int(std::ceil(std::acos(c) / (2.0 * kPi) * w)) + 2;
        }
        // phi = pi - 2 pi (x + 0.5) / w: the column of phi_r.
        const int centre = int(std::floor((kPi - phi_r) / (2.0 * kPi) * w));
        const int count = std::min(int(w), 2 * half_span + 1);
        for (int i = 0; i < count; ++i)
        {
            const int x = ((centre - std::min(half_span, int(w) / 2) + i) % int(w) + int(w)) % int(w);
            const double c = st * (columns.cos_phi[x] * r.x + columns.sin_phi[x] * r.y) + ct * r.z;
            if (c > lobe.cos_cut())
            {
                const float* p = env.at(uint32_t(x), uint32_t(y));
                sum += double(lobe(float(c))) * omega * glm::dvec3(p[0], p[1], p[2]);
            }
        }
    }
    return (exponent + 1.0) / (2.0 * kPi) * sum;
}
} // namespace

std::vector<glm::dvec3> phong_reference(const io::ImageRgba& env, double exponent,
                                        std::span<const glm::dvec3> dirs)
{
    const math::PhongLobe lobe(exponent);
    const Columns columns(env.width);
    std::vector<glm::dvec3> out(dirs.size());
    tbb::parallel_for(size_t(0), dirs.size(),
                      [&](size_t i) { out[i] = reference(env, columns, lobe, exponent, dirs[i]); });
    return out;
}

std::vector<PrefilterComparison> compare_prefiltered_maps(const io::ImageRgba& env,
                                                          const io::EnvmapAsset& asset, uint32_t directions)
{
    std::vector<glm::dvec3> dirs(directions);
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (uint32_t i = 0; i < directions; ++i)
    {
        const double z = 1.0 - (i + 0.5) * 2.0 / directions, s = std::sqrt(1.0 - z * z);
        dirs[i] = glm::dvec3(s * std::cos(golden * i), s * std::sin(golden * i), z);
    }
    std::vector<std::pair<double, const math::ParabolicImage*>> maps{{1.0, &asset.diffuse}};
    for (size_t i = 0; i < asset.glossy.size(); ++i)
        maps.emplace_back(double(asset.exponents[i]), &asset.glossy[i]);
    std::vector<PrefilterComparison> out;
    for (const auto& [e, map] : maps)
    {
        PrefilterComparison c;
        c.exponent = e;
        c.parabolic_size = map->size;
        c.parabolic_texels = 2ull * map->size * map->size;
        c.cube_size = std::max(1u, map->size / 2);
        c.cube_texels = 6ull * c.cube_size * c.cube_size;
        const auto t0 = std::chrono::steady_clock::now();
        const CubeMap cube = prefilter_cube(cube_from_equirect(c.cube_size, env), e);
        c.cube_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const math::PhongLobe lobe(e);
        const Columns columns(env.width);
        std::vector<double> pe(directions), ce(directions), rr(directions);
        tbb::parallel_for(uint32_t(0), directions,
                          [&](uint32_t i)
                          {
                              const glm::dvec3 ref = reference(env, columns, lobe, e, dirs[i]);
                              const glm::dvec3 p = map->sample(dirs[i]) - ref,
                                               q = cube_sample(cube, dirs[i]) - ref;
                              pe[i] = glm::dot(p, p) / 3.0;
                              ce[i] = glm::dot(q, q) / 3.0;
                              rr[i] = glm::dot(ref, ref) / 3.0;
                          });
        double sp = 0, sc = 0, sr = 0;
        for (uint32_t i = 0; i < directions; ++i)
            sp += pe[i], sc += ce[i], sr += rr[i];
        c.parabolic_rmse = std::sqrt(sp / directions);
        c.cube_rmse = std::sqrt(sc / directions);
        c.reference_rms = std::sqrt(sr / directions);
        out.push_back(c);
    }
    return out;
}

} // namespace hemi::bake
