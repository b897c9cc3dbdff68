// hemi-bake basis-report: Habel & Wimmer 2010 Sec. 5's claims on our random signals, and the report files.
#include <hemi/bake/basis_report.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

TEST(BasisReport, ReproducesHabelsClaims)
{
    hemi::bake::BasisReport r = hemi::bake::make_basis_report(2000, 7);
    auto imse = [&](const char* name) { return r.imse.at(name).mean_imse; };
    // "H4 ... the same error as least square projected linear Spherical Harmonics" (exactly: same span).
    EXPECT_NEAR(imse("h4"), imse("sh4ls"), 1e-9 * imse("h4"));
    // "With 6 coefficients the lowest error": H6 below the other 6-coefficient basis, Zernike.
    EXPECT_LT(imse("h6"), imse("zernike6"));
    // "only quadratic Spherical Harmonics have a lower error" than H6.
    for (const auto& [name, st] : r.imse)
    {
        if (name != "h6" && name != "sh9")
        {
            EXPECT_LT(imse("h6"), st.mean_imse) << name;
        }
    }
    EXPECT_LT(imse("sh9"), imse("h6"));
    // "a lower error with 3 coefficients than the Half-Life 2 basis" (Zernike).
    EXPECT_LT(imse("zernike3"), imse("hl2"));
    // Sloan Table 2 rides along: HL2 cannot hold the constant.
    EXPECT_NEAR(r.sloan_table2.at("hl2")[0], 0.125, 1e-6);
}

TEST(BasisReport, WritesJsonAndPlot)
{
    hemi::bake::BasisReport r = hemi::bake::make_basis_report(50, 3);
    fs::path dir = fs::temp_directory_path() / "hemi_basis_report_test";
    fs::create_directories(dir);
    hemi::bake::write_basis_report_json((dir / "r.json").string(), r);
    hemi::bake::plot_basis_report((dir / "fig3.png").string(), r);
    std::ifstream f(dir / "r.json");
    nlohmann::json j = nlohmann::json::parse(f);
    for (const char* b : {"hl2", "h4", "h6", "sal4", "sh4ls", "zernike3", "zernike6", "sep4"})
    {
        ASSERT_TRUE(j["projection"].contains(b)) << b;
        EXPECT_EQ(j["projection"][b][0].size(), 9u) << b;
        EXPECT_TRUE(j["imse"][b].contains("mean")) << b;
        EXPECT_TRUE(j["imse"][b].contains("rel_rms")) << b;
    }
    EXPECT_TRUE(j["imse"].contains("sh9"));
    EXPECT_EQ(j["sloan_table2"]["sal4"].size(), 9u);
    EXPECT_EQ(j["svd_singular_values"]["A"].size(), 9u);
    EXPECT_EQ(j["svd_singular_values"]["A_convolved"].size(), 9u);
    std::ifstream png(dir / "fig3.png", std::ios::binary);
    char sig[4] = {};
    png.read(sig, 4);
    EXPECT_EQ(std::string(sig + 1, 3), "PNG");
    fs::remove_all(dir);
}

TEST(BasisReport, RejectsZeroSignals)
{
    EXPECT_THROW(hemi::bake::make_basis_report(0, 1), std::invalid_argument);
}

// The report's numbers do not depend on how the work is split across threads.
TEST(BasisReport, SameNumbersWhateverTheThreadCount)
{
    hemi::bake::BasisReport many = hemi::bake::make_basis_report(700, 9), one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = hemi::bake::make_basis_report(700, 9);
    }
    for (const auto& [name, st] : many.imse)
    {
        EXPECT_EQ(st.mean_imse, one.imse.at(name).mean_imse) << name;
        EXPECT_EQ(st.rel_rms, one.imse.at(name).rel_rms) << name;
    }
}
