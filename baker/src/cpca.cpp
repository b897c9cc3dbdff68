#include <hemi/bake/cpca.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

namespace
{
using RowMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct ClusterFit
{
    Eigen::VectorXf mean;
    Eigen::MatrixXf basis; // D x V, orthonormal columns, largest variance first
};

ClusterFit fit(const Eigen::Map<const RowMatrix>& x, const std::vector<uint32_t>& members, uint32_t d,
               uint32_t v)
{
    ClusterFit f;
    f.mean = Eigen::VectorXf::Zero(d);
    f.basis = Eigen::MatrixXf::Zero(d, v);
    if (members.empty())
        return f;
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(d);
    for (uint32_t i : members)
        mean += x.row(i).transpose().cast<double>();
    mean /= double(members.size());
    Eigen::MatrixXd centred(members.size(), d);
    for (size_t r = 0; r < members.size(); ++r)
        centred.row(Eigen::Index(r)) = x.row(members[r]).cast<double>() - mean.transpose();
    const Eigen::MatrixXd covariance = centred.transpose() * centred;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
    // Eigenvalues ascend: the last V columns, reversed, are the principal directions.
    for (uint32_t j = 0; j < v; ++j)
    {
        Eigen::VectorXd column = solver.eigenvectors().col(Eigen::Index(d - 1 - j));
        // Deterministic sign: the largest-magnitude component positive.
        Eigen::Index largest;
        column.cwiseAbs().maxCoeff(&largest);
        if (column(largest) < 0)
            column = -column;
        f.basis.col(j) = column.cast<float>();
    }
    f.mean = mean.cast<float>();
    return f;
}

// Squared reconstruction error of x by a cluster (x - mean minus its projection on the orthonormal basis).
float residual(const Eigen::VectorXf& x, const ClusterFit& f)
{
    const Eigen::VectorXf c = x - f.mean;
    return (c - f.basis * (f.basis.transpose() * c))
        .squaredNorm(); // no cancellation, unlike |c|^2 - |B^T c|^2
}
} // namespace

io::PrtCpca compress_cpca(std::span<const float> matrices, uint32_t n, uint32_t d, uint32_t clusters,
                          uint32_t vectors, int iterations)
{
    if (n == 0 || d == 0 || matrices.size() != size_t(n) * d)
        throw std::invalid_argument("hemi: CPCA expects " + std::to_string(size_t(n) * d) + " values, got " +
                                    std::to_string(matrices.size()));
    if (clusters == 0 || clusters > n)
        throw std::invalid_argument("hemi: CPCA cluster count " + std::to_string(clusters) +
                                    " is not in [1, " + std::to_string(n) + "]");
    if (vectors == 0)
        throw std::invalid_argument("hemi: CPCA needs at least one PCA vector per cluster");
    for (float value : matrices)
        if (!std::isfinite(value))
            throw std::invalid_argument("hemi: CPCA input has a non-finite value");
    vectors = std::min(vectors, d);
    const Eigen::Map<const RowMatrix> x(matrices.data(), n, d);

    // Farthest-point seeding from vertex 0: deterministic and spreads the clusters over the data.
    std::vector<uint32_t> assignment(n, 0);
    {
        std::vector<uint32_t> seeds = {0};
        std::vector<float> distance(n, std::numeric_limits<float>::max());
        while (seeds.size() < clusters)
        {
            const auto s = x.row(seeds.back());
            uint32_t farthest = 0;
            for (uint32_t i = 0; i < n; ++i)
            {
                const float dist = (x.row(i) - s).squaredNorm();
                if (dist < distance[i])
                {
                    distance[i] = dist;
                    assignment[i] = uint32_t(seeds.size() - 1);
                }
                if (distance[i] > distance[farthest])
                    farthest = i;
            }
            seeds.push_back(farthest);
        }
        const auto s = x.row(seeds.back());
        for (uint32_t i = 0; i < n; ++i)
            if ((x.row(i) - s).squaredNorm() < distance[i])
                assignment[i] = uint32_t(seeds.size() - 1);
    }

    std::vector<ClusterFit> fits(clusters);
    for (int it = 0; it < std::max(1, iterations); ++it)
    {
        std::vector<std::vector<uint32_t>> members(clusters);
        for (uint32_t i = 0; i < n; ++i)
            members[assignment[i]].push_back(i);
        for (uint32_t c = 0; c < clusters; ++c)
            fits[c] = fit(x, members[c], d, vectors);
        if (clusters == 1)
            break;
        bool moved = false;
        for (uint32_t i = 0; i < n; ++i)
        {
            const Eigen::VectorXf xi = x.row(i).transpose();
            uint32_t best = assignment[i];
            float best_error = residual(xi, fits[best]);
            for (uint32_t c = 0; c < clusters; ++c)
            {
                if (members[c].empty())
                    continue;
                const float e = residual(xi, fits[c]);
                if (e < best_error)
                {
                    best_error = e;
                    best = c;
                }
            }
            moved = moved || best != assignment[i];
            assignment[i] = best;
        }
        // A cluster left without members is re-seeded with the vertex reconstructed worst.
        std::vector<uint32_t> counts(clusters, 0);
        for (uint32_t a : assignment)
            ++counts[a];
        for (uint32_t c = 0; c < clusters; ++c)
            if (counts[c] == 0)
            {
                uint32_t worst = 0;
                float worst_error = -1.0f;
                for (uint32_t i = 0; i < n; ++i)
                {
                    if (counts[assignment[i]] <= 1)
                        continue;
                    const float e = residual(x.row(i).transpose(), fits[assignment[i]]);
                    if (e > worst_error)
                    {
                        worst_error = e;
                        worst = i;
                    }
                }
                if (worst_error >= 0.0f)
                {
                    --counts[assignment[worst]];
                    assignment[worst] = c;
                    counts[c] = 1;
                    moved = true;
                }
            }
        if (!moved)
            break;
        if (it + 1 == std::max(1, iterations))
        {
            // The last reassignment needs its fits.
            std::vector<std::vector<uint32_t>> final_members(clusters);
            for (uint32_t i = 0; i < n; ++i)
                final_members[assignment[i]].push_back(i);
            for (uint32_t c = 0; c < clusters; ++c)
                fits[c] = fit(x, final_members[c], d, vectors);
        }
    }

    io::PrtCpca out;
    out.clusters = clusters;
    out.vectors = vectors;
    out.means.resize(size_t(clusters) * d);
    out.basis.resize(size_t(clusters) * vectors * d);
    for (uint32_t c = 0; c < clusters; ++c)
    {
        std::copy(fits[c].mean.data(), fits[c].mean.data() + d, out.means.begin() + ptrdiff_t(c) * d);
        for (uint32_t j = 0; j < vectors; ++j)
            for (uint32_t e = 0; e < d; ++e)
                out.basis[(size_t(c) * vectors + j) * d + e] = fits[c].basis(e, j);
    }
    out.cluster = assignment;
    out.weights.resize(size_t(n) * vectors);
    double squared = 0.0;
    for (uint32_t i = 0; i < n; ++i)
    {
        const ClusterFit& f = fits[assignment[i]];
        const Eigen::VectorXf centred = x.row(i).transpose() - f.mean;
        const Eigen::VectorXf w = f.basis.transpose() * centred;
        std::copy(w.data(), w.data() + vectors, out.weights.begin() + ptrdiff_t(i) * vectors);
        squared += double((centred - f.basis * w).squaredNorm());
    }
    out.rms_error = float(std::sqrt(squared / (double(n) * d)));
    return out;
}

void reconstruct_cpca(const io::PrtCpca& cpca, uint32_t d, uint32_t vertex, std::span<float> out)
{
    const uint32_t c = cpca.cluster.at(vertex);
    for (uint32_t e = 0; e < d; ++e)
    {
        float value = cpca.means[size_t(c) * d + e];
        for (uint32_t j = 0; j < cpca.vectors; ++j)
            value += cpca.weights[size_t(vertex) * cpca.vectors + j] *
                     cpca.basis[(size_t(c) * cpca.vectors + j) * d + e];
        out[e] = value;
    }
}

} // namespace hemi::bake
