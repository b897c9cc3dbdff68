// CPCA against constructed data whose exact compression is known, and its reported error against an
// independent reconstruction (the stored layout multiplied out here, not bake::reconstruct_cpca).
#include <hemi/bake/cpca.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>
#include <string>

namespace
{

// n points in d dimensions: cluster c (of `clusters`) is mean_c + a combination of `rank` random directions
// of its own; the points of cluster c are the indices i with i % clusters == c.
std::vector<float> subspace_data(uint32_t n, uint32_t d, uint32_t clusters, uint32_t rank, uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::normal_distribution<float> g;
    std::vector<std::vector<float>> means(clusters, std::vector<float>(d)),
        dirs(clusters * rank, std::vector<float>(d));
    for (auto& m : means)
        for (float& x : m)
            x = 10.0f * g(rng);
    for (auto& v : dirs)
        for (float& x : v)
            x = g(rng);
    std::vector<float> out(size_t(n) * d);
    for (uint32_t i = 0; i < n; ++i)
    {
        const uint32_t c = i % clusters;
        for (uint32_t e = 0; e < d; ++e)
            out[size_t(i) * d + e] = means[c][e];
        for (uint32_t r = 0; r < rank; ++r)
        {
            const float w = g(rng);
            for (uint32_t e = 0; e < d; ++e)
                out[size_t(i) * d + e] += w * dirs[c * rank + r][e];
        }
    }
    return out;
}

// Point i is mean[cluster[i]] + sum_v weights[i][v] * basis[cluster[i]][v] (io::PrtCpca's layout: means C x
// D, basis C x V x D, weights N x V), multiplied out here in double precision.
double reconstruction_rms(const hemi::io::PrtCpca& c, std::span<const float> x, uint32_t n, uint32_t d)
{
    EXPECT_EQ(c.cluster.size(), n);
    EXPECT_EQ(c.weights.size(), size_t(n) * c.vectors);
    EXPECT_EQ(c.means.size(), size_t(c.clusters) * d);
    EXPECT_EQ(c.basis.size(), size_t(c.clusters) * c.vectors * d);
    double sum = 0.0;
    for (uint32_t i = 0; i < n; ++i)
    {
        const size_t k = c.cluster[i];
        for (uint32_t e = 0; e < d; ++e)
        {
            double v = c.means[k * d + e];
            for (uint32_t j = 0; j < c.vectors; ++j)
                v += double(c.weights[size_t(i) * c.vectors + j]) * c.basis[(k * c.vectors + j) * d + e];
            sum += (v - x[size_t(i) * d + e]) * (v - x[size_t(i) * d + e]);
        }
    }
    return std::sqrt(sum / (double(n) * d));
}

// compress_cpca(x, n, d, clusters, vectors) throws std::invalid_argument whose message contains `part`.
void expect_refused(std::span<const float> x, uint32_t n, uint32_t d, uint32_t clusters, uint32_t vectors,
                    const std::string& part)
{
    try
    {
        hemi::bake::compress_cpca(x, n, d, clusters, vectors);
        ADD_FAILURE() << "accepted; expected a refusal naming '" << part << "'";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
}

} // namespace

// Data of rank 5 around one mean: 5 PCA vectors reproduce it (to float precision); 3 do not.
TEST(Cpca, OneClusterOfRankVIsExact)
{
    const uint32_t n = 400, d = 36;
    const std::vector<float> x = subspace_data(n, d, 1, 5, 1);
    const hemi::io::PrtCpca exact = hemi::bake::compress_cpca(x, n, d, 1, 5);
    EXPECT_LT(reconstruction_rms(exact, x, n, d), 1e-4);
    EXPECT_LT(exact.rms_error, 1e-4);
    const hemi::io::PrtCpca lossy = hemi::bake::compress_cpca(x, n, d, 1, 3);
    const double rms = reconstruction_rms(lossy, x, n, d);
    EXPECT_GT(rms, 0.05);
    EXPECT_NEAR(lossy.rms_error, rms, 1e-4 * rms + 1e-6) << "the reported error is the reconstruction's";
}

// Three clusters, each its own rank-2 subspace around a far-apart mean: 3 x 2 CPCA separates them exactly
// (every point of a generating cluster lands in one CPCA cluster) and reconstructs everything; 1 x 2 cannot.
TEST(Cpca, ClustersFindTheGeneratingSubspaces)
{
    const uint32_t n = 600, d = 25;
    const std::vector<float> x = subspace_data(n, d, 3, 2, 7);
    const hemi::io::PrtCpca c = hemi::bake::compress_cpca(x, n, d, 3, 2);
    EXPECT_LT(reconstruction_rms(c, x, n, d), 1e-3);
    for (uint32_t i = 3; i < n; ++i)
        EXPECT_EQ(c.cluster[i], c.cluster[i % 3]) << i;
    EXPECT_NE(c.cluster[0], c.cluster[1]);
    EXPECT_NE(c.cluster[1], c.cluster[2]);
    EXPECT_NE(c.cluster[0], c.cluster[2]);
    const hemi::io::PrtCpca one = hemi::bake::compress_cpca(x, n, d, 1, 2);
    EXPECT_GT(reconstruction_rms(one, x, n, d), 1.0);
}

// Each bad input is refused with a message naming the problem.
TEST(Cpca, RejectsBadInput)
{
    std::vector<float> x(10 * 4, 1.0f);
    expect_refused(x, 10, 5, 1, 2, "CPCA expects 50 values, got 40");
    expect_refused(x, 10, 4, 0, 2, "cluster count 0 is not in [1, 10]");
    expect_refused(x, 10, 4, 11, 2, "cluster count 11 is not in [1, 10]");
    expect_refused(x, 10, 4, 1, 0, "at least one PCA vector");
    x[7] = NAN;
    expect_refused(x, 10, 4, 1, 2, "non-finite value");
}
