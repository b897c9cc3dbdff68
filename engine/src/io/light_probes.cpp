// Light probes and their visibility-weighted lookup (light_probes.h).
#include <hemi/io/light_probes.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hemi::io
{
namespace
{

bool finite3(const glm::vec3& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

} // namespace

glm::vec2 octahedral_encode(const glm::vec3& d)
{
    const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
    glm::vec2 p(d.x / l1, d.y / l1);
    if (d.z < 0.0f)
        p = glm::vec2((1.0f - std::abs(p.y)) * (p.x >= 0.0f ? 1.0f : -1.0f),
                      (1.0f - std::abs(p.x)) * (p.y >= 0.0f ? 1.0f : -1.0f));
    return p * 0.5f + 0.5f;
}

glm::vec3 octahedral_decode(const glm::vec2& uv)
{
    const glm::vec2 p = uv * 2.0f - 1.0f;
    glm::vec3 d(p.x, p.y, 1.0f - std::abs(p.x) - std::abs(p.y));
    if (d.z < 0.0f)
    {
        const float x = d.x;
        d.x = (1.0f - std::abs(d.y)) * (x >= 0.0f ? 1.0f : -1.0f);
        d.y = (1.0f - std::abs(x)) * (d.y >= 0.0f ? 1.0f : -1.0f);
    }
    const float l = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    return d / l;
}

glm::vec3 LightProbes::position(uint32_t i, uint32_t j, uint32_t k) const
{
    const glm::vec3 ijk{float(i), float(j), float(k)};
    const glm::vec3 steps = glm::max(glm::vec3(count) - 1.0f, glm::vec3(1.0f));
    return lo + (hi - lo) * ijk / steps;
}

glm::vec3 LightProbes::position(size_t probe) const
{
    return position(uint32_t(probe % count.x), uint32_t(probe / count.x % count.y),
                    uint32_t(probe / (size_t(count.x) * count.y)));
}

glm::vec2 LightProbes::depth_at(size_t probe, const glm::vec3& direction) const
{
    const int r = int(depth_resolution);
    const glm::vec2* map = depth.data() + probe * size_t(r) * size_t(r);
    // A texel outside the square is its mirror image across the edge it crossed (the octahedral map's edges
    // fold onto themselves: (0, v) and (0, 1 - v) are one direction); a corner is the opposite corner.
    auto texel = [&](int x, int y)
    {
        if (y < 0 || y >= r)
        {
            y = y < 0 ? 0 : r - 1;
            x = r - 1 - x;
        }
        if (x < 0 || x >= r)
        {
            x = x < 0 ? 0 : r - 1;
            y = r - 1 - y;
        }
        return map[size_t(y) * size_t(r) + size_t(x)];
    };
    const glm::vec2 t = octahedral_encode(direction) * float(r) - 0.5f;
    const float fx = std::floor(t.x), fy = std::floor(t.y);
    const int x = int(fx), y = int(fy);
    const float ax = t.x - fx, ay = t.y - fy;
    return (1.0f - ay) * ((1.0f - ax) * texel(x, y) + ax * texel(x + 1, y)) +
           ay * ((1.0f - ax) * texel(x, y + 1) + ax * texel(x + 1, y + 1));
}

float LightProbes::visibility(size_t probe, const glm::vec3& p) const
{
    if (depth.empty())
        return 1.0f;
    const glm::vec3 d = p - position(probe);
    const float r = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (!(r > 0.0f) || !std::isfinite(r))
        return 1.0f;
    const glm::vec2 m = depth_at(probe, d / r);
    if (r <= m.x)
        return 1.0f;
    const float variance = m.y * m.y, beyond = r - m.x;
    const float chebyshev = variance / (variance + beyond * beyond);
    return std::max(chebyshev * chebyshev * chebyshev, kMinVisibility);
}

LightProbes::Blend LightProbes::blend(const glm::vec3& p) const
{
    Blend b;
    if (empty() || count.x == 0 || count.y == 0 || count.z == 0 || valid.size() != irradiance.size())
        return b;
    // The cell and the weights along each axis.
    uint32_t i0[3], i1[3];
    float t[3];
    for (int a = 0; a < 3; ++a)
    {
        const uint32_t n = count[a];
        const float extent = hi[a] - lo[a];
        float f = n > 1 && extent > 0.0f ? (p[a] - lo[a]) / extent * float(n - 1) : 0.0f;
        f = std::isfinite(f) ? std::clamp(f, 0.0f, float(n - 1)) : 0.0f; // NaN: the first cell, not UB
        i0[a] = std::min(uint32_t(f), n - 1);
        i1[a] = std::min(i0[a] + 1, n - 1);
        t[a] = f - float(i0[a]);
    }
    float total = 0.0f;
    for (int corner = 0; corner < 8; ++corner)
    {
        const uint32_t i = corner & 1 ? i1[0] : i0[0], j = corner & 2 ? i1[1] : i0[1],
                       k = corner & 4 ? i1[2] : i0[2];
        const size_t at = i + size_t(count.x) * (j + size_t(count.y) * k);
        float w = (corner & 1 ? t[0] : 1.0f - t[0]) * (corner & 2 ? t[1] : 1.0f - t[1]) *
                  (corner & 4 ? t[2] : 1.0f - t[2]);
        if (!valid[at] || w <= 0.0f)
            continue;
        w *= visibility(at, p);
        total += w;
        b.probe[b.count] = at;
        b.weight[b.count++] = w;
    }
    if (total > 0.0f)
    {
        for (int c = 0; c < b.count; ++c)
            b.weight[c] /= total;
        return b;
    }
    // No valid probe around p: the nearest valid one.
    float best = INFINITY;
    for (size_t at = 0; at < size(); ++at)
    {
        const glm::vec3 d = position(at) - p;
        const float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
        if (valid[at] && d2 < best)
        {
            best = d2;
            b.probe[0] = at;
            b.weight[0] = 1.0f;
            b.count = 1;
        }
    }
    return b;
}

std::array<glm::vec3, 9> LightProbes::at(const glm::vec3& p) const
{
    std::array<glm::vec3, 9> out{};
    const Blend b = blend(p);
    for (int n = 0; n < b.count; ++n)
        for (int c = 0; c < 9; ++c)
            out[size_t(c)] += b.weight[n] * irradiance[b.probe[n]][size_t(c)];
    return out;
}

std::array<float, 4> LightProbes::occlusion_at(const glm::vec3& p) const
{
    if (occlusion.empty())
        return {1.0f, 1.0f, 1.0f, 1.0f};
    std::array<float, 4> out{};
    const Blend b = blend(p);
    for (int n = 0; n < b.count; ++n)
        for (size_t c = 0; c < 4; ++c)
            out[c] += b.weight[n] * occlusion[b.probe[n]][c];
    for (float& c : out) // weights that sum to 1 in float can take a blend of 1s a rounding above it
        c = std::clamp(c, 0.0f, 1.0f);
    return out;
}

std::string light_probes_problem(const LightProbes& p)
{
    if (p.count == glm::uvec3(0) && p.irradiance.empty() && p.valid.empty() && p.depth.empty())
        return {};
    const uint64_t n = probe_grid_count(p.count.x, p.count.y, p.count.z);
    if (n == 0)
        return "probe grid " + std::to_string(p.count.x) + "x" + std::to_string(p.count.y) + "x" +
               std::to_string(p.count.z) + " is empty or larger than 2^24 probes";
    if (p.irradiance.size() != n || p.valid.size() != n)
        return "the probe grid holds " + std::to_string(p.irradiance.size()) + " probes and " +
               std::to_string(p.valid.size()) + " flags, expected " + std::to_string(n);
    if (!finite3(p.lo) || !finite3(p.hi) || p.lo.x > p.hi.x || p.lo.y > p.hi.y || p.lo.z > p.hi.z)
        return "the probe grid's corners are not finite or not ordered";
    for (const auto& probe : p.irradiance)
        for (const glm::vec3& c : probe)
            if (!finite3(c))
                return "a probe holds a value that is not finite";
    if (!p.occlusion.empty() && p.occlusion.size() != n)
        return "the probe grid holds " + std::to_string(p.occlusion.size()) + " occlusions for " +
               std::to_string(n) + " probes";
    for (const auto& o : p.occlusion)
        for (float v : o)
            if (!(v >= 0.0f && v <= 1.0f))
                return "a probe's occlusion is outside [0, 1]";
    if (p.depth_resolution == 0 && p.depth.empty())
        return {};
    const uint64_t r = p.depth_resolution;
    if (r == 0 || r > kMaxProbeDepthResolution)
        return "the probes' depth maps are " + std::to_string(r) + " texels a side, not 1 to " +
               std::to_string(kMaxProbeDepthResolution);
    if (p.depth.size() != n * r * r)
        return "the probes' depth maps hold " + std::to_string(p.depth.size()) + " texels, " +
               std::to_string(n) + " probes of " + std::to_string(r) + "x" + std::to_string(r) + " need " +
               std::to_string(n * r * r);
    if (!(p.max_distance > 0.0f) || !std::isfinite(p.max_distance))
        return "the probes' largest distance is not a positive finite number";
    for (const glm::vec2& m : p.depth)
        if (!(m.x >= 0.0f && m.x <= p.max_distance && m.y >= 0.0f && m.y <= p.max_distance))
            return "a probe's depth map holds a distance that is negative, not finite or beyond its largest "
                   "distance";
    return {};
}

size_t probe_texel_stride(uint32_t depth_resolution)
{
    return 8 + (size_t(depth_resolution) * depth_resolution + 1) / 2;
}

std::vector<glm::vec4> probe_texels(const LightProbes& probes)
{
    if (std::string problem = light_probes_problem(probes); !problem.empty())
        throw std::invalid_argument("hemi: probe_texels: " + problem);
    const size_t stride = probe_texel_stride(probes.depth_resolution),
                 rr = size_t(probes.depth_resolution) * probes.depth_resolution;
    std::vector<glm::vec4> out(probes.size() * stride, glm::vec4(0.0f));
    for (size_t p = 0; p < probes.size(); ++p)
    {
        glm::vec4* t = out.data() + p * stride;
        float f[28] = {};
        for (size_t j = 0; j < 9; ++j)
            for (int c = 0; c < 3; ++c)
                f[j * 3 + size_t(c)] = probes.irradiance[p][j][c];
        f[27] = probes.valid[p] ? 1.0f : 0.0f;
        for (size_t i = 0; i < 7; ++i)
            t[i] = glm::vec4(f[i * 4], f[i * 4 + 1], f[i * 4 + 2], f[i * 4 + 3]);
        t[7] = probes.occlusion.empty() ? glm::vec4(1.0f)
                                        : glm::vec4(probes.occlusion[p][0], probes.occlusion[p][1],
                                                    probes.occlusion[p][2], probes.occlusion[p][3]);
        for (size_t i = 0; i < rr && !probes.depth.empty(); ++i)
        {
            const glm::vec2 m = probes.depth[p * rr + i];
            glm::vec4& v = t[8 + i / 2];
            if (i % 2 == 0)
                v.x = m.x, v.y = m.y;
            else
                v.z = m.x, v.w = m.y;
        }
    }
    return out;
}

} // namespace hemi::io
