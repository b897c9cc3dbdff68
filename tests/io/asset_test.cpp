// The .hemi container: round trip, and every way a file can be wrong is a FormatError naming the file.
#include "../temp_dir.h"

#include <hemi/io/asset.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>
#include <hemi/io/memory.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <unistd.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>

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

// The three ways to add a section (a copy, bytes generated piece by piece, a view of the caller's bytes), in
// memory and through a spool file, write the bytes of the documented layout, built here byte by byte:
// sections larger than the writer's 1 MiB pieces, of odd sizes, cross the pieces whole. A spool that drops or
// repeats a piece, or a streamed hash that misses a byte, differs.
TEST(Asset, SpooledGeneratedAndViewedSectionsWriteTheDocumentedBytes)
{
    std::vector<std::byte> a(3 * (1u << 20) + 7), b((1u << 20) + 5), c(1001);
    for (size_t i = 0; i < a.size(); ++i)
        a[i] = std::byte((i * 2654435761u) >> 13);
    for (size_t i = 0; i < b.size(); ++i)
        b[i] = std::byte(i % 251);
    for (size_t i = 0; i < c.size(); ++i)
        c[i] = std::byte(255 - i % 256);
    std::vector<char> expected;
    auto put = [&](const void* p, size_t n)
    { expected.insert(expected.end(), static_cast<const char*>(p), static_cast<const char*>(p) + n); };
    put("HEMIASET", 8);
    const uint32_t version = hemi::io::kAssetVersion, count = 3;
    put(&version, 4);
    put(&count, 4);
    uint64_t offset = 16 + 3 * 48;
    for (const auto& [name, bytes] : {std::pair{"a", &a}, std::pair{"b", &b}, std::pair{"c", &c}})
    {
        char padded[32] = {};
        std::strcpy(padded, name);
        put(padded, 32);
        const uint64_t size = bytes->size();
        put(&offset, 8);
        put(&size, 8);
        offset += size;
    }
    for (const auto* bytes : {&a, &b, &c})
        put(bytes->data(), bytes->size());
    const uint64_t hash = XXH64(expected.data(), expected.size(), 0);
    put(&hash, 8);

    const fs::path spool = dir() / "writer.spool";
    for (const bool spooled : {false, true})
    {
        const fs::path out = dir() / (spooled ? "spooled.hemi" : "memory.hemi");
        {
            std::unique_ptr<hemi::io::AssetWriter> w = spooled
                                                           ? std::make_unique<hemi::io::AssetWriter>(spool)
                                                           : std::make_unique<hemi::io::AssetWriter>();
            w->add("a", a);
            w->add_generated("b", b.size(),
                             [&](uint64_t at, std::span<std::byte> piece)
                             {
                                 ASSERT_LE(at + piece.size(), b.size());
                                 std::memcpy(piece.data(), b.data() + at, piece.size());
                             });
            w->add_view("c", c);
            w->write(out);
            EXPECT_EQ(fs::exists(spool), spooled);
        }
        EXPECT_FALSE(fs::exists(spool)) << "the spool goes with its writer";
        EXPECT_EQ(bytes_of(out), expected) << (spooled ? "spooled" : "in memory");
    }
    try
    {
        hemi::io::AssetWriter w(dir() / "no such folder" / "x.spool");
        ADD_FAILURE() << "a spool in a missing folder";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("x.spool"), std::string::npos) << e.what();
    }
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
    auto expect = [](const fs::path& p, const std::string& part)
    {
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

// A large file that is no asset (2 GiB of zeros, sparse on disk) is refused from its head: the reader's
// peak memory grows by far less than the file (it read every byte into memory before the magic check).
TEST(Asset, AFileThatIsNoAssetIsRefusedBeforeItIsRead)
{
    const fs::path p = dir() / "zeros.hemi";
    std::ofstream(p).close();
    fs::resize_file(p, uint64_t(2) << 30);
    const uint64_t before = hemi::io::peak_memory();
    try
    {
        hemi::io::AssetReader r(p);
        ADD_FAILURE() << "accepted " << p;
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("zeros.hemi: not a hemi asset (wrong magic)"), std::string::npos)
            << e.what();
    }
    EXPECT_LT(hemi::io::peak_memory(), before + (uint64_t(256) << 20));
    fs::remove(p);
}

namespace
{
// Rewrites the checksum of a hand-edited container so that the reader reaches its structure checks.
void reseal(std::vector<char>& b)
{
    const uint64_t sum = XXH64(b.data(), b.size() - 8, 0);
    std::memcpy(b.data() + b.size() - 8, &sum, 8);
}
} // namespace

// Two sections of one name, or sections sharing bytes, are never written by hemi: a file that has them
// (checksum intact) is refused naming the problem, instead of the last entry silently winning.
TEST(Asset, DuplicateAndOverlappingSectionsAreRefused)
{
    const fs::path p = write_sample("structure.hemi");
    const std::vector<char> good = bytes_of(p);
    const size_t table = 16, entry = 48; // header; name[32], offset u64, size u64 per entry
    {
        std::vector<char> b = good;
        std::memcpy(b.data() + table + entry, "matrices\0\0\0\0", 12); // entry 1 ("indices") renamed
        reseal(b);
        const fs::path bad = dir() / "duplicate.hemi";
        write_bytes(bad, b, b.size());
        try
        {
            hemi::io::AssetReader r(bad);
            ADD_FAILURE() << "a duplicate section was accepted";
        }
        catch (const hemi::io::FormatError& e)
        {
            EXPECT_NE(std::string(e.what()).find("'matrices' appears twice"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
        }
    }
    {
        std::vector<char> b = good;
        uint64_t first = 0;
        std::memcpy(&first, b.data() + table + 32, 8);
        const uint64_t inside = first + 4; // entry 1 now starts inside entry 0's 20 bytes
        std::memcpy(b.data() + table + entry + 32, &inside, 8);
        reseal(b);
        const fs::path bad = dir() / "overlap.hemi";
        write_bytes(bad, b, b.size());
        try
        {
            hemi::io::AssetReader r(bad);
            ADD_FAILURE() << "overlapping sections were accepted";
        }
        catch (const hemi::io::FormatError& e)
        {
            EXPECT_NE(std::string(e.what()).find("overlap"), std::string::npos) << e.what();
        }
    }
    {
        std::vector<char> b = good;
        const uint64_t into_table = 20; // a section inside the header and table
        std::memcpy(b.data() + table + 32, &into_table, 8);
        reseal(b);
        const fs::path bad = dir() / "into_table.hemi";
        write_bytes(bad, b, b.size());
        EXPECT_THROW(hemi::io::AssetReader r(bad), hemi::io::FormatError);
    }
}

// Writes fail fast and name the cause: a missing folder is named as such (not "disk full"), a folder in the
// target's place too; a temporary file that a killed writer left beside the target (its process gone) is
// removed by the next write, and a running writer's is left alone.
TEST(AtomicFile, OutputProblemsAreNamedAndStaleTemporariesRemoved)
{
    const fs::path missing = dir() / "no_such_folder" / "out.hemi";
    try
    {
        write_sample("../no_such_folder_x/out.hemi");
        ADD_FAILURE() << "wrote into a missing folder";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
    EXPECT_NE(hemi::io::output_problem(missing).find("does not exist"), std::string::npos);
    EXPECT_EQ(hemi::io::output_problem(dir() / "fine.hemi"), "");
    fs::create_directories(dir() / "a_folder.hemi");
    EXPECT_NE(hemi::io::output_problem(dir() / "a_folder.hemi").find("folder"), std::string::npos);

    const fs::path target = dir() / "stale.hemi";
    // pid 2^22 - 1 is above Linux's default pid_max (2^22) for most systems: no such process.
    const fs::path dead = target.string() + ".tmp4194303.7",
                   alive = target.string() + ".tmp" + std::to_string(getpid()) + ".99";
    std::ofstream(dead) << "half";
    std::ofstream(alive) << "in progress";
    ASSERT_EQ(hemi::io::stale_temporaries(target), std::vector<fs::path>{dead});
    write_sample("stale.hemi");
    EXPECT_FALSE(fs::exists(dead)) << "the killed write's temporary outlived the next write";
    EXPECT_TRUE(fs::exists(alive)) << "a running writer's temporary was removed";
    fs::remove(alive);
}
