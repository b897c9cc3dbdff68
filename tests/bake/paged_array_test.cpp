// PagedArray (bake/paged_array.h): what a bake out of core keeps its texel records in. Items written in
// order and read back from many threads at once through a cache far smaller than the array give the items
// written, in memory and in a file alike; the file is gone from its directory from the start; a directory
// that cannot hold it is named in the error.
#include "../temp_dir.h"

#include <hemi/bake/paged_array.h>
#include <hemi/io/image.h> // io::FormatError

#include <gtest/gtest.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>

namespace
{

namespace fs = std::filesystem;
using hemi::bake::PagedArray;
using hemi::bake::PagedStore;

struct Item
{
    uint64_t a;
    uint32_t b, c;
};

Item expected(size_t i)
{
    return {uint64_t(i) * 2654435761u, uint32_t(i ^ 0x5a5a5a5a), uint32_t(i * 7 + 1)};
}

// Random reads (a hash of the index and the round) from every thread: the item read is the item written.
size_t wrong_reads(const PagedArray<Item>& array, size_t reads)
{
    std::atomic<size_t> wrong{0};
    tbb::parallel_for(size_t(0), reads,
                      [&](size_t r)
                      {
                          const size_t i = size_t((r * 0x9e3779b97f4a7c15ull) >> 20) % array.size();
                          const Item got = array[i], want = expected(i);
                          wrong += got.a != want.a || got.b != want.b || got.c != want.c;
                      });
    return wrong;
}

} // namespace

TEST(PagedArray, ItemsReadBackFromAnyThreadAreTheItemsWrittenInMemoryAndInPages)
{
    const fs::path dir = hemi::test::temp_dir("paged_array_test") / "pages";
    fs::create_directories(dir);
    // Two chunks (in memory) and a bit, 128 pages and a bit (in a file), appended one item and a few hundred
    // at a time (across page and chunk ends).
    constexpr size_t kItems = 2 * PagedStore::kChunkItems + 37;
    for (const bool paged : {false, true})
    {
        PagedArray<Item> array =
            paged ? PagedArray<Item>(PagedStore(sizeof(Item), dir, "test-items", 1)) : PagedArray<Item>();
        for (size_t i = 0; i < kItems;)
        {
            std::vector<Item> some;
            for (size_t k = 0; k < (i % 3 == 0 ? 1 : 333) && i < kItems; ++k, ++i)
                some.push_back(expected(i));
            array.append(some);
        }
        array.finish();
        EXPECT_EQ(array.store().paged(), paged);
        EXPECT_TRUE(fs::is_empty(dir)) << "the file is left in its directory";
        ASSERT_EQ(array.size(), kItems);
        // In order, then at random from every thread, through a shared cache of one page.
        size_t wrong = 0;
        for (size_t i = 0; i < kItems; ++i)
            wrong += array[i].a != expected(i).a || array[i].c != expected(i).c;
        EXPECT_EQ(wrong, 0u) << paged;
        EXPECT_EQ(wrong_reads(array, 200000), 0u) << paged;
        // A copy shares the items; in_memory() gives them in memory, read back from the file.
        const PagedArray<Item> copy = array, loaded = array.in_memory();
        EXPECT_EQ(copy[kItems - 1].b, expected(kItems - 1).b);
        EXPECT_FALSE(loaded.store().paged());
        EXPECT_EQ(wrong_reads(loaded, 100000), 0u) << paged;
        EXPECT_THROW(array.push_back(expected(0)), std::logic_error);
        EXPECT_EQ(array.store().cache_bytes(2),
                  paged ? (1 + 2 * PagedStore::kLocalPages) * PagedStore::kPageItems * sizeof(Item) : 0u);
    }
}

TEST(PagedArray, ADirectoryThatCannotHoldTheFileIsNamed)
{
    const fs::path missing = hemi::test::temp_dir("paged_array_test") / "no" / "such";
    try
    {
        PagedStore(sizeof(Item), missing, "test-items", 4);
        ADD_FAILURE() << "no error";
    }
    catch (const hemi::io::FormatError& e)
    {
        EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
    }
}
