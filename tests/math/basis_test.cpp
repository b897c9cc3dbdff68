// Hemispherical bases against the numbers printed in Sloan 2006 and Habel & Wimmer 2010, orthonormality on
// the hemisphere, and the GLSL twins against the C++ evaluation on the GPU.
#include "../gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>
#include <hemi/math/basis.h>
#include <hemi/math/separable_basis.h>
#include <hemi/math/sh.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <random>

using namespace hemi::math;

namespace
{
const double kSqrtPi = std::sqrt(M_PI);

void expect_matrix(const std::vector<double>& got, const std::vector<double>& want, int rows, double tol,
                   const char* what)
{
    ASSERT_EQ(got.size(), size_t(rows) * 9);
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < 9; ++j)
            EXPECT_NEAR(got[i * 9 + j], want[i * 9 + j], tol) << what << " row " << i << " column " << j;
}

// Rounds to `digits` significant digits, the way the papers print their tables.
double round_significant(double x, int digits)
{
    if (x == 0.0)
        return 0.0;
    double scale = std::pow(10.0, digits - 1 - int(std::floor(std::log10(std::abs(x)))));
    return std::round(x * scale) / scale;
}
} // namespace

TEST(Bases, OrthonormalOnTheHemisphere)
{
    for (const BasisDesc& b : bases())
    {
        if (!b.orthonormal)
            continue;
        std::vector<double> g = gram_matrix(b);
        for (int i = 0; i < b.size; ++i)
            for (int k = 0; k < b.size; ++k)
                EXPECT_NEAR(g[i * b.size + k], i == k ? 1.0 : 0.0, 1e-6)
                    << b.name << " <b" << i << ", b" << k << ">";
    }
}

// Koenderink et al.'s hemispherical Zernike polynomials in their polar closed form, typed here from the
// disk's definition rather than zernike.cpp's Cartesian one: the direction at (theta, phi) sits at radius rho
// = sqrt(1 - cos theta) on the unit disk (the equal-area map, d(omega) = 2 rho d(rho) d(phi)), and Z_n^m =
// N_nm R_n^|m|(rho) cos(m phi) (sin for m < 0) with R_0^0 = 1, R_1^1 = rho, R_2^0 = 2 rho^2 - 1, R_2^2 =
// rho^2, normalised on the hemisphere by N = sqrt((n + 1) / (2 pi)) for m = 0 and sqrt((n + 1) / pi)
// otherwise. zernike3 is the first three, zernike6 all six, in the order (0,0), (1,1), (1,-1), (2,0), (2,2),
// (2,-2).
TEST(BasisZernike, EqualsThePolarClosedForm)
{
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 500; ++i)
    {
        // Uniform on the hemisphere, plus the pole and the horizon.
        const double cos_theta = i == 0 ? 1.0 : i == 1 ? 0.0 : u(rng), phi = 2.0 * M_PI * u(rng);
        const double sin_theta = std::sqrt(1.0 - cos_theta * cos_theta), rho = std::sqrt(1.0 - cos_theta);
        const double want[6] = {std::sqrt(1.0 / (2.0 * M_PI)),
                                std::sqrt(2.0 / M_PI) * rho * std::cos(phi),
                                std::sqrt(2.0 / M_PI) * rho * std::sin(phi),
                                std::sqrt(3.0 / (2.0 * M_PI)) * (2.0 * rho * rho - 1.0),
                                std::sqrt(3.0 / M_PI) * rho * rho * std::cos(2.0 * phi),
                                std::sqrt(3.0 / M_PI) * rho * rho * std::sin(2.0 * phi)};
        const glm::vec3 n(float(sin_theta * std::cos(phi)), float(sin_theta * std::sin(phi)),
                          float(cos_theta));
        for (const char* name : {"zernike3", "zernike6"})
        {
            const BasisDesc& b = basis(name);
            float got[HEMI_BASIS_MAX_SIZE];
            b.eval(n, got);
            for (int k = 0; k < b.size; ++k)
                EXPECT_NEAR(got[k], want[k], 2e-6)
                    << name << " function " << k << " at theta " << std::acos(cos_theta) << ", phi " << phi;
        }
    }
}

// Sloan 2006, Appendix 7.2: the printed matrix weights the raw lobes (n . b_i), so it equals
// sqrt(3 / (2 pi)) times our projection onto the normalised lobes.
TEST(BasisHl2, ReproducesSloansMatrix)
{
    const double s = std::sqrt(M_PI);
    const std::vector<double> printed = {std::sqrt(3.0) / (4 * s),
                                         std::sqrt(6.0) / (4 * s),
                                         1 / (2 * s),
                                         std::sqrt(2.0) / (4 * s),
                                         0,
                                         3 * std::sqrt(30.0) / (32 * s),
                                         std::sqrt(15.0) / (16 * s),
                                         3 * std::sqrt(10.0) / (32 * s),
                                         0,
                                         std::sqrt(3.0) / (4 * s),
                                         -std::sqrt(6.0) / (4 * s),
                                         1 / (2 * s),
                                         std::sqrt(2.0) / (4 * s),
                                         0,
                                         -3 * std::sqrt(30.0) / (32 * s),
                                         std::sqrt(15.0) / (16 * s),
                                         3 * std::sqrt(10.0) / (32 * s),
                                         0,
                                         std::sqrt(3.0) / (4 * s),
                                         0,
                                         1 / (2 * s),
                                         -std::sqrt(2.0) / (2 * s),
                                         0,
                                         0,
                                         std::sqrt(15.0) / (16 * s),
                                         -3 * std::sqrt(10.0) / (16 * s),
                                         0};
    std::vector<double> p = projection_from_sh9(basis("hl2"));
    for (double& v : p)
        v *= std::sqrt(3.0 / (2.0 * M_PI));
    expect_matrix(p, printed, 3, 1e-6, "HL2");
}

// Sloan 2006, Appendix 7.1, with a and b in closed form.
TEST(BasisSal4, ReproducesSloansMatrix)
{
    const double ln = std::log(3 + 2 * std::sqrt(2.0));
    const double a = (44 - 9 * std::sqrt(2.0) * ln) / 32,
                 b = (39 * std::sqrt(10.0) * ln - 20 * std::sqrt(5.0)) / 256;
    const double r2 = std::sqrt(2.0);
    const std::vector<double> printed = {r2 / 2,
                                         0,
                                         std::sqrt(6.0) / 4,
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         0, //
                                         0,
                                         a,
                                         0,
                                         0,
                                         0,
                                         b,
                                         0,
                                         0,
                                         0, //
                                         0,
                                         0,
                                         r2 / 4,
                                         0,
                                         0,
                                         0,
                                         std::sqrt(30.0) / 8,
                                         0,
                                         0, //
                                         0,
                                         0,
                                         0,
                                         a,
                                         0,
                                         0,
                                         0,
                                         b,
                                         0};
    expect_matrix(projection_from_sh9(basis("sal4")), printed, 4, 1e-6, "SAL4");
    EXPECT_NEAR(a, 0.673872, 1e-6);
    EXPECT_NEAR(b, 0.674516, 1e-6);
}

// Habel & Wimmer 2010, Eq. (14).
TEST(BasisH6, ReproducesHabelsTh)
{
    const double r = 1 / std::sqrt(2.0), q = 3.0 / 8.0 * std::sqrt(2.5);
    const std::vector<double> printed = {r,
                                         0,
                                         0.5 * std::sqrt(1.5),
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         0, //
                                         0,
                                         r,
                                         0,
                                         0,
                                         0,
                                         q,
                                         0,
                                         0,
                                         0, //
                                         0,
                                         0,
                                         1 / (2 * std::sqrt(2.0)),
                                         0,
                                         0,
                                         0,
                                         0.25 * std::sqrt(7.5),
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         r,
                                         0,
                                         0,
                                         0,
                                         q,
                                         0, //
                                         0,
                                         0,
                                         0,
                                         0,
                                         r,
                                         0,
                                         0,
                                         0,
                                         0, //
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         0,
                                         r};
    expect_matrix(projection_from_sh9(basis("h6")), printed, 6, 1e-6, "T_h");
    // H4 is the first four rows.
    std::vector<double> h4 = projection_from_sh9(basis("h4"));
    expect_matrix(h4, std::vector<double>(printed.begin(), printed.begin() + 36), 4, 1e-6, "T_h (H4)");
}

// Sloan 2006, Table 2 (integrated squared error over the hemisphere of projecting each SH9 function),
// compared at the printed number of significant digits. The note's "y2^-2 twice" is an erratum
// (DESIGN.md Sec. 5): y2,-2 and y2,2 are the null-space functions, both 0.5.
TEST(Bases, ReproduceSloanTable2)
{
    struct Entry
    {
        double value;
        int digits;
    };
    const Entry sal[9] = {{0, 0},      {4.6e-2, 2}, {0, 0},      {4.6e-2, 2}, {5e-1, 1},
                          {4.5e-2, 2}, {3.1e-2, 2}, {4.5e-2, 2}, {5e-1, 1}};
    const Entry hl2[9] = {{1.3e-1, 2}, {0, 0},      {0, 0},      {0, 0},   {5e-1, 1},
                          {1.5e-1, 2}, {3.8e-1, 2}, {1.5e-1, 2}, {5e-1, 1}};
    for (int j = 0; j < 9; ++j)
    {
        double e_sal = projection_error_of_sh9_function(basis("sal4"), j);
        double e_hl2 = projection_error_of_sh9_function(basis("hl2"), j);
        if (sal[j].digits == 0)
            EXPECT_NEAR(e_sal, 0.0, 1e-9) << "SAL y" << j;
        else
            EXPECT_DOUBLE_EQ(round_significant(e_sal, sal[j].digits), sal[j].value)
                << "SAL y" << j << ": " << e_sal;
        if (hl2[j].digits == 0)
            EXPECT_NEAR(e_hl2, 0.0, 1e-9) << "HL2 y" << j;
        else
            EXPECT_DOUBLE_EQ(round_significant(e_hl2, hl2[j].digits), hl2[j].value)
                << "HL2 y" << j << ": " << e_hl2;
    }
}

// Habel & Wimmer 2010, Sec. 4.1: H4 and least-squares linear SH span the same functions, so their fits of
// any SH9 signal are the same function on the hemisphere.
TEST(BasisH4, EqualsLeastSquaresLinearShOnTheHemisphere)
{
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> ph = projection_from_sh9(basis("h4")), pl = projection_from_sh9(basis("sh4ls"));
    for (int trial = 0; trial < 20; ++trial)
    {
        double s[9];
        for (double& v : s)
            v = u(rng);
        glm::vec3 n = glm::normalize(glm::vec3(float(u(rng)), float(u(rng)), float(std::abs(u(rng)) + 0.01)));
        float bh[9], bl[9];
        basis("h4").eval(n, bh);
        basis("sh4ls").eval(n, bl);
        double fh = 0, fl = 0;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 9; ++j)
            {
                fh += ph[i * 9 + j] * s[j] * bh[i];
                fl += pl[i * 9 + j] * s[j] * bl[i];
            }
        EXPECT_NEAR(fh, fl, 1e-5);
    }
}

TEST(Bases, LookupByNameNamesTheKnownOnes)
{
    EXPECT_EQ(basis("h6").size, 6);
    try
    {
        basis("h5");
        FAIL();
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("zernike6"), std::string::npos) << e.what();
    }
}

class BasisGlsl : public hemi::test::GpuTest
{
};

// Every basis's GLSL twin (shaders/include/hemi/basis/) evaluated in a compute shader at 4096 random
// directions equals the C++ evaluation.
TEST_F(BasisGlsl, EqualsCppOnTheGpu)
{
    auto& dev = hemi::test::device();
    const uint32_t count = 4096;
    std::mt19937 rng(23);
    std::normal_distribution<float> g;
    std::vector<glm::vec4> normals(count);
    for (auto& n : normals)
    {
        glm::vec3 d = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
        d.z = std::abs(d.z);
        n = glm::vec4(d, 0.0f);
    }
    hemi::gpu::Buffer in = hemi::gpu::create_buffer(dev, {count * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    hemi::gpu::write_buffer(dev, in, normals.data(), count * 16);
    const VkDeviceSize out_bytes = count * HEMI_BASIS_MAX_SIZE * 4;
    hemi::gpu::Buffer out = hemi::gpu::create_buffer(dev, {out_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    std::vector<hemi::gpu::Binding> bindings = {
        {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
        {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT},
        {2, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT}};
    hemi::gpu::Buffer sep = hemi::gpu::create_buffer(dev, {9 * 16, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    hemi::gpu::write_buffer(dev, sep, sep4_weights().data(), 9 * 16); // 9 rows of 4 floats = std140 vec4[9]
    for (const BasisDesc& b : bases())
    {
        hemi::gpu::Program program = hemi::gpu::create_compute_program(
            dev, {hemi::test::test_spirv("basis_eval.comp"), bindings, 4, {uint32_t(b.id)}});
        hemi::gpu::DescriptorPool pool = hemi::gpu::create_descriptor_pool(dev, bindings, 1);
        VkDescriptorSet set = hemi::gpu::allocate_descriptor_set(dev, pool, program.set_layout);
        hemi::gpu::DescriptorWrite writes[3];
        writes[0].binding = 0;
        writes[0].buffer = {in, 0, VK_WHOLE_SIZE};
        writes[1].binding = 1;
        writes[1].buffer = {out, 0, VK_WHOLE_SIZE};
        writes[2].binding = 2;
        writes[2].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        writes[2].buffer = {sep, 0, VK_WHOLE_SIZE};
        hemi::gpu::write_descriptors(dev, set, writes);
        hemi::gpu::one_shot(dev,
                            [&](VkCommandBuffer cmd)
                            {
                                vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.pipeline);
                                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.layout,
                                                        0, 1, &set, 0, nullptr);
                                vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, 4, &count);
                                vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
                            });
        std::vector<float> values(count * HEMI_BASIS_MAX_SIZE);
        hemi::gpu::read_buffer(dev, out, values.data(), out_bytes);
        double worst = 0;
        for (uint32_t i = 0; i < count; ++i)
        {
            float want[HEMI_BASIS_MAX_SIZE] = {};
            b.eval(glm::vec3(normals[i]), want);
            for (int k = 0; k < HEMI_BASIS_MAX_SIZE; ++k)
                worst = std::max(worst, double(std::abs(values[i * HEMI_BASIS_MAX_SIZE + k] - want[k])));
        }
        EXPECT_LT(worst, 1e-5) << b.name;
    }
}

// Sloan 2006, Table 2 note: y2,-2 and y2,2 are in the null space of the first four SVD terms; the 5th and
// 6th singular vectors are exactly those functions. (A is built from float SH evaluation, hence 2e-4.)
TEST(SeparableBasis, QuadraticXyTermsAreTheFifthAndSixthVectors)
{
    SeparableSvd svd = separable_svd(false);
    for (int k = 0; k < 4; ++k)
    {
        EXPECT_NEAR(svd.v[4 * 9 + k], 0.0, 2e-4) << "y2,-2 in vector " << k;
        EXPECT_NEAR(svd.v[8 * 9 + k], 0.0, 2e-4) << "y2,2 in vector " << k;
    }
    double in56 = 0;
    for (int k = 4; k < 6; ++k)
        in56 += svd.v[4 * 9 + k] * svd.v[4 * 9 + k] + svd.v[8 * 9 + k] * svd.v[8 * 9 + k];
    EXPECT_NEAR(in56, 2.0, 1e-6); // both unit vectors lie entirely in vectors 5 and 6
    for (int k = 1; k < 9; ++k)
        EXPECT_LE(svd.singular_values[k], svd.singular_values[k - 1]);
}

// The lifted concentric map is equal-area: a uniform grid on the square lands uniformly on the hemisphere,
// so the fraction of grid points in any cap equals the cap's share of 2pi. A cosine-weighted lift
// (z = sqrt(1 - r^2)) would put 75% of the points in the cap z > 1/2 instead of 50%.
TEST(SeparableBasis, ConcentricMapIsEqualAreaOnTheHemisphere)
{
    int above = 0;
    const int n = 1024;
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k)
        {
            glm::vec3 d = concentric_hemisphere(glm::vec2((k + 0.5f) / n * 2 - 1, (i + 0.5f) / n * 2 - 1));
            ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
            above += d.z > 0.5f;
        }
    EXPECT_NEAR(double(above) / (n * n), 0.5, 0.003);
}

// The 4-term separable basis (convolution folded in) represents the constant irradiance nearly exactly,
// unlike HL2: a wrong W = C V S^-1 (e.g. V without S^-1, or C on the wrong side) loses the DC term.
TEST(SeparableBasis, SepFourHoldsTheConstantNearlyExactly)
{
    const BasisDesc& b = basis("sep4");
    std::vector<double> p = projection_from_sh9(b);
    // The constant (irradiance of a uniform environment) is represented nearly exactly: Sloan's remark
    // that the separable basis handles the DC term, unlike HL2 (Table 2: 0.13).
    double err = projection_error_of_sh9_function(b, 0);
    EXPECT_LT(err, 1e-3);
    EXPECT_LT(err, projection_error_of_sh9_function(basis("hl2"), 0));
    EXPECT_EQ(p.size(), 36u);
}

// Sloan's runtime lookup: texel (i, k) of the 64 x 64 texture holds the sep4 functions at the normal whose
// orthographic projection is the texel centre (rows from n.y = -1), and rim normals outside the disk.
TEST(SeparableBasis, TextureIsIndexedByTheOrthographicProjection)
{
    const int size = 64;
    std::vector<float> tex = separable_texture(size);
    ASSERT_EQ(tex.size(), size_t(size) * size * 4);
    const BasisDesc& b = basis("sep4");
    struct Probe
    {
        int row, col;
    };
    for (Probe p : {Probe{32, 32}, Probe{5, 40}, Probe{50, 12}, Probe{0, 0}})
    {
        float x = (p.col + 0.5f) / size * 2 - 1, y = (p.row + 0.5f) / size * 2 - 1;
        float r2 = x * x + y * y;
        glm::vec3 n =
            r2 < 1 ? glm::vec3(x, y, std::sqrt(1 - r2)) : glm::vec3(x / std::sqrt(r2), y / std::sqrt(r2), 0);
        float want[HEMI_BASIS_MAX_SIZE];
        b.eval(n, want);
        for (int m = 0; m < 4; ++m)
            EXPECT_NEAR(tex[(size_t(p.row) * size + p.col) * 4 + m], want[m], 1e-6f) << p.row << "," << p.col;
    }
    // The texture is not symmetric in n.y (u_1 is odd in y): a transposed or flipped layout would differ.
    EXPECT_NE(tex[(size_t(5) * size + 32) * 4 + 1], tex[(size_t(58) * size + 32) * 4 + 1]);
}
