// Image writers: atomic, and the bytes they write decode to what was given.
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include "../hostile_inputs.h"
#include "raw_exr.h"

#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfTiledOutputFile.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <tuple>

namespace fs = std::filesystem;

namespace
{
fs::path temp_dir()
{
    fs::path d = fs::temp_directory_path() /
                 ("hemi_io_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
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

// Both writers' files decode to what was given: the PNG, read back by the decoder, holds at every pixel and
// channel the sRGB encoding of the clamped linear value (the IEC 61966-2-1 curve, typed here) rounded to 8
// bits and the clamped alpha; the EXR holds the values themselves (to half precision, whichever type it
// stores). Every value differs, so a swapped channel or a transposed row is seen as well as a wrong curve.
TEST(ImageWriters, WritePngAndExrFiles)
{
    const uint32_t w = 3, h = 2;
    hemi::io::ImageRgba img{w, h, std::vector<float>(w * h * 4)};
    for (size_t i = 0; i < img.pixels.size(); ++i)
        img.pixels[i] = i % 4 == 3 ? 0.1f + 0.17f * float(i / 4) : 0.001f + 0.05f * float(i);
    img.pixels[4] = 1.5f; // clamped to white in the PNG, kept in the EXR
    fs::path png = temp_dir() / "ok.png", exr = temp_dir() / "ok.exr";
    hemi::io::write_png(png, img);
    hemi::io::write_exr(exr, img);
    const hemi::io::ImageRgba8 decoded = hemi::io::read_png(png);
    ASSERT_EQ(decoded.width, w);
    ASSERT_EQ(decoded.height, h);
    ASSERT_EQ(decoded.pixels.size(), img.pixels.size());
    for (size_t i = 0; i < img.pixels.size(); ++i)
    {
        const float v = std::clamp(img.pixels[i], 0.0f, 1.0f);
        const float encoded =
            i % 4 == 3 ? v : (v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f);
        EXPECT_EQ(int(decoded.pixels[i]), int(std::lround(encoded * 255.0f))) << "PNG byte " << i;
    }
    const hemi::io::ImageRgba back = hemi::io::read_exr(exr);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    ASSERT_EQ(back.pixels.size(), img.pixels.size());
    for (size_t i = 0; i < img.pixels.size(); ++i)
        EXPECT_NEAR(back.pixels[i], img.pixels[i], 1e-3f * img.pixels[i]) << "EXR value " << i;
    for (const auto& entry : fs::directory_iterator(temp_dir()))
        EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos)
            << "temporary left behind: " << entry.path();
}

TEST(AtomicFile, FailedWriteLeavesTheOldFileAndNoTemporary)
{
    fs::path p = temp_dir() / "keep.txt";
    hemi::io::write_atomically(p, [](const fs::path& tmp) { std::ofstream(tmp) << "old"; });
    EXPECT_THROW(hemi::io::write_atomically(p,
                                            [](const fs::path& tmp)
                                            {
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

// A few hundred bytes declaring a 16384 x 16384 display window around one pixel of data would make a reader
// that zero-fills the display window allocate 4 GiB: refused, fast, naming the windows; while ordinary
// auto-cropped files (a small display window, or one at most 64 times its data) still read.
TEST(ExrReader, HugeDisplayWindowsAroundTinyDataAreRefusedQuickly)
{
    auto write = [](const fs::path& p, int display, int data)
    {
        Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(display - 1, display - 1)),
                           Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(data - 1, data - 1)));
        header.channels().insert("R", Imf::Channel(Imf::FLOAT));
        std::vector<float> r(size_t(data) * data, 1.0f);
        Imf::OutputFile file(p.c_str(), header);
        Imf::FrameBuffer fb;
        fb.insert("R", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(r.data()), 4, 4 * size_t(data)));
        file.setFrameBuffer(fb);
        file.writePixels(data);
    };
    const fs::path hostile = temp_dir() / "huge_display.exr";
    write(hostile, 16384, 1);
    EXPECT_LT(fs::file_size(hostile), 1000u);
    try
    {
        hemi::io::read_exr(hostile);
        ADD_FAILURE() << "a 16384x16384 display window around one pixel was read";
    }
    catch (const hemi::io::FormatError& e)
    {
        // Refused by the header check, before any pixel is allocated (the caps of io/image.h).
        EXPECT_NE(std::string(e.what()).find("display window"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(hostile.string()), std::string::npos) << e.what();
    }
    const fs::path cropped = temp_dir() / "cropped_1k.exr";
    write(cropped, 1024, 16); // 4096 times its data window, but small: read
    EXPECT_EQ(hemi::io::read_exr(cropped).width, 1024u);
    const fs::path padded = temp_dir() / "padded_2k.exr";
    write(padded, 2048, 256); // 64 times its data window: read
    EXPECT_EQ(hemi::io::read_exr(padded).width, 2048u);
}

// The 64x padding rule on its own: display windows under the 2^27-pixel cap but over 1024 x 1024, around data
// windows that are a little (2048^2 around 255 x 256: 64.2 times) or much (1100^2 around 8 x 8) smaller.
// Both files are otherwise sound (with the rule removed they read), so only the rule refuses them; the
// message names the file and the two windows.
TEST(ExrReader, DisplayWindowsOverSixtyFourTimesTheirDataAreRefused)
{
    auto write = [](const fs::path& p, int display, int data_w, int data_h)
    {
        Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(display - 1, display - 1)),
                           Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(data_w - 1, data_h - 1)));
        header.channels().insert("R", Imf::Channel(Imf::FLOAT));
        std::vector<float> r(size_t(data_w) * data_h, 1.0f);
        Imf::OutputFile file(p.c_str(), header);
        Imf::FrameBuffer fb;
        fb.insert("R", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(r.data()), 4, 4 * size_t(data_w)));
        file.setFrameBuffer(fb);
        file.writePixels(data_h);
    };
    const struct
    {
        int display, data_w, data_h;
        const char* what;
    } cases[] = {{2048, 255, 256, "is more than 64 times its data window (65280 pixels)"},
                 {1100, 8, 8, "is more than 64 times its data window (64 pixels)"}};
    for (const auto& c : cases)
    {
        const fs::path p = temp_dir() / ("padded_" + std::to_string(c.display) + ".exr");
        write(p, c.display, c.data_w, c.data_h);
        ASSERT_LT(uint64_t(c.display) * uint64_t(c.display), hemi::io::kMaxExrPixels);
        expect_format_error_naming(p, "EXR display window of " + std::to_string(c.display) + "x" +
                                          std::to_string(c.display) + " " + c.what);
    }
}

namespace
{
using hemi::test::RawExr;

std::string exr_error(const std::vector<uint8_t>& bytes, const fs::path& p)
{
    {
        std::ofstream f(p, std::ios::binary | std::ios::trunc);
        f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    }
    try
    {
        hemi::io::read_exr(p);
    }
    catch (const hemi::io::FormatError& e)
    {
        return e.what();
    }
    return "(read)";
}
} // namespace

// The hand-made file the next tests change one thing of reads as it should (so each refusal below is the
// change's doing).
TEST(ExrReader, HandMadeFileReads)
{
    const fs::path p = temp_dir() / "hand_made.exr";
    const std::vector<uint8_t> bytes = RawExr::standard(4, 3).bytes;
    ASSERT_EQ(exr_error(bytes, p), "(read)");
    const hemi::io::ImageRgba img = hemi::io::read_exr(p);
    ASSERT_EQ(img.width, 4u);
    ASSERT_EQ(img.height, 3u);
    for (uint32_t y = 0; y < 3; ++y)
        for (uint32_t x = 0; x < 4; ++x)
        {
            EXPECT_EQ(img.at(x, y)[0], 1.0f);
            EXPECT_EQ(img.at(x, y)[1], 0.0f);
            EXPECT_EQ(img.at(x, y)[3], 1.0f);
        }
}

// read_exr walks the headers before OpenEXR does and refuses, naming the file, what OpenEXR would allocate
// for (or misread) without the file holding it: every refusal of that walk, each made by one change to the
// hand-made file. A reader that left these to OpenEXR would allocate what the header claims (an attribute of
// 1 GiB, an offset table of 8 MiB, ...) and fail later with another message.
TEST(ExrReader, HeadersClaimingWhatTheFileCannotHoldAreRefused)
{
    const std::vector<uint8_t> standard = RawExr::standard().bytes;
    auto with =
        [](const std::function<void(RawExr&)>& header, int32_t w = 4, int32_t h = 3, uint32_t version = 2)
    {
        RawExr e(version);
        header(e);
        e.end_header().half_scanlines(w, h);
        return e.bytes;
    };
    auto standard_plus = [&](const std::function<void(RawExr&)>& extra)
    {
        return with(
            [&](RawExr& e)
            {
                e.image_attributes(4, 3);
                extra(e);
            });
    };
    const struct
    {
        const char* name;
        std::vector<uint8_t> bytes;
        std::string what;
    } cases[] = {
        {"magic", std::vector<uint8_t>{0x76, 0x2f, 0x31, 0x02, 2, 0, 0, 0}, "no EXR magic number"},
        {"version", with([](RawExr& e) { e.image_attributes(4, 3); }, 4, 3, 3), "version field 3"},
        {"flags", with([](RawExr& e) { e.image_attributes(4, 3); }, 4, 3, 2 | 0x2000), "version field 8194"},
        {"attribute_1gib",
         standard_plus([](RawExr& e) { e.attribute("comment", "string", RawExr::text("hi"), 1 << 30); }),
         "header attribute 'comment' (string) claims 1073741824 bytes, the file has"},
        {"attribute_negative", standard_plus([](RawExr& e) { e.attribute("comment", "string", {}, -5); }),
         "header attribute 'comment' (string) claims -5 bytes"},
        {"box_of_20_bytes",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("dataWindow", "box2i", RawExr::ints({0, 0, 3, 2, 0}));
             }),
         "header attribute 'dataWindow' (box2i) has 20 bytes, not 16"},
        {"predefined_of_another_type",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("dataWindow", "v2i", RawExr::ints({0, 0}));
             }),
         "header attribute 'dataWindow' (v2i) was declared of type 'box2i'"},
        {"custom_of_two_types",
         standard_plus(
             [](RawExr& e)
             {
                 e.attribute("owner", "string", RawExr::text("me"));
                 e.attribute("owner", "int", RawExr::ints({1}));
             }),
         "header attribute 'owner' (int) was declared of type 'string'"},
        {"chlist_longer_than_its_channels",
         with(
             [](RawExr& e)
             {
                 std::vector<uint8_t> channels = RawExr::chlist({{"R"}});
                 channels.push_back(7);
                 e.attribute("channels", "chlist", channels);
                 e.attribute("dataWindow", "box2i", RawExr::box(0, 0, 3, 2));
                 e.attribute("displayWindow", "box2i", RawExr::box(0, 0, 3, 2));
                 e.attribute("compression", "compression", {0});
             }),
         "header attribute 'channels' (chlist) has 20 bytes, but its channels take 19"},
        {"preview_of_a_million_pixels_in_8_bytes",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("preview", "preview", RawExr::ints({1000, 1000}));
             }),
         "header attribute 'preview' (preview) of 8 bytes does not hold its preview image"},
        {"floatvector",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("weights", "floatvector", {0, 0, 0, 0, 0, 0});
             }),
         "of 6 bytes is no whole number of floats"},
        {"idmanifest",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("ids", "idmanifest", {0, 0});
             }),
         "header attribute 'ids' (idmanifest) of 2 bytes is truncated"},
        {"long_name",
         standard_plus([](RawExr& e) { e.attribute(std::string(256, 'n'), "int", RawExr::ints({1})); }),
         "an attribute name of more than 255 bytes"},
        {"truncated_header", std::vector<uint8_t>(standard.begin(), standard.begin() + 60),
         "truncated header"},
        {"deep",
         with(
             [](RawExr& e)
             {
                 e.image_attributes(4, 3);
                 e.attribute("type", "string", RawExr::text("deepscanline"));
             },
             4, 3, 2 | 0x800),
         "deep data or an unknown kind of part (type 'deepscanline')"},
        {"inverted_data_window",
         standard_plus([](RawExr& e) { e.attribute("dataWindow", "box2i", RawExr::box(3, 0, 0, 2)); }),
         "invalid data window (3, 0) - (0, 2)"},
        {"unknown_compression",
         standard_plus([](RawExr& e) { e.attribute("compression", "compression", {10}); }),
         "unknown compression method 10"},
        {"tiled_without_tiles", with([](RawExr& e) { e.image_attributes(4, 3); }, 4, 3, 2 | 0x200),
         "a tiled image without a valid tile description"},
        {"pixel_type_7",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("channels", "chlist", RawExr::chlist({{"R", 7}}));
             }),
         "channel 'R' has pixel type 7"},
        {"subsampled_R",
         standard_plus(
             [](RawExr& e) {
                 e.attribute("channels", "chlist", RawExr::chlist({{"R", 1, 2, 1}}));
             }),
         "EXR channel 'R' is subsampled (2x1)"},
        {"no_colour", with([](RawExr& e) { e.image_attributes(4, 3, 0, {{"Z"}}); }),
         "EXR has no R, G, B or Y channel"},
        // 2^20 rows of one pixel, no compression: 2^20 chunks, an 8 MiB offset table in a file of 200 bytes.
        {"offset_table_of_8_mib", with([](RawExr& e) { e.image_attributes(1, 1 << 20); }, 1, 1),
         "EXR offset tables of 1048576 chunks (8388608 bytes) do not fit in the file's"},
        // One row of 2^20 pixels, no compression: 2 MiB of samples in a file of 2 KiB.
        {"wide_row", with([](RawExr& e) { e.image_attributes(1 << 20, 1); }, 1000, 1),
         "EXR data window of 1048576x1 pixels (2097152 bytes) cannot be coded in"},
        // A second channel list holding only R after one of 2000 FLOAT channels: OpenEXR merges the two
        // (8,002 bytes a pixel, 33 MB for this 4096-pixel row), so the scan must count both, not the last.
        {"repeated_channel_list",
         with(
             [](RawExr& e)
             {
                 std::vector<hemi::test::RawExrChannel> many;
                 for (int i = 0; i < 2000; ++i)
                 {
                     std::string name(1, 'c'); // not "c" + ...: GCC 12 warns falsely (-Wrestrict) there
                     name += std::to_string(i);
                     many.push_back({name, 2});
                 }
                 e.attribute("channels", "chlist", RawExr::chlist(many));
                 e.image_attributes(4096, 1);
             },
             4096, 1),
         "EXR data window of 4096x1 pixels (32776192 bytes) cannot be coded in"},
        // One pixel in a tile of 4096 x 4096: OpenEXR would allocate the whole tile (and read_exr's row of
        // tiles 256 MiB) for two bytes of data.
        {"tile_of_16_megapixels",
         with(
             [](RawExr& e)
             {
                 e.image_attributes(1, 1);
                 std::vector<uint8_t> tiles = RawExr::ints({4096, 4096});
                 tiles.push_back(0);
                 e.attribute("tiles", "tiledesc", tiles);
             },
             1, 1, 2 | 0x200),
         "EXR chunks of 4096x4096 pixels cannot be coded in"},
    };
    for (const auto& c : cases)
    {
        const fs::path p = temp_dir() / (std::string("hostile_") + c.name + ".exr");
        const std::string e = exr_error(c.bytes, p);
        EXPECT_NE(e.find(p.string()), std::string::npos) << c.name << ": " << e;
        EXPECT_NE(e.find(c.what), std::string::npos) << c.name << ": " << e;
    }
}

// Multi-part files: part 0 is what read_exr reads; the offset tables of every part must fit, and a part of a
// type OpenEXR does not know needs its chunk count.
TEST(ExrReader, MultiPartOffsetTablesMustFit)
{
    auto part = [](RawExr& e, const char* name, const char* type, int32_t height)
    {
        e.image_attributes(4, height);
        e.attribute("name", "string", RawExr::text(name));
        e.attribute("type", "string", RawExr::text(type));
        e.attribute("chunkCount", "int", RawExr::ints({height}));
        e.end_header();
    };
    RawExr unknown(2 | 0x1000);
    part(unknown, "a", "scanlineimage", 3);
    unknown.image_attributes(4, 3).attribute("name", "string", RawExr::text("b"));
    unknown.attribute("type", "string", RawExr::text("mystery")).end_header().end_header();
    unknown.bytes.resize(unknown.bytes.size() + 200);
    const fs::path p1 = temp_dir() / "multipart_unknown.exr";
    std::string e = exr_error(unknown.bytes, p1);
    EXPECT_NE(e.find("part 1 of type 'mystery' has no chunk count"), std::string::npos) << e;
    EXPECT_NE(e.find(p1.string()), std::string::npos) << e;
    // The second part claims 2^20 scanlines (no compression): its table alone would be 8 MiB.
    RawExr tall(2 | 0x1000);
    part(tall, "a", "scanlineimage", 3);
    part(tall, "b", "scanlineimage", 1 << 20);
    tall.end_header();
    tall.bytes.resize(tall.bytes.size() + 200);
    const fs::path p2 = temp_dir() / "multipart_tall.exr";
    e = exr_error(tall.bytes, p2);
    EXPECT_NE(e.find("EXR offset tables of 1048579 chunks"), std::string::npos) << e;
    EXPECT_NE(e.find(p2.string()), std::string::npos) << e;
}

// What the bound on the data a file can code must never refuse: the most compressible image there is (one
// value everywhere) written by OpenEXR with each of its compression methods, with a lossy (R), an RLE-coded
// (A) and a float channel (G, which PXR24 stores in 24 bits), reads back. Prints each file's expansion (its
// pixels' bytes per stored byte) for the bounds of image.cpp.
TEST(ExrReader, HighlyCompressedFilesOfEveryMethodRead)
{
    const int w = 2048, h = 256;
    std::vector<uint16_t> half_value(size_t(w) * h, 0x3800); // 0.5
    std::vector<uint16_t> half_one(size_t(w) * h, 0x3c00);
    std::vector<float> float_value(size_t(w) * h, 0.25f);
    for (int c = 0; c < int(Imf::NUM_COMPRESSION_METHODS); ++c)
    {
        const fs::path p = temp_dir() / ("constant_" + std::to_string(c) + ".exr");
        {
            Imf::Header header(w, h);
            header.compression() = Imf::Compression(c);
            header.channels().insert("R", Imf::Channel(Imf::HALF));
            header.channels().insert("A", Imf::Channel(Imf::HALF));
            header.channels().insert("G", Imf::Channel(Imf::FLOAT));
            Imf::OutputFile file(p.c_str(), header);
            Imf::FrameBuffer fb;
            fb.insert("R",
                      Imf::Slice(Imf::HALF, reinterpret_cast<char*>(half_value.data()), 2, 2 * size_t(w)));
            fb.insert("A", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(half_one.data()), 2, 2 * size_t(w)));
            fb.insert("G",
                      Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(float_value.data()), 4, 4 * size_t(w)));
            file.setFrameBuffer(fb);
            file.writePixels(h);
        }
        const uint64_t bytes = fs::file_size(p);
        std::printf("compression %d: %d x %d pixels of 8 bytes in %llu bytes, expansion %.0f\n", c, w, h,
                    (unsigned long long)bytes, double(w) * h * 8 / double(bytes));
        try
        {
            const hemi::io::ImageRgba img = hemi::io::read_exr(p);
            ASSERT_EQ(img.width, uint32_t(w));
            EXPECT_NEAR(img.at(100, 200)[0], 0.5f, 0.01f) << "compression " << c;
            EXPECT_NEAR(img.at(100, 200)[1], 0.25f, 0.01f) << "compression " << c;
            EXPECT_EQ(img.at(w - 1, h - 1)[3], 1.0f) << "compression " << c;
        }
        catch (const hemi::io::FormatError& e)
        {
            ADD_FAILURE() << "compression " << c << ": " << e.what();
        }
    }
}

// read_exr reads the data window in bands that start at one chunk and grow: every pixel lands where it
// belongs, with the padding of an auto-cropped display window around it, for scanline files of 1 and 16 lines
// a chunk and a tiled file (8 x 8 tiles, mipmapped), and for a grey (Y) file. Every value differs (so a band
// at the wrong row, a shifted pad or a transposition is seen).
TEST(ExrReader, BandsPutEveryPixelInPlace)
{
    const int dx0 = 13, dy0 = 5, dw = 60,
              dh = 70; // data window (13, 5) - (72, 74) in display (0, 0) - (99, 79)
    auto value = [](int x, int y, int c) { return float(x * 1000 + y * 4 + c) * 0.001f; };
    std::vector<float> rgba(size_t(dw) * dh * 4);
    for (int y = 0; y < dh; ++y)
        for (int x = 0; x < dw; ++x)
            for (int c = 0; c < 4; ++c)
                rgba[(size_t(y) * dw + x) * 4 + c] = value(x + dx0, y + dy0, c);
    const Imath::Box2i display(Imath::V2i(0, 0), Imath::V2i(99, 79));
    const Imath::Box2i data(Imath::V2i(dx0, dy0), Imath::V2i(dx0 + dw - 1, dy0 + dh - 1));
    char* base = reinterpret_cast<char*>(rgba.data()) - (size_t(dx0) * 16 + size_t(dy0) * 16 * dw);
    auto frame_buffer = [&](bool grey)
    {
        Imf::FrameBuffer fb;
        const char* names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < (grey ? 1 : 4); ++c)
            fb.insert(grey ? "Y" : names[c], Imf::Slice(Imf::FLOAT, base + 4 * c, 16, 16 * size_t(dw)));
        return fb;
    };
    auto check = [&](const fs::path& p, bool grey)
    {
        const hemi::io::ImageRgba img = hemi::io::read_exr(p);
        ASSERT_EQ(img.width, 100u);
        ASSERT_EQ(img.height, 80u);
        int wrong = 0;
        for (int y = 0; y < 80; ++y)
            for (int x = 0; x < 100; ++x)
                for (int c = 0; c < 4; ++c)
                {
                    const bool inside = x >= dx0 && x < dx0 + dw && y >= dy0 && y < dy0 + dh;
                    const float want = !inside ? 0.0f
                                       : grey  ? (c == 3 ? 1.0f : value(x, y, 0))
                                               : value(x, y, c);
                    wrong += img.at(uint32_t(x), uint32_t(y))[c] != want;
                }
        EXPECT_EQ(wrong, 0) << p;
    };
    for (Imf::Compression compression : {Imf::NO_COMPRESSION, Imf::ZIP_COMPRESSION})
    {
        const fs::path p = temp_dir() / ("bands_" + std::to_string(int(compression)) + ".exr");
        Imf::Header header(display, data);
        header.compression() = compression;
        for (const char* n : {"R", "G", "B", "A"})
            header.channels().insert(n, Imf::Channel(Imf::FLOAT));
        {
            Imf::OutputFile file(p.c_str(), header);
            file.setFrameBuffer(frame_buffer(false));
            file.writePixels(dh);
        }
        check(p, false);
    }
    {
        const fs::path p = temp_dir() / "bands_tiled.exr";
        Imf::Header header(display, data);
        for (const char* n : {"R", "G", "B", "A"})
            header.channels().insert(n, Imf::Channel(Imf::FLOAT));
        header.setTileDescription(Imf::TileDescription(8, 8, Imf::MIPMAP_LEVELS));
        Imf::TiledOutputFile file(p.c_str(), header);
        file.setFrameBuffer(frame_buffer(false));
        for (int level = 0; level < file.numLevels(); ++level)
            file.writeTiles(0, file.numXTiles(level) - 1, 0, file.numYTiles(level) - 1, level);
    }
    check(temp_dir() / "bands_tiled.exr", false);
    {
        const fs::path p = temp_dir() / "bands_grey.exr";
        Imf::Header header(display, data);
        header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
        Imf::OutputFile file(p.c_str(), header);
        file.setFrameBuffer(frame_buffer(true));
        file.writePixels(dh);
    }
    check(temp_dir() / "bands_grey.exr", true);
}

// ---- 8-bit textures: PNG and JPEG decoding (the images glTF scenes and assets carry) ----

namespace
{
uint32_t crc32_of(const uint8_t* p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i)
    {
        c ^= p[i];
        for (int k = 0; k < 8; ++k)
            c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xFFFFFFFFu;
}

void put_be32(std::vector<uint8_t>& out, uint32_t v)
{
    for (int s = 24; s >= 0; s -= 8)
        out.push_back(uint8_t(v >> s));
}

void put_chunk(std::vector<uint8_t>& out, const char* type, const std::vector<uint8_t>& data)
{
    put_be32(out, uint32_t(data.size()));
    const size_t at = out.size();
    out.insert(out.end(), type, type + 4);
    out.insert(out.end(), data.begin(), data.end());
    put_be32(out, crc32_of(out.data() + at, 4 + data.size()));
}

// A PNG written by hand (stb_image_write writes 8-bit RGBA only): `rows` are the raw scanlines without their
// filter byte; the image data is zlib with stored (uncompressed) blocks. `empty_idat` puts a zero-length IDAT
// chunk before the data, which the PNG specification allows.
std::vector<uint8_t> handmade_png(uint32_t w, uint32_t h, uint8_t depth, uint8_t colour_type,
                                  const std::vector<std::vector<uint8_t>>& rows, bool empty_idat = false)
{
    std::vector<uint8_t> raw;
    for (const auto& row : rows)
    {
        raw.push_back(0); // filter: none
        raw.insert(raw.end(), row.begin(), row.end());
    }
    std::vector<uint8_t> z = {0x78, 0x01};
    for (size_t at = 0; at < raw.size() || at == 0; at += 65535)
    {
        const size_t n = std::min<size_t>(65535, raw.size() - at);
        z.push_back(at + n == raw.size() ? 1 : 0);
        z.push_back(uint8_t(n)), z.push_back(uint8_t(n >> 8));
        z.push_back(uint8_t(~n)), z.push_back(uint8_t(~n >> 8));
        z.insert(z.end(), raw.begin() + long(at), raw.begin() + long(at + n));
        if (raw.empty())
            break;
    }
    uint32_t a = 1, b = 0;
    for (uint8_t c : raw)
        a = (a + c) % 65521, b = (b + a) % 65521;
    put_be32(z, b << 16 | a);
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    put_be32(ihdr, w);
    put_be32(ihdr, h);
    ihdr.insert(ihdr.end(), {depth, colour_type, 0, 0, 0});
    put_chunk(png, "IHDR", ihdr);
    if (empty_idat)
        put_chunk(png, "IDAT", {});
    put_chunk(png, "IDAT", z);
    put_chunk(png, "IEND", {});
    return png;
}

hemi::io::EncodedImage encoded(const std::string& name, const std::string& mime, std::vector<uint8_t> bytes)
{
    return {name, mime, std::move(bytes)};
}

void expect_decode_error(const hemi::io::EncodedImage& image, const std::string& part)
{
    try
    {
        hemi::io::decode_image(image);
        ADD_FAILURE() << image.name << " was decoded; expected an error about '" << part << "'";
    }
    catch (const hemi::io::FormatError& e)
    {
        const std::string what = e.what();
        EXPECT_NE(what.find(image.name), std::string::npos) << what;
        EXPECT_NE(what.find(part), std::string::npos) << what;
    }
}

hemi::io::ImageRgba8 smooth(uint32_t w, uint32_t h)
{
    hemi::io::ImageRgba8 img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            uint8_t* p = &img.pixels[(size_t(y) * w + x) * 4];
            p[0] = uint8_t(30 + 150 * x / w), p[1] = uint8_t(200 - 100 * y / h),
            p[2] = uint8_t(90 + (x + y) % 8);
            p[3] = 255;
        }
    return img;
}
} // namespace

TEST(ImageDecode, PngIsExactAndJpegIsClose)
{
    hemi::io::ImageRgba8 img{7, 5, std::vector<uint8_t>(7 * 5 * 4)};
    for (size_t i = 0; i < img.pixels.size(); ++i)
        img.pixels[i] = uint8_t(i * 53 % 251);
    const hemi::io::ImageRgba8 png =
        hemi::io::decode_image(encoded("a.png", "image/png", hemi::io::encode_png(img)));
    EXPECT_EQ(png.width, 7u);
    EXPECT_EQ(png.height, 5u);
    EXPECT_EQ(png.pixels, img.pixels);

    const hemi::io::ImageRgba8 want = smooth(32, 24);
    const hemi::io::ImageRgba8 jpeg =
        hemi::io::decode_image(encoded("a.jpg", "image/jpeg", hemi::io::encode_jpeg(want, 95)));
    ASSERT_EQ(jpeg.width, 32u);
    ASSERT_EQ(jpeg.height, 24u);
    double sum = 0.0;
    int worst = 0;
    for (size_t i = 0; i < want.pixels.size(); ++i)
    {
        const int e = std::abs(int(jpeg.pixels[i]) - int(want.pixels[i]));
        worst = std::max(worst, e);
        sum += e;
    }
    EXPECT_LE(worst, 10);
    EXPECT_LT(sum / double(want.pixels.size()), 2.0);
    EXPECT_EQ(jpeg.pixels[3], 255) << "JPEG has no alpha: opaque";
    // An empty mime type means "by the signature".
    EXPECT_EQ(hemi::io::decode_image(encoded("b.png", "", hemi::io::encode_png(img))).pixels, img.pixels);
}

// Grey and RGB get alpha 255; 16-bit samples are rounded to 8 bits (511 -> 2, which truncation makes 1).
TEST(ImageDecode, ExpandsChannelsAndRounds16BitSamples)
{
    const std::vector<uint8_t> grey = handmade_png(3, 1, 8, 0, {{0, 128, 255}});
    const hemi::io::ImageRgba8 g = hemi::io::decode_image(encoded("grey.png", "image/png", grey));
    EXPECT_EQ(g.pixels, (std::vector<uint8_t>{0, 0, 0, 255, 128, 128, 128, 255, 255, 255, 255, 255}));
    const std::vector<uint8_t> rgb = handmade_png(2, 1, 8, 2, {{1, 2, 3, 4, 5, 6}});
    EXPECT_EQ(hemi::io::decode_image(encoded("rgb.png", "image/png", rgb)).pixels,
              (std::vector<uint8_t>{1, 2, 3, 255, 4, 5, 6, 255}));

    // RGBA, 16 bits per sample, big-endian: 0, 65535, 511 (-> 2), 32896 (-> 128) / 0x7F7F (-> 127), 257 (->
    // 1), 65279 (-> 254), 1000 (-> 4).
    const std::vector<uint16_t> samples = {0, 65535, 511, 32896, 0x7F7F, 257, 65279, 1000};
    std::vector<uint8_t> row;
    for (uint16_t s : samples)
        row.push_back(uint8_t(s >> 8)), row.push_back(uint8_t(s));
    const std::vector<uint8_t> wide = handmade_png(2, 1, 16, 6, {row});
    const hemi::io::ImageRgba8 w = hemi::io::decode_image(encoded("wide.png", "image/png", wide));
    ASSERT_EQ(w.width, 2u);
    std::vector<uint8_t> want;
    for (uint16_t s : samples)
        want.push_back(uint8_t(std::lround(double(s) * 255.0 / 65535.0)));
    EXPECT_EQ(w.pixels, want);
    EXPECT_EQ(w.pixels[2], 2);
    // A 16-bit grey image.
    const std::vector<uint8_t> grey16 = handmade_png(1, 2, 16, 0, {{0x01, 0xFF}, {0xFF, 0xFF}});
    EXPECT_EQ(hemi::io::decode_image(encoded("grey16.png", "image/png", grey16)).pixels,
              (std::vector<uint8_t>{2, 2, 2, 255, 255, 255, 255, 255}));
    // A zero-length IDAT chunk before the data is legal PNG (and would make stb copy to a null pointer).
    const std::vector<uint8_t> empty_first = handmade_png(3, 1, 8, 0, {{0, 128, 255}}, true);
    EXPECT_EQ(hemi::io::decode_image(encoded("empty_idat.png", "image/png", empty_first)).pixels, g.pixels);
}

TEST(ImageDecode, RefusesBrokenImagesNamingThem)
{
    hemi::io::ImageRgba8 img{6, 4, std::vector<uint8_t>(6 * 4 * 4, 77)};
    const std::vector<uint8_t> png = hemi::io::encode_png(img);
    const std::vector<uint8_t> jpeg = hemi::io::encode_jpeg(smooth(16, 16), 90);
    expect_decode_error(encoded("empty.png", "image/png", {}), "empty image (0 bytes)");
    expect_decode_error(encoded("anim.gif", "image/gif", {'G', 'I', 'F', '8', '9', 'a', 1, 0, 1, 0}),
                        "neither a PNG nor a JPEG");
    expect_decode_error(encoded("liar.jpg", "image/jpeg", png),
                        "declared image/jpeg, but the bytes are image/png");
    expect_decode_error(encoded("liar.png", "image/png", jpeg),
                        "declared image/png, but the bytes are image/jpeg");
    // Every truncation of either format (the signature kept) is refused, none decoded to a partial image.
    for (const auto& [name, mime, bytes] :
         {std::tuple{"cut.png", "image/png", png}, std::tuple{"cut.jpg", "image/jpeg", jpeg}})
        for (size_t n = 8; n < bytes.size(); ++n)
        {
            const hemi::io::EncodedImage cut =
                encoded(name, mime, std::vector<uint8_t>(bytes.begin(), bytes.begin() + long(n)));
            EXPECT_THROW(hemi::io::decode_image(cut), hemi::io::FormatError)
                << name << " cut to " << n << " bytes";
        }
    expect_decode_error(encoded("cut.png", "image/png", std::vector<uint8_t>(png.begin(), png.end() - 5)),
                        "truncated PNG");
    expect_decode_error(encoded("cut.jpg", "image/jpeg", std::vector<uint8_t>(jpeg.begin(), jpeg.end() - 2)),
                        "truncated JPEG");
    // A flipped bit inside the image data: the chunk's CRC no longer matches.
    std::vector<uint8_t> flipped = png;
    flipped[png.size() - 20] ^= 0x04;
    expect_decode_error(encoded("flipped.png", "image/png", flipped), "fails its CRC check");
    // A zero-sized image, and a first chunk that is not IHDR.
    expect_decode_error(encoded("zero.png", "image/png", handmade_png(0, 1, 8, 0, {})), "0x1 pixels (empty)");
    std::vector<uint8_t> no_ihdr = handmade_png(3, 1, 8, 0, {{1, 2, 3}});
    std::memcpy(no_ihdr.data() + 12, "ABCD", 4);
    expect_decode_error(encoded("no_ihdr.png", "image/png", no_ihdr), "corrupt PNG");
    // A chunk length that points far beyond the file.
    std::vector<uint8_t> long_chunk = png;
    long_chunk[8] = 0x7F;
    expect_decode_error(encoded("long_chunk.png", "image/png", long_chunk), "truncated PNG");
}

TEST(ImageDecode, EncodedFilesAreTypedByTheirSignature)
{
    hemi::io::ImageRgba8 img{2, 2, std::vector<uint8_t>(16, 200)};
    const fs::path misnamed = temp_dir() / "really_a_png.jpg";
    hemi::io::write_png(misnamed, img);
    const hemi::io::EncodedImage e = hemi::io::read_encoded_image(misnamed);
    EXPECT_EQ(e.mime_type, "image/png");
    EXPECT_EQ(e.name, misnamed.string());
    EXPECT_EQ(hemi::io::decode_image(e).pixels, img.pixels);
    const fs::path jpeg = temp_dir() / "photo.png";
    const std::vector<uint8_t> jpeg_bytes = hemi::io::encode_jpeg(img, 80);
    std::ofstream(jpeg, std::ios::binary)
        .write(reinterpret_cast<const char*>(jpeg_bytes.data()), long(jpeg_bytes.size()));
    EXPECT_EQ(hemi::io::read_encoded_image(jpeg).mime_type, "image/jpeg");
    EXPECT_THROW(hemi::io::read_png(jpeg), hemi::io::FormatError);
    const fs::path text = temp_dir() / "notes.png";
    std::ofstream(text) << "hello";
    EXPECT_THROW(hemi::io::read_encoded_image(text), hemi::io::FormatError);
    EXPECT_THROW(hemi::io::read_encoded_image(temp_dir() / "absent.png"), hemi::io::FormatError);
    EXPECT_THROW(hemi::io::encode_jpeg(img, 0), std::invalid_argument);
    EXPECT_THROW(hemi::io::encode_png(hemi::io::ImageRgba8{2, 2, std::vector<uint8_t>(3)}),
                 std::invalid_argument);
}

// Found by tests/fuzz/fuzz_image: a JPEG Huffman table of more than 256 codes made Debian's stb_image write
// past its tables. Refused before stb sees it, naming the image and the table.
TEST(ImageDecode, JpegHuffmanTablesOfMoreThan256CodesAreRefused)
{
    const std::vector<uint8_t> jpeg = hemi::io::encode_jpeg(smooth(16, 8), 80);
    const std::vector<uint8_t> hostile = hemi::test::jpeg_with_oversized_huffman_table(jpeg);
    ASSERT_FALSE(hostile.empty()) << "the encoder's JPEG has no Huffman table to replace";
    try
    {
        hemi::io::decode_image({"hostile.jpg", "image/jpeg", hostile});
        ADD_FAILURE() << "a 272-code Huffman table was decoded";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("hostile.jpg"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("Huffman table of 272 codes"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(hemi::io::decode_image({"fine.jpg", "image/jpeg", jpeg}));
}

// Found by tests/fuzz/fuzz_image: 760 bytes whose JPEG frame header claims 16392 x 9488 took 13 s and 1.6 GB
// to decode. A header is refused when its size cannot be coded in the bytes that follow (io/image.cpp says
// why the bound is below any real file's), before decoding; the same file with its real size decodes.
TEST(ImageDecode, HeadersClaimingMorePixelsThanTheBytesCanCodeAreRefused)
{
    const std::vector<uint8_t> jpeg = hemi::io::encode_jpeg(smooth(16, 8), 80);
    const std::vector<uint8_t> hostile = hemi::test::jpeg_with_frame_size(jpeg, 16392, 9488);
    ASSERT_FALSE(hostile.empty());
    try
    {
        hemi::io::decode_image({"huge.jpg", "image/jpeg", hostile});
        ADD_FAILURE() << "a 16392x9488 frame in " << hostile.size() << " bytes was decoded";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("16392x9488 pixels cannot be coded"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(
        hemi::io::decode_image({"same.jpg", "image/jpeg", hemi::test::jpeg_with_frame_size(jpeg, 16, 8)})
            .width,
        16u);
    // A real large image is well above the bound: 2048 x 1024 of smooth content.
    EXPECT_EQ(hemi::io::decode_image({"big.jpg", "image/jpeg", hemi::io::encode_jpeg(smooth(2048, 1024), 50)})
                  .width,
              2048u);
    EXPECT_EQ(
        hemi::io::decode_image({"big.png", "image/png", hemi::io::encode_png(smooth(2048, 1024))}).width,
        2048u);
}

// Found by tests/fuzz/fuzz_image: Huffman code lengths that over-subscribe the code space (no prefix code)
// made stb_image 2.27 index its tables with negative numbers. Refused by the Kraft inequality first.
TEST(ImageDecode, JpegHuffmanTablesThatAreNoPrefixCodeAreRefused)
{
    const std::vector<uint8_t> hostile =
        hemi::test::jpeg_with_oversubscribed_huffman_table(hemi::io::encode_jpeg(smooth(16, 8), 80));
    ASSERT_FALSE(hostile.empty());
    try
    {
        hemi::io::decode_image({"prefix.jpg", "image/jpeg", hostile});
        ADD_FAILURE() << "an over-subscribed Huffman table was decoded";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("not a prefix code"), std::string::npos) << e.what();
    }
}

// Found by tests/fuzz/fuzz_image's short campaign in CI: a scan whose component decodes with a Huffman table
// no DHT defines (stb_image then reads a zeroed table's symbols out of bounds). Refused before decoding; a
// real JPEG (every table it uses defined) still decodes.
TEST(ImageDecode, JpegScansWithUndefinedHuffmanTablesAreRefused)
{
    const std::vector<uint8_t> good = hemi::io::encode_jpeg(smooth(16, 8), 80);
    const std::vector<uint8_t> hostile = hemi::test::jpeg_with_undefined_huffman_table(good);
    ASSERT_FALSE(hostile.empty());
    try
    {
        hemi::io::decode_image({"tables.jpg", "image/jpeg", hostile});
        ADD_FAILURE() << "a scan with an undefined Huffman table was decoded";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("not defined"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("tables.jpg"), std::string::npos) << e.what();
    }
    // A baseline scan decodes AC coefficients whatever its Se says: an undefined AC table there is refused
    // too.
    const std::vector<uint8_t> baseline = hemi::test::jpeg_with_undefined_ac_table_in_a_baseline_scan(good);
    ASSERT_FALSE(baseline.empty());
    EXPECT_THROW(hemi::io::decode_image({"baseline.jpg", "image/jpeg", baseline}), hemi::io::FormatError);
    EXPECT_EQ(hemi::io::decode_image({"good.jpg", "image/jpeg", good}).width, 16u);
}

// Real HDRIs' few slightly negative values (all of Blender's studio-light worlds hold some, down to -0.004)
// are read as 0 and counted; a negative value beyond 1% of the image's mean is refused, naming the image and
// the pixel; alpha is not radiance and is left alone.
TEST(EnvironmentImage, SmallNegativeRadianceIsReadAsZeroAndALargeOneRefused)
{
    hemi::io::ImageRgba image{3, 2, std::vector<float>(24, 1.0f)};
    image.pixels[1] = -0.004f;         // pixel (0, 0), green
    image.pixels[4 * 4 + 2] = -0.001f; // pixel (1, 1), blue
    image.pixels[4 * 5 + 3] = -5.0f;   // pixel (2, 1), alpha: not radiance
    const hemi::io::NegativeRadiance n = hemi::io::clamp_negative_radiance(image, "sky.exr");
    EXPECT_EQ(n.clamped, 2u);
    EXPECT_FLOAT_EQ(n.least, -0.004f);
    EXPECT_EQ(image.pixels[1], 0.0f);
    EXPECT_EQ(image.pixels[4 * 4 + 2], 0.0f);
    EXPECT_EQ(image.pixels[4 * 5 + 3], -5.0f);
    EXPECT_EQ(image.pixels[0], 1.0f);

    hemi::io::ImageRgba bad{3, 2, std::vector<float>(24, 1.0f)};
    bad.pixels[4 * 5 + 0] = -0.02f; // pixel (2, 1): 2% of the mean
    try
    {
        hemi::io::clamp_negative_radiance(bad, "sky.exr");
        ADD_FAILURE() << "a negative radiance of 2% of the mean was accepted";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("sky.exr: pixel (2, 1)"), std::string::npos) << e.what();
    }
    EXPECT_EQ(bad.pixels[4 * 5 + 0], -0.02f) << "nothing changed when refused";
}
