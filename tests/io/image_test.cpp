// Image writers: atomic, and the bytes they write decode to what was given.
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include "../hostile_inputs.h"

#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
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
