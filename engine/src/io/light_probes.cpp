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

// A scattered probe's weight at p before its visibility: (1 - d^2 / reach^2)^8 within its reach.
float bump(const glm::vec4& probe, const glm::vec3& p)
{
    const glm::vec3 d = p - glm::vec3(probe);
    const float t = 1.0f - (d.x * d.x + d.y * d.y + d.z * d.z) / (probe.w * probe.w);
    const float t2 = t * t, t4 = t2 * t2;
    return t > 0.0f ? t4 * t4 : 0.0f;
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
    if (scattered())
        return glm::vec3(points[probe]);
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
    return std::max(chebyshev * chebyshev, kMinVisibility);
}

LightProbes::Blend LightProbes::blend(const glm::vec3& p, const ProbeIndex* index) const
{
    Blend b;
    if (empty() || count.x == 0 || count.y == 0 || count.z == 0 || valid.size() != irradiance.size())
        return b;
    float total = 0.0f;
    auto add = [&](size_t at, float w)
    {
        if (!valid[at] || !(w > 0.0f))
            return;
        w *= visibility(at, p);
        total += w;
        b.probe.push_back(uint32_t(at));
        b.weight.push_back(w);
    };
    if (scattered())
    {
        if (index)
            for (uint32_t at : index->near(p))
                add(at, bump(points[at], p));
        else
            for (size_t at = 0; at < points.size(); ++at)
                add(at, bump(points[at], p));
    }
    else
    {
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
        for (int corner = 0; corner < 8; ++corner)
        {
            const uint32_t i = corner & 1 ? i1[0] : i0[0], j = corner & 2 ? i1[1] : i0[1],
                           k = corner & 4 ? i1[2] : i0[2];
            add(i + size_t(count.x) * (j + size_t(count.y) * k), (corner & 1 ? t[0] : 1.0f - t[0]) *
                                                                     (corner & 2 ? t[1] : 1.0f - t[1]) *
                                                                     (corner & 4 ? t[2] : 1.0f - t[2]));
        }
    }
    if (total > 0.0f)
    {
        for (float& w : b.weight)
            w /= total;
        return b;
    }
    // No valid probe around p: the nearest valid one.
    b.probe.clear();
    b.weight.clear();
    float best = INFINITY;
    size_t nearest = size();
    for (size_t at = 0; at < size(); ++at)
    {
        const glm::vec3 d = position(at) - p;
        const float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
        if (valid[at] && d2 < best)
        {
            best = d2;
            nearest = at;
        }
    }
    if (nearest < size())
    {
        b.probe.push_back(uint32_t(nearest));
        b.weight.push_back(1.0f);
    }
    return b;
}

std::array<glm::vec3, 9> LightProbes::at(const glm::vec3& p, const ProbeIndex* index) const
{
    std::array<glm::vec3, 9> out{};
    const Blend b = blend(p, index);
    for (size_t n = 0; n < b.count(); ++n)
        for (int c = 0; c < 9; ++c)
            out[size_t(c)] += b.weight[n] * irradiance[b.probe[n]][size_t(c)];
    return out;
}

std::array<float, 4> LightProbes::occlusion_at(const glm::vec3& p, const ProbeIndex* index) const
{
    if (occlusion.empty())
        return {1.0f, 1.0f, 1.0f, 1.0f};
    std::array<float, 4> out{};
    const Blend b = blend(p, index);
    for (size_t n = 0; n < b.count(); ++n)
        for (size_t c = 0; c < 4; ++c)
            out[c] += b.weight[n] * occlusion[b.probe[n]][c];
    for (float& c : out) // weights that sum to 1 in float can take a blend of 1s a rounding above it
        c = std::clamp(c, 0.0f, 1.0f);
    return out;
}

std::span<const uint32_t> ProbeIndex::near(const glm::vec3& p) const
{
    if (first.empty())
        return {};
    uint32_t c[3];
    for (int a = 0; a < 3; ++a)
    {
        const float f = (p[a] - lo[a]) / cell[a];
        if (!(f >= 0.0f && f < float(cells[a])))
            return {};
        c[a] = std::min(uint32_t(f), cells[a] - 1);
    }
    const size_t at = c[0] + size_t(cells.x) * (c[1] + size_t(cells.y) * c[2]);
    return std::span(probes).subspan(first[at], first[at + 1] - first[at]);
}

ProbeIndex index_probes(const LightProbes& probes)
{
    if (std::string problem = light_probes_problem(probes); !problem.empty())
        throw std::invalid_argument("hemi: index_probes: " + problem);
    ProbeIndex index;
    if (!probes.scattered())
        return index;
    // Over the valid probes' reach, cells as large as the median reach (so that a cell lists about as many
    // probes as a bump holds), fewer where that would make more than 8 cells a probe.
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    std::vector<float> reach;
    for (size_t i = 0; i < probes.size(); ++i)
        if (probes.valid[i])
        {
            const glm::vec4& q = probes.points[i];
            lo = glm::min(lo, glm::vec3(q) - q.w);
            hi = glm::max(hi, glm::vec3(q) + q.w);
            reach.push_back(q.w);
        }
    if (reach.empty())
        return index;
    std::nth_element(reach.begin(), reach.begin() + ptrdiff_t(reach.size() / 2), reach.end());
    float side = reach[reach.size() / 2];
    const glm::vec3 extent = hi - lo;
    const double most = 8.0 * double(reach.size()) + 64.0;
    for (;;)
    {
        const glm::dvec3 n = glm::max(glm::ceil(glm::dvec3(extent) / double(side)), glm::dvec3(1.0));
        if (n.x * n.y * n.z <= most)
        {
            index.cells = glm::uvec3(n);
            break;
        }
        side *= 1.25f;
    }
    index.lo = lo;
    index.cell = glm::max(extent / glm::vec3(index.cells), glm::vec3(1e-30f));
    const size_t cells = size_t(index.cells.x) * index.cells.y * index.cells.z;
    // Each probe into the cells its ball meets: counted, then placed (probe order within a cell).
    auto each_cell = [&](size_t i, auto&& f)
    {
        const glm::vec4& q = probes.points[i];
        const glm::vec3 c(q);
        glm::uvec3 a, b;
        for (int k = 0; k < 3; ++k)
        {
            a[k] = uint32_t(std::clamp(std::floor((c[k] - q.w - lo[k]) / index.cell[k]), 0.0f,
                                       float(index.cells[k] - 1)));
            b[k] = uint32_t(std::clamp(std::floor((c[k] + q.w - lo[k]) / index.cell[k]), 0.0f,
                                       float(index.cells[k] - 1)));
        }
        for (uint32_t z = a.z; z <= b.z; ++z)
            for (uint32_t y = a.y; y <= b.y; ++y)
                for (uint32_t x = a.x; x <= b.x; ++x)
                {
                    const glm::vec3 box_lo = lo + glm::vec3(x, y, z) * index.cell,
                                    box_hi = box_lo + index.cell;
                    const glm::vec3 d = c - glm::clamp(c, box_lo, box_hi);
                    if (d.x * d.x + d.y * d.y + d.z * d.z < q.w * q.w)
                        f(x + size_t(index.cells.x) * (y + size_t(index.cells.y) * z));
                }
    };
    index.first.assign(cells + 1, 0);
    for (size_t i = 0; i < probes.size(); ++i)
        if (probes.valid[i])
            each_cell(i, [&](size_t at) { ++index.first[at + 1]; });
    for (size_t c = 0; c < cells; ++c)
        index.first[c + 1] += index.first[c];
    index.probes.resize(index.first[cells]);
    std::vector<uint32_t> fill(index.first.begin(), index.first.end() - 1);
    for (size_t i = 0; i < probes.size(); ++i)
        if (probes.valid[i])
            each_cell(i, [&](size_t at) { index.probes[fill[at]++] = uint32_t(i); });
    return index;
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
    if (!p.points.empty())
    {
        if (p.points.size() != n || p.count.y != 1 || p.count.z != 1)
            return std::to_string(p.points.size()) + " scattered probes in a grid of " +
                   std::to_string(p.count.x) + "x" + std::to_string(p.count.y) + "x" +
                   std::to_string(p.count.z) + ", expected " + std::to_string(p.points.size()) + "x1x1";
        for (const glm::vec4& q : p.points)
            if (!finite3(glm::vec3(q)) || !(q.w > 0.0f) || !std::isfinite(q.w))
                return "a scattered probe's position is not finite or its reach not a positive finite number";
    }
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
    return 9 + (size_t(depth_resolution) * depth_resolution + 1) / 2;
}

std::vector<glm::vec4> probe_texels(const LightProbes& probes)
{
    if (std::string problem = light_probes_problem(probes); !problem.empty())
        throw std::invalid_argument("hemi: probe_texels: " + problem);
    const size_t stride = probe_texel_stride(probes.depth_resolution),
                 rr = size_t(probes.depth_resolution) * probes.depth_resolution;
    const ProbeIndex index = index_probes(probes);
    const size_t records = kProbeTexelHeader + probes.size() * stride, first_at = records,
                 list_at = first_at + (index.first.size() + 3) / 4,
                 total = probes.scattered() ? list_at + (index.probes.size() + 3) / 4 : records;
    constexpr size_t exact = size_t(1) << 24; // integers stored as floats
    if (total >= exact || index.probes.size() >= exact)
        throw std::invalid_argument("hemi: probe_texels: " + std::to_string(probes.size()) + " probes take " +
                                    std::to_string(total) + " texels, more than 2^24");
    std::vector<glm::vec4> out(total, glm::vec4(0.0f));
    out[0] = glm::vec4(probes.scattered() ? 1.0f : 0.0f, float(probes.depth_resolution), float(probes.size()),
                       float(stride));
    if (probes.scattered())
    {
        out[1] = glm::vec4(glm::vec3(index.cells), float(first_at));
        out[2] = glm::vec4(index.lo, float(list_at));
        out[3] = glm::vec4(index.cell, 0.0f);
        for (size_t i = 0; i < index.first.size(); ++i)
            out[first_at + i / 4][int(i % 4)] = float(index.first[i]);
        for (size_t i = 0; i < index.probes.size(); ++i)
            out[list_at + i / 4][int(i % 4)] = float(index.probes[i]);
    }
    else
    {
        out[1] = glm::vec4(glm::vec3(probes.count), 0.0f);
        out[2] = glm::vec4(probes.lo, 0.0f);
        out[3] = glm::vec4(probes.hi, 0.0f);
    }
    for (size_t p = 0; p < probes.size(); ++p)
    {
        glm::vec4* t = out.data() + kProbeTexelHeader + p * stride;
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
        t[8] = probes.scattered() ? probes.points[p] : glm::vec4(probes.position(p), 0.0f);
        for (size_t i = 0; i < rr && !probes.depth.empty(); ++i)
        {
            const glm::vec2 m = probes.depth[p * rr + i];
            glm::vec4& v = t[9 + i / 2];
            if (i % 2 == 0)
                v.x = m.x, v.y = m.y;
            else
                v.z = m.x, v.w = m.y;
        }
    }
    return out;
}

} // namespace hemi::io
