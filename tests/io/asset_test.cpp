// The .hemi container: round trip, and every way a file can be wrong is a FormatError naming the file.
#include "../temp_dir.h"

#include <hemi/io/asset.h>
#include <hemi/io/image.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace
{
fs::path dir()
{
    return hemi::test::temp_dir("asset_test");
}

fs::path write_sample(const std::string& name)
{
    hemi::io::AssetWriter w;
    std::vector<float> matrices = {1.5f, -2.0f, 3.25f, 0.0f, 7.0f};
    std::vector<uint32_t> indices = {0, 1, 2};
    w.add_array<float>("matrices", matrices);
    w.add_array<uint32_t>("indices", indices);
    w.add("empty", {});
    fs::path p = dir() / name;
    w.write(p);
    return p;
}

std::vector<char> bytes_of(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::vector<char>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& p, const std::vector<char>& b, size_t n)
{
    std::ofstream(p, std::ios::binary | std::ios::trunc).write(b.data(), std::streamsize(n));
}
} // namespace

TEST(Asset, RoundTripsSections)
{
    hemi::io::AssetReader r(write_sample("ok.hemi"));
    EXPECT_EQ(r.version(), hemi::io::kAssetVersion);
    EXPECT_EQ(r.array<float>("matrices"), (std::vector<float>{1.5f, -2.0f, 3.25f, 0.0f, 7.0f}));
    EXPECT_EQ(r.array<uint32_t>("indices"), (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_TRUE(r.section("empty").empty());
    EXPECT_FALSE(r.has("cpca"));
    EXPECT_THROW(r.section("cpca"), hemi::io::FormatError);
    EXPECT_THROW(r.array<double>("matrices"), hemi::io::FormatError); // 20 bytes is not a multiple of 8
}

TEST(Asset, WriterRejectsBadNames)
{
    hemi::io::AssetWriter w;
    EXPECT_THROW(w.add("", {}), std::invalid_argument);
    EXPECT_THROW(w.add(std::string(32, 'x'), {}), std::invalid_argument);
    w.add("a", {});
    EXPECT_THROW(w.add("a", {}), std::invalid_argument);
}

TEST(Asset, RejectsEveryTruncationAndEveryFlippedByte)
{
    fs::path good = write_sample("whole.hemi"), bad = dir() / "bad.hemi";
    std::vector<char> b = bytes_of(good);
    for (size_t n = 0; n < b.size(); ++n)
    {
        write_bytes(bad, b, n);
        EXPECT_THROW(hemi::io::AssetReader{bad}, hemi::io::FormatError) << "truncated to " << n;
    }
    for (size_t i = 0; i < b.size(); ++i)
    {
        std::vector<char> c = b;
        c[i] ^= 0x20;
        write_bytes(bad, c, c.size());
        EXPECT_THROW(hemi::io::AssetReader{bad}, hemi::io::FormatError) << "byte " << i << " flipped";
    }
}

TEST(Asset, ErrorsNameTheFileAndTheProblem)
{
    auto expect = [](const fs::path& p, const std::string& part) {
        try
        {
            hemi::io::AssetReader r(p);
            ADD_FAILURE() << "accepted " << p;
        }
        catch (const hemi::io::FormatError& e)
        {
            std::string what = e.what();
            EXPECT_NE(what.find(p.filename().string()), std::string::npos) << what;
            EXPECT_NE(what.find(part), std::string::npos) << what;
        }
    };
    expect(dir() / "missing.hemi", "no such file");
    std::ofstream(dir() / "text.hemi") << "hello, this is not an asset at all";
    expect(dir() / "text.hemi", "wrong magic");
    std::vector<char> b = bytes_of(write_sample("v.hemi"));
    b[8] = 99; // version field
    write_bytes(dir() / "v.hemi", b, b.size());
    expect(dir() / "v.hemi", "version 99");
    std::vector<char> c = bytes_of(write_sample("c.hemi"));
    c[c.size() - 20] ^= 1;
    write_bytes(dir() / "c.hemi", c, c.size());
    expect(dir() / "c.hemi", "checksum mismatch");
}
