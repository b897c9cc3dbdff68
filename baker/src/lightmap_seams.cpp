#include <hemi/bake/lightmap_seams.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
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
    size_t triangle;        // its first index in mesh.indices
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
            edges[it->second].push_back({i, j, t});
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
        auto facing = [&](size_t t)
        {
            const glm::vec3 p = mesh.positions[mesh.indices[t]];
            return glm::cross(mesh.positions[mesh.indices[t + 1]] - p,
                              mesh.positions[mesh.indices[t + 2]] - p);
        };
        if (!(glm::dot(facing(a.triangle), facing(b.triangle)) > 0.0f))
            continue; // the two face opposite ways (a sliver folded back over its neighbour, as a patch's
                      // tessellation leaves them; a face and its back): no surface continues across it
        if (normals && (glm::dot(glm::normalize(mesh.normals[a.first]),
                                 glm::normalize(mesh.normals[b.first])) < cos_crease ||
                        glm::dot(glm::normalize(mesh.normals[a.second]),
                                 glm::normalize(mesh.normals[b.second])) < cos_crease))
            continue; // a crease
        bool frames_agree = true;
        if (mesh.tangents.size() == mesh.positions.size() && normals)
            for (const auto& [va, vb] : {std::pair{a.first, b.first}, std::pair{a.second, b.second}})
            {
                const glm::vec4 ta = mesh.tangents[va], tb = mesh.tangents[vb];
                const glm::vec3 n = glm::normalize(mesh.normals[va]);
                const glm::vec3 pa = glm::vec3(ta) - n * glm::dot(n, glm::vec3(ta)),
                                pb = glm::vec3(tb) - n * glm::dot(n, glm::vec3(tb));
                const float la = glm::length(pa), lb = glm::length(pb);
                if ((ta.w < 0.0f) != (tb.w < 0.0f) || !(la > 0.0f && lb > 0.0f) ||
                    glm::dot(pa, pb) < cos_crease * la * lb)
                    frames_agree = false;
            }
        seams.push_back({a0, a1, b0, b1, frames_agree});
    }
    return seams;
}

io::BlockGrid lightmap_seam_blocks(std::span<const LightmapSeam> seams, const io::BlockGrid& grid)
{
    const uint32_t B = io::BlockGrid::kSize, bx = grid.blocks_x();
    const int64_t w = grid.width(), h = grid.height();
    std::vector<uint8_t> keep(size_t(bx) * grid.blocks_y(), 0); // a byte a block (1/64 a texel)
    const glm::vec2 texels{float(w), float(h)};
    for (const LightmapSeam& s : seams)
        for (const auto& [p0, p1] : {std::pair{s.a0, s.a1}, std::pair{s.b0, s.b1}})
        {
            const int steps = 1 + int(std::ceil(4.0f * glm::length((p1 - p0) * texels)));
            for (int i = 0; i <= steps; ++i)
            {
                const io::BilinearFootprint f = io::bilinear_footprint(
                    p0 + (p1 - p0) * (float(i) / float(steps)), grid.width(), grid.height());
                for (int64_t y = std::max<int64_t>(0, f.y0 - 1); y <= std::min(h - 1, f.y1 + 1); ++y)
                    for (int64_t x = std::max<int64_t>(0, f.x0 - 1); x <= std::min(w - 1, f.x1 + 1); ++x)
                    {
                        const uint32_t block = uint32_t(y / B) * bx + uint32_t(x / B);
                        keep[block] = 1;
                    }
            }
        }
    std::vector<uint32_t> blocks;
    for (const uint32_t block : grid.blocks())
        if (keep[block])
            blocks.push_back(block);
    return io::BlockGrid(grid.width(), grid.height(), std::move(blocks));
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

namespace
{
// The parameters in (0, 1) where the segment p0 + (p1 - p0) t, in texel-centre coordinates, crosses a
// texel-grid line (an integer x or y): there its bilinear lookup changes from one quad of texels to the next.
void grid_crossings(glm::dvec2 p0, glm::dvec2 p1, std::vector<double>& out)
{
    for (int axis = 0; axis < 2; ++axis)
    {
        const double a = p0[axis], b = p1[axis];
        if (a == b)
            continue;
        for (double n = std::ceil(std::min(a, b)); n <= std::max(a, b); n += 1.0)
        {
            const double t = (n - a) / (b - a);
            if (t > 0.0 && t < 1.0)
                out.push_back(t);
        }
    }
}
} // namespace

struct LightmapSeamStitch::Impl
{
    uint32_t width = 0, height = 0;
    std::vector<uint32_t> blocks;
    std::vector<size_t> slots;
    Eigen::SparseMatrix<double> s; // the seam term S over the unknowns
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
};

LightmapSeamStitch::LightmapSeamStitch(std::span<const LightmapSeam> seams, const io::BlockGrid& grid,
                                       double closeness)
    : impl_(std::make_unique<Impl>())
{
    if (!(closeness > 0.0) || !std::isfinite(closeness))
        throw std::invalid_argument("seam stitching needs a positive closeness weight");
    Impl& m = *impl_;
    m.width = grid.width();
    m.height = grid.height();
    m.blocks = grid.blocks();
    const glm::dvec2 texels(m.width, m.height);
    // Every quadrature point of a seam: the (slot, weight) pairs of L_a - L_b there, and its weight. Walked
    // twice (the texels first, then the system), so that no list of every point is kept.
    struct Row
    {
        std::array<std::pair<int64_t, double>, 8> terms;
        double weight;
    };
    std::vector<double> cuts;
    const double gauss_t[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
    const double gauss_w[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    const auto rows_of = [&](const LightmapSeam& seam, auto&& use)
    {
        const glm::dvec2 a0 = glm::dvec2(seam.a0) * texels - 0.5, a1 = glm::dvec2(seam.a1) * texels - 0.5;
        const glm::dvec2 b0 = glm::dvec2(seam.b0) * texels - 0.5, b1 = glm::dvec2(seam.b1) * texels - 0.5;
        const double length = std::max(glm::length(a1 - a0), glm::length(b1 - b0));
        if (!(length > 0.0))
            return;
        cuts.assign({0.0, 1.0});
        grid_crossings(a0, a1, cuts);
        grid_crossings(b0, b1, cuts);
        std::sort(cuts.begin(), cuts.end());
        for (size_t c = 0; c + 1 < cuts.size(); ++c)
        {
            const double half = 0.5 * (cuts[c + 1] - cuts[c]), mid = 0.5 * (cuts[c + 1] + cuts[c]);
            if (!(half > 0.0))
                continue;
            for (int q = 0; q < 3; ++q)
            {
                const float t = float(mid + half * gauss_t[q]);
                const io::BilinearFootprint fa =
                    io::bilinear_footprint(seam.a0 + (seam.a1 - seam.a0) * t, m.width, m.height);
                const io::BilinearFootprint fb =
                    io::bilinear_footprint(seam.b0 + (seam.b1 - seam.b0) * t, m.width, m.height);
                Row row{};
                row.weight = gauss_w[q] * half * length;
                size_t term = 0;
                for (const auto& [f, sign] : {std::pair{fa, 1.0}, std::pair{fb, -1.0}})
                {
                    const double tx = f.tx, ty = f.ty;
                    row.terms[term++] = {grid.slot(f.x0, f.y0), sign * (1 - tx) * (1 - ty)};
                    row.terms[term++] = {grid.slot(f.x1, f.y0), sign * tx * (1 - ty)};
                    row.terms[term++] = {grid.slot(f.x0, f.y1), sign * (1 - tx) * ty};
                    row.terms[term++] = {grid.slot(f.x1, f.y1), sign * tx * ty};
                }
                use(row);
            }
        }
    };
    for (const LightmapSeam& seam : seams)
        rows_of(seam,
                [&](const Row& row)
                {
                    for (const auto& [slot, w] : row.terms)
                        if (slot >= 0 && w != 0.0)
                            m.slots.push_back(size_t(slot));
                });
    std::sort(m.slots.begin(), m.slots.end());
    m.slots.erase(std::unique(m.slots.begin(), m.slots.end()), m.slots.end());
    const auto unknown = [&](int64_t slot) {
        return Eigen::Index(std::lower_bound(m.slots.begin(), m.slots.end(), size_t(slot)) - m.slots.begin());
    };
    // S's entries, a seam at a time: its points share texels, so each seam's are summed before they join
    // the rest (a few dozen per seam instead of 64 per point).
    std::vector<Eigen::Triplet<double>> triplets, seam_triplets;
    for (const LightmapSeam& seam : seams)
    {
        seam_triplets.clear();
        rows_of(seam,
                [&](const Row& row)
                {
                    for (const auto& [si, wi] : row.terms)
                        if (si >= 0 && wi != 0.0)
                            for (const auto& [sj, wj] : row.terms)
                                if (sj >= 0 && wj != 0.0)
                                    seam_triplets.emplace_back(unknown(si), unknown(sj),
                                                               row.weight * wi * wj);
                });
        std::sort(seam_triplets.begin(), seam_triplets.end(),
                  [](const auto& x, const auto& y)
                  { return x.row() != y.row() ? x.row() < y.row() : x.col() < y.col(); });
        const size_t first = triplets.size();
        for (const Eigen::Triplet<double>& e : seam_triplets)
            if (triplets.size() > first && triplets.back().row() == e.row() &&
                triplets.back().col() == e.col())
                triplets.back() =
                    Eigen::Triplet<double>(e.row(), e.col(), triplets.back().value() + e.value());
            else
                triplets.push_back(e);
    }
    const Eigen::Index n = Eigen::Index(m.slots.size());
    m.s.resize(n, n);
    m.s.setFromTriplets(triplets.begin(), triplets.end());
    if (n == 0)
        return;
    Eigen::SparseMatrix<double> system = m.s;
    for (Eigen::Index i = 0; i < n; ++i)
        system.coeffRef(i, i) += closeness;
    m.solver.compute(system);
    if (m.solver.info() != Eigen::Success)
        throw std::runtime_error("seam stitching: the least-squares system could not be factored");
}

LightmapSeamStitch::~LightmapSeamStitch() = default;
LightmapSeamStitch::LightmapSeamStitch(LightmapSeamStitch&&) noexcept = default;
LightmapSeamStitch& LightmapSeamStitch::operator=(LightmapSeamStitch&&) noexcept = default;

const std::vector<size_t>& LightmapSeamStitch::slots() const
{
    return impl_->slots;
}

void LightmapSeamStitch::apply(io::BlockMaps& maps) const
{
    const Impl& m = *impl_;
    if (maps.width() != m.width || maps.height() != m.height || maps.grid.blocks() != m.blocks)
        throw std::invalid_argument("seam stitching: the maps are not on the grid the stitch was built for");
    const Eigen::Index n = Eigen::Index(m.slots.size());
    if (n == 0 || maps.k == 0)
        return;
    const Eigen::Index columns = Eigen::Index(maps.k) * 3;
    Eigen::MatrixXd x(n, columns);
    for (Eigen::Index i = 0; i < n; ++i)
        for (uint32_t k = 0; k < maps.k; ++k)
            for (int c = 0; c < 3; ++c)
                x(i, Eigen::Index(k) * 3 + c) =
                    double(maps.values[maps.index(k, m.slots[size_t(i)]) + size_t(c)]);
    const Eigen::MatrixXd rhs = -(m.s * x);
    const Eigen::MatrixXd d = m.solver.solve(rhs);
    for (Eigen::Index i = 0; i < n; ++i)
        for (uint32_t k = 0; k < maps.k; ++k)
            for (int c = 0; c < 3; ++c)
            {
                const double change = d(i, Eigen::Index(k) * 3 + c);
                if (change != 0.0)
                    maps.values[maps.index(k, m.slots[size_t(i)]) + size_t(c)] =
                        float(x(i, Eigen::Index(k) * 3 + c) + change);
            }
}

} // namespace hemi::bake
