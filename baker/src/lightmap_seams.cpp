#include <hemi/bake/lightmap_seams.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <tuple>

namespace hemi::bake
{

namespace
{
// A position's bits, for exact comparison and ordering.
using PositionKey = std::array<uint32_t, 3>;
PositionKey key_of(const glm::vec3& p)
{
    PositionKey k;
    std::memcpy(k.data(), &p, sizeof k);
    return k;
}

struct EdgeSide
{
    uint32_t first, second; // vertex indices, `first` at the edge key's smaller end
};
} // namespace

std::vector<LightmapSeam> find_lightmap_seams(const io::Mesh& mesh, float crease_degrees)
{
    if (mesh.uvs1.size() != mesh.positions.size())
        throw std::invalid_argument("lightmap seams need lightmap UVs (TEXCOORD_1) at every vertex");
    const bool normals = mesh.normals.size() == mesh.positions.size();
    const float cos_crease = std::cos(crease_degrees * float(M_PI) / 180.0f);
    // Every edge by its two ends' positions (the smaller key first), with the sides that have it, in the
    // order the edges are first met.
    std::map<std::pair<PositionKey, PositionKey>, size_t> index;
    std::vector<std::vector<EdgeSide>> edges;
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
        for (int e = 0; e < 3; ++e)
        {
            uint32_t i = mesh.indices[t + size_t(e)], j = mesh.indices[t + size_t((e + 1) % 3)];
            PositionKey ki = key_of(mesh.positions[i]), kj = key_of(mesh.positions[j]);
            if (ki == kj)
                continue; // degenerate
            if (kj < ki)
            {
                std::swap(i, j);
                std::swap(ki, kj);
            }
            const auto [it, added] = index.emplace(std::pair{ki, kj}, edges.size());
            if (added)
                edges.emplace_back();
            edges[it->second].push_back({i, j});
        }
    std::vector<LightmapSeam> seams;
    for (const std::vector<EdgeSide>& sides : edges)
    {
        if (sides.size() != 2)
            continue; // a boundary, or three or more triangles
        const EdgeSide& a = sides[0];
        const EdgeSide& b = sides[1];
        const glm::vec2 a0 = mesh.uvs1[a.first], a1 = mesh.uvs1[a.second], b0 = mesh.uvs1[b.first],
                        b1 = mesh.uvs1[b.second];
        if (a0 == b0 && a1 == b1)
            continue; // one chart on both sides
        if (normals && (glm::dot(glm::normalize(mesh.normals[a.first]),
                                 glm::normalize(mesh.normals[b.first])) < cos_crease ||
                        glm::dot(glm::normalize(mesh.normals[a.second]),
                                 glm::normalize(mesh.normals[b.second])) < cos_crease))
            continue; // a crease
        seams.push_back({a0, a1, b0, b1});
    }
    return seams;
}

LightmapSeamMetric measure_lightmap_seams(std::span<const LightmapSeam> seams, const io::BlockMaps& maps)
{
    LightmapSeamMetric m;
    m.seams = seams.size();
    std::vector<double> differences;
    double scale = 0.0;
    const glm::vec2 texels(float(maps.width()), float(maps.height()));
    for (const LightmapSeam& s : seams)
    {
        const float length =
            std::max(glm::length((s.a1 - s.a0) * texels), glm::length((s.b1 - s.b0) * texels));
        const int points = std::max(2, int(std::ceil(length)));
        for (int p = 0; p < points; ++p)
        {
            const float t = (float(p) + 0.5f) / float(points);
            const glm::vec2 ua = s.a0 + (s.a1 - s.a0) * t, ub = s.b0 + (s.b1 - s.b0) * t;
            ++m.points;
            for (uint32_t k = 0; k < maps.k; ++k)
            {
                const glm::vec3 va = maps.bilinear(k, ua), vb = maps.bilinear(k, ub);
                for (int c = 0; c < 3; ++c)
                {
                    differences.push_back(std::abs(double(va[c]) - double(vb[c])));
                    scale += 0.5 * (std::abs(double(va[c])) + std::abs(double(vb[c])));
                }
            }
        }
    }
    if (differences.empty() || !(scale > 0.0))
        return m;
    scale /= double(differences.size());
    double sum = 0.0;
    for (const double d : differences)
        sum += d;
    m.mean = sum / double(differences.size()) / scale;
    const size_t at =
        std::min(differences.size() - 1, size_t(std::ceil(0.95 * double(differences.size()))) - 1);
    std::nth_element(differences.begin(), differences.begin() + std::ptrdiff_t(at), differences.end());
    m.p95 = differences[at] / scale;
    return m;
}

} // namespace hemi::bake
