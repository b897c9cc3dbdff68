// The PRT transfer pass (device) and the host path against a plain triple loop over the row-major input.
#include "../gpu_fixture.h"

#include <hemi/render/transfer.h>

#include <cmath>
#include <random>

using hemi::render::TransferMatrices;
using hemi::render::TransferPass;

namespace
{

struct Case
{
    uint32_t n, k, l;
};

std::vector<float> random_values(size_t count, uint32_t seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
    std::vector<float> v(count);
    for (float& x : v)
        x = dist(rng);
    return v;
}

// c_v[k] = sum_j T_v[k][j] * l[j], in double: the reference both paths are held to.
std::vector<double> reference(const std::vector<float>& t, const std::vector<glm::vec3>& light, const Case& c)
{
    std::vector<double> out(size_t(c.n) * c.k * 3);
    for (uint32_t v = 0; v < c.n; ++v)
        for (uint32_t k = 0; k < c.k; ++k)
            for (int ch = 0; ch < 3; ++ch)
            {
                double sum = 0;
                for (uint32_t j = 0; j < c.l; ++j)
                    sum += double(t[(size_t(v) * c.k + k) * c.l + j]) * light[j][ch];
                out[(size_t(v) * c.k + k) * 3 + ch] = sum;
            }
    return out;
}

// Relative error against the magnitude of the terms (the sum can cancel to ~0).
void expect_matches(const std::vector<float>& got, const std::vector<double>& ref,
                    const std::vector<float>& t, const std::vector<glm::vec3>& light, const Case& c,
                    const char* path)
{
    ASSERT_EQ(got.size(), size_t(c.n) * c.k * 4);
    int failures = 0;
    for (uint32_t v = 0; v < c.n && failures < 5; ++v)
        for (uint32_t k = 0; k < c.k; ++k)
            for (int ch = 0; ch < 3; ++ch)
            {
                double scale = 0;
                for (uint32_t j = 0; j < c.l; ++j)
                    scale += std::abs(double(t[(size_t(v) * c.k + k) * c.l + j]) * light[j][ch]);
                double r = ref[(size_t(v) * c.k + k) * 3 + ch];
                double g = got[(size_t(v) * c.k + k) * 4 + ch];
                if (std::abs(g - r) > 1e-5 * scale)
                {
                    ADD_FAILURE() << path << " N=" << c.n << " K=" << c.k << " L=" << c.l << " vertex " << v
                                  << " coefficient " << k << " channel " << ch << ": got " << g
                                  << ", expected " << r << " (relative error " << std::abs(g - r) / scale
                                  << ")";
                    ++failures;
                }
            }
    for (uint32_t v = 0; v < c.n; ++v)
        for (uint32_t k = 0; k < c.k; ++k)
            ASSERT_EQ(got[(size_t(v) * c.k + k) * 4 + 3], 0.0f) << path << ": alpha of coefficient texel";
}

class TransferPassTest : public hemi::test::GpuTest
{
};

} // namespace

TEST_F(TransferPassTest, DeviceAndHostEqualReferenceForEveryShape)
{
    // Sizes that are not multiples of the 32-vertex block, the 4-vertex invocation or the 64-wide workgroup.
    const uint32_t sizes[] = {1, 5, 33, 301, 1031};
    uint32_t seed = 1;
    for (uint32_t k : {3u, 4u, 6u, 9u})
        for (uint32_t l : {9u, 16u, 25u, 36u})
            for (uint32_t n : sizes)
            {
                Case c{n, k, l};
                std::vector<float> t = random_values(size_t(n) * k * l, seed++);
                std::vector<float> lv = random_values(size_t(l) * 3, seed++);
                std::vector<glm::vec3> light(l);
                for (uint32_t j = 0; j < l; ++j)
                    light[j] = {lv[j * 3], lv[j * 3 + 1], lv[j * 3 + 2]};
                std::vector<double> ref = reference(t, light, c);

                TransferMatrices m(n, k, l, t);
                std::vector<float> host(size_t(n) * k * 4);
                hemi::render::transfer_multiply_host(m, light, host);
                expect_matches(host, ref, t, light, c, "host");

                TransferPass pass(hemi::test::device(), m);
                pass.run(light);
                expect_matches(pass.read_coefficients(), ref, t, light, c, "device");
            }
}

// Sets beyond one texel-buffer view (2^27 texels on lavapipe, 2 GiB) are split into segments, one view
// pair and one dispatch each. Force small views so that the segment arithmetic (view offsets, per-segment
// vertex counts, the partial last segment) is exercised at test sizes.
TEST_F(TransferPassTest, SegmentedSetsEqualReference)
{
    Case c{1000, 9, 25};
    std::vector<float> t = random_values(size_t(c.n) * c.k * c.l, 11);
    std::vector<float> lv = random_values(size_t(c.l) * 3, 12);
    std::vector<glm::vec3> light(c.l);
    for (uint32_t j = 0; j < c.l; ++j)
        light[j] = {lv[j * 3], lv[j * 3 + 1], lv[j * 3 + 2]};
    TransferMatrices m(c.n, c.k, c.l, t);
    // One block is 9*25*8 = 1800 texels; 2 * 1800 = 3600 texels per view -> 2 blocks per segment -> 16
    // segments.
    TransferPass pass(hemi::test::device(), m, 3600);
    EXPECT_EQ(pass.segment_count(), 16u);
    pass.run(light);
    expect_matches(pass.read_coefficients(), reference(t, light, c), t, light, c, "segmented device");
}

TEST_F(TransferPassTest, LightingChangesBetweenRunsAreSeen)
{
    Case c{70, 9, 25};
    std::vector<float> t = random_values(size_t(c.n) * c.k * c.l, 7);
    TransferMatrices m(c.n, c.k, c.l, t);
    TransferPass pass(hemi::test::device(), m);
    for (int frame = 0; frame < 3; ++frame)
    {
        std::vector<glm::vec3> light(c.l, glm::vec3(0.0f));
        light[frame] = glm::vec3(1.0f, 2.0f, 3.0f); // picks column `frame` of every matrix
        pass.run(light);
        std::vector<float> got = pass.read_coefficients();
        for (uint32_t v = 0; v < c.n; v += 13)
            for (uint32_t k = 0; k < c.k; ++k)
            {
                float expect = t[(size_t(v) * c.k + k) * c.l + frame];
                EXPECT_NEAR(got[(size_t(v) * c.k + k) * 4 + 2], 3.0f * expect, 1e-6f) << "frame " << frame;
            }
    }
}

TEST(TransferMatricesTest, StoresElementInterleavedBlocks)
{
    // Layout contract of hemi/shared/transfer.h: element f of vertex v at block(v)*K*L*32 + f*32 + v%32.
    std::vector<float> t(40 * 3 * 9);
    for (size_t i = 0; i < t.size(); ++i)
        t[i] = float(i);
    TransferMatrices m(40, 3, 9, t);
    EXPECT_EQ(m.block_count(), 2u);
    EXPECT_EQ(m.data().size(), 2u * 3 * 9 * 32);
    EXPECT_EQ(m.data()[0 * 32 + 1], t[1 * 27 + 0]);
    EXPECT_EQ(m.data()[5 * 32 + 31], t[31 * 27 + 5]);
    EXPECT_EQ(m.data()[27 * 32 + 26 * 32 + 7], t[39 * 27 + 26]);
    EXPECT_EQ(m.data()[27 * 32 + 26 * 32 + 8], 0.0f); // padding vertex 40
    EXPECT_EQ(m.at(39, 2, 8), t[39 * 27 + 26]);
}

namespace
{
// Runs `f`, which must throw std::invalid_argument whose message contains `naming` (the problem, stated).
template <class F> void expect_invalid_argument_naming(F&& f, const std::string& naming)
{
    try
    {
        f();
        ADD_FAILURE() << "no exception; expected one naming '" << naming << "'";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find(naming), std::string::npos) << "message: " << e.what();
    }
}
} // namespace

// Each bad shape is refused with a message that names what is wrong, not only with the exception's type.
TEST(TransferMatricesTest, RejectsBadShapes)
{
    std::vector<float> t(10 * 9 * 25, 0.0f);
    expect_invalid_argument_naming([&] { TransferMatrices(0, 9, 25, {}); }, "zero vertices");
    expect_invalid_argument_naming(
        [&] { TransferMatrices(10, 9, 25, std::span<const float>(t).first(t.size() - 1)); },
        "expected 2250 floats");
    expect_invalid_argument_naming([&] { TransferMatrices(10, 10, 25, t); }, "K = 10");
    expect_invalid_argument_naming([&] { TransferMatrices(10, 9, 24, t); }, "L = 24");
    expect_invalid_argument_naming([&] { TransferMatrices(10, 0, 25, t); }, "K = 0");
    expect_invalid_argument_naming([&] { TransferMatrices(10, 9, 25, std::span<const float>(t).first(100)); },
                                   "expected 2250 floats");
}

TEST(TransferMatricesTest, RejectsNaN)
{
    std::vector<float> t(10 * 4 * 9, 0.0f);
    t[5 * 36 + 3] = std::nanf("");
    try
    {
        TransferMatrices(10, 4, 9, t);
        FAIL();
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("vertex 5, element 3"), std::string::npos) << e.what();
    }
}

TEST_F(TransferPassTest, RejectsMismatchedLightingAndOutput)
{
    std::vector<float> t(33 * 4 * 9, 0.5f);
    TransferMatrices m(33, 4, 9, t);
    std::vector<glm::vec3> wrong(16, glm::vec3(1.0f)), right(9, glm::vec3(1.0f));
    std::vector<float> out(33 * 4 * 4), short_out(10);
    expect_invalid_argument_naming([&] { hemi::render::transfer_multiply_host(m, wrong, out); },
                                   "lighting has 16");
    expect_invalid_argument_naming([&] { hemi::render::transfer_multiply_host(m, right, short_out); },
                                   "output has 10 floats");
    TransferPass pass(hemi::test::device(), m);
    expect_invalid_argument_naming([&] { pass.run(wrong); }, "lighting has 16");
    // NaN lighting, on the host path and on the device path.
    right[3].y = std::nanf("");
    expect_invalid_argument_naming([&] { hemi::render::transfer_multiply_host(m, right, out); },
                                   "non-finite");
    expect_invalid_argument_naming([&] { pass.run(right); }, "non-finite");
}
