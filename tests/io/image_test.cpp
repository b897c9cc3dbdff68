// Image writers: atomic, and the bytes they write decode to what was given.
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace
{
fs::path temp_dir()
{
    fs::path d = fs::temp_directory_path() / ("hemi_io_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    fs::create_directories(d);
    return d;
}
} // namespace

TEST(ImageWriters, RejectInconsistentImagesNamingTheFile)
{
    hemi::io::ImageRgba bad{4, 4, std::vector<float>(10)};
    fs::path p = temp_dir() / "bad.png";
    try
    {
        hemi::io::write_png(p, bad);
        FAIL();
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(p));
    EXPECT_THROW(hemi::io::write_exr(temp_dir() / "bad.exr", bad), hemi::io::FormatError);
}

TEST(ImageWriters, WritePngAndExrFiles)
{
    hemi::io::ImageRgba img{3, 2, std::vector<float>(3 * 2 * 4, 0.5f)};
    fs::path png = temp_dir() / "ok.png", exr = temp_dir() / "ok.exr";
    hemi::io::write_png(png, img);
    hemi::io::write_exr(exr, img);
    std::ifstream f(png, std::ios::binary);
    char sig[8];
    f.read(sig, 8);
    EXPECT_EQ(std::string(sig + 1, 3), "PNG");
    std::ifstream e(exr, std::ios::binary);
    unsigned char magic[4];
    e.read(reinterpret_cast<char*>(magic), 4);
    EXPECT_EQ(magic[0], 0x76); // OpenEXR magic 20000630
    EXPECT_EQ(magic[1], 0x2f);
    for (const auto& entry : fs::directory_iterator(temp_dir()))
        EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << "temporary left behind: " << entry.path();
}

TEST(AtomicFile, FailedWriteLeavesTheOldFileAndNoTemporary)
{
    fs::path p = temp_dir() / "keep.txt";
    hemi::io::write_atomically(p, [](const fs::path& tmp) { std::ofstream(tmp) << "old"; });
    EXPECT_THROW(hemi::io::write_atomically(p,
                                            [](const fs::path& tmp) {
                                                std::ofstream(tmp) << "half";
                                                throw std::runtime_error("interrupted");
                                            }),
                 std::runtime_error);
    std::ifstream f(p);
    std::string s;
    f >> s;
    EXPECT_EQ(s, "old");
    for (const auto& entry : fs::directory_iterator(temp_dir()))
        EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(SrgbOetf, MatchesTheStandard)
{
    EXPECT_FLOAT_EQ(hemi::io::srgb_oetf(0.0f), 0.0f);
    EXPECT_NEAR(hemi::io::srgb_oetf(1.0f), 1.0f, 1e-6f);
    EXPECT_NEAR(hemi::io::srgb_oetf(0.002f), 0.02584f, 1e-5f);
    EXPECT_NEAR(hemi::io::srgb_oetf(0.18f), 0.46135f, 1e-4f);
}

namespace
{
std::vector<char> read_all(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::vector<char>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}
void write_all(const fs::path& p, const std::vector<char>& bytes, size_t n)
{
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), std::streamsize(n));
}
void expect_format_error_naming(const fs::path& p, const std::string& what_part)
{
    try
    {
        hemi::io::read_exr(p);
        ADD_FAILURE() << "read_exr accepted " << p;
    }
    catch (const hemi::io::FormatError& e)
    {
        std::string what = e.what();
        EXPECT_NE(what.find(p.filename().string()), std::string::npos) << what;
        EXPECT_NE(what.find(what_part), std::string::npos) << what;
    }
}
} // namespace

TEST(ExrReader, RejectsMissingFile)
{
    expect_format_error_naming(temp_dir() / "does_not_exist.exr", "no such file");
}

TEST(ExrReader, RejectsEveryTruncatedLength)
{
    hemi::io::ImageRgba img{5, 3, std::vector<float>(5 * 3 * 4, 0.25f)};
    fs::path good = temp_dir() / "good.exr", cut = temp_dir() / "cut.exr";
    hemi::io::write_exr(good, img);
    std::vector<char> bytes = read_all(good);
    ASSERT_GT(bytes.size(), 100u);
    for (size_t n = 0; n < bytes.size(); ++n)
    {
        write_all(cut, bytes, n);
        EXPECT_THROW(hemi::io::read_exr(cut), hemi::io::FormatError) << "truncated to " << n << " bytes";
    }
}

TEST(ExrReader, RejectsGarbageAndNaN)
{
    fs::path p = temp_dir() / "garbage.exr";
    write_all(p, std::vector<char>(300, 'x'), 300);
    expect_format_error_naming(p, "not a readable EXR");
    hemi::io::ImageRgba img{4, 2, std::vector<float>(4 * 2 * 4, 1.0f)};
    img.pixels[(1 * 4 + 2) * 4 + 1] = std::nanf("");
    fs::path nan = temp_dir() / "nan.exr";
    hemi::io::write_exr(nan, img);
    expect_format_error_naming(nan, "pixel (2, 1) is not finite");
}

// An auto-cropped EXR (data window inside a larger display window, as compositing tools write) is read
// over its display window, with the data at its offset; an equirect projection then sees the whole sphere.
TEST(ExrReader, PlacesTheDataWindowInsideTheDisplayWindow)
{
    fs::path p = temp_dir() / "cropped.exr";
    {
        Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(7, 3)),
                           Imath::Box2i(Imath::V2i(2, 1), Imath::V2i(5, 2)));
        header.channels().insert("R", Imf::Channel(Imf::FLOAT));
        std::vector<float> r(4 * 2);
        for (size_t i = 0; i < r.size(); ++i)
            r[i] = float(i + 1);
        Imf::OutputFile file(p.c_str(), header);
        Imf::FrameBuffer fb;
        // Base pointer for the data window's origin (2, 1): pixel (x, y) at base + x * 4 + y * 16 bytes.
        char* base = reinterpret_cast<char*>(r.data()) - (2 * 4 + 1 * 16);
        fb.insert("R", Imf::Slice(Imf::FLOAT, base, 4, 16));
        file.setFrameBuffer(fb);
        file.writePixels(2);
    }
    hemi::io::ImageRgba img = hemi::io::read_exr(p);
    ASSERT_EQ(img.width, 8u);
    ASSERT_EQ(img.height, 4u);
    EXPECT_EQ(img.at(0, 0)[0], 0.0f);
    EXPECT_EQ(img.at(2, 1)[0], 1.0f);
    EXPECT_EQ(img.at(5, 2)[0], 8.0f);
    EXPECT_EQ(img.at(2, 1)[3], 1.0f); // missing alpha reads as 1 inside the data window
    EXPECT_EQ(img.at(7, 3)[3], 0.0f); // and 0 outside it
}
