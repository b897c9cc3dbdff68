// CPCA against constructed data whose exact compression is known, and its reported error against an
// independent reconstruction.
#include <hemi/bake/cpca.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace
{

// n points in d dimensions: cluster c (of `clusters`) is mean_c + a combination of `rank` random directions
// of its own; the points of cluster c are the indices i with i % clusters == c.
std::vector<float> subspace_data(uint32_t n, uint32_t d, uint32_t clusters, uint32_t rank, uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::normal_distribution<float> g;
    std::vector<std::vector<float>> means(clusters, std::vector<float>(d)), dirs(clusters * rank, std::vector<float>(d));
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

double reconstruction_rms(const hemi::io::PrtCpca& c, std::span<const float> x, uint32_t n, uint32_t d)
{
    std::vector<float> row(d);
    double sum = 0.0;
    for (uint32_t i = 0; i < n; ++i)
    {
        hemi::bake::reconstruct_cpca(c, d, i, row);
        for (uint32_t e = 0; e < d; ++e)
            sum += double(row[e] - x[size_t(i) * d + e]) * (row[e] - x[size_t(i) * d + e]);
    }
    return std::sqrt(sum / (double(n) * d));
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

TEST(Cpca, RejectsBadInput)
{
    std::vector<float> x(10 * 4, 1.0f);
    EXPECT_THROW(hemi::bake::compress_cpca(x, 10, 5, 1, 2), std::invalid_argument); // size mismatch
    EXPECT_THROW(hemi::bake::compress_cpca(x, 10, 4, 0, 2), std::invalid_argument);
    EXPECT_THROW(hemi::bake::compress_cpca(x, 10, 4, 11, 2), std::invalid_argument);
    EXPECT_THROW(hemi::bake::compress_cpca(x, 10, 4, 1, 0), std::invalid_argument);
    x[7] = NAN;
    EXPECT_THROW(hemi::bake::compress_cpca(x, 10, 4, 1, 2), std::invalid_argument);
}
