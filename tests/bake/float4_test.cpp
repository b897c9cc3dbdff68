// The bake's four-lane exp and log (hemi/bake/float4.h), against double's std::exp and std::log.
#include <hemi/bake/float4.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace
{
using hemi::bake::f32x4;

// |value - reference| in units of the last place of a float the size of the reference.
double ulps(float value, double reference)
{
    return std::abs(double(value) - reference) / std::ldexp(1.0, std::ilogb(reference) - 23);
}
} // namespace

TEST(Float4, ExpOfNonPositiveValuesIsWithinOneUlpAndZeroBelowFloatsRange)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> linear(-87.0f, 0.0f), exponent(-60.0f, 4.4f);
    double worst = 0.0;
    for (int i = 0; i < 250000; ++i)
    {
        // Four values a call, each lane its own: uniform over the range, and small ones by their logarithm.
        const f32x4 x = {linear(rng), -std::exp(exponent(rng)), linear(rng), -std::exp(exponent(rng))};
        const f32x4 e = hemi::bake::exp_nonpositive(x);
        for (int lane = 0; lane < 4; ++lane)
            worst = std::max(worst, ulps(e[lane], std::exp(double(x[lane]))));
    }
    EXPECT_LE(worst, 1.0);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const f32x4 edges = hemi::bake::exp_nonpositive(f32x4{0.0f, -0.0f, -87.0f, -1e-30f});
    EXPECT_EQ(edges[0], 1.0f);
    EXPECT_EQ(edges[1], 1.0f);
    EXPECT_LE(ulps(edges[2], std::exp(-87.0)), 1.0);
    EXPECT_EQ(edges[3], 1.0f);
    const f32x4 beyond = hemi::bake::exp_nonpositive(f32x4{-87.5f, -1000.0f, -inf, nan});
    for (int lane = 0; lane < 4; ++lane)
        EXPECT_EQ(beyond[lane], 0.0f) << lane;
    const f32x4 positive =
        hemi::bake::exp_nonpositive(f32x4{1e-30f, 1.0f, 1000.0f, inf}); // outside its range
    for (int lane = 0; lane < 4; ++lane)
        EXPECT_EQ(positive[lane], 1.0f) << lane;
}

TEST(Float4, LogOfPositiveValuesIsWithinOneUlpAndZeroAtOne)
{
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> exponent(-87.0f, 88.0f), near(-16.6f, -0.1f);
    double worst = 0.0;
    for (int i = 0; i < 250000; ++i)
    {
        // Over float's normal range by the logarithm, and just below and above 1, where ln x is small.
        const f32x4 x = {std::exp(exponent(rng)), 1.0f - std::exp(near(rng)), 1.0f + std::exp(near(rng)),
                         std::exp(exponent(rng))};
        const f32x4 l = hemi::bake::log_positive(x);
        for (int lane = 0; lane < 4; ++lane)
        {
            ASSERT_GE(x[lane], std::numeric_limits<float>::min());
            if (x[lane] != 1.0f)
                worst = std::max(worst, ulps(l[lane], std::log(double(x[lane]))));
        }
    }
    EXPECT_LE(worst, 1.0);
    const f32x4 edges = hemi::bake::log_positive(
        f32x4{1.0f, std::numeric_limits<float>::min(), std::numeric_limits<float>::max(), 0.5f});
    EXPECT_EQ(edges[0], 0.0f);
    EXPECT_LE(ulps(edges[1], std::log(double(std::numeric_limits<float>::min()))), 1.0);
    EXPECT_LE(ulps(edges[2], std::log(double(std::numeric_limits<float>::max()))), 1.0);
    EXPECT_LE(ulps(edges[3], std::log(0.5)), 1.0);
}
