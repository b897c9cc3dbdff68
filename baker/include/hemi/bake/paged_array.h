#pragma once
// An array that a bake writes once, in order, and then reads by index from any thread: held in memory, or,
// for a bake larger than its memory budget, in a temporary file read back a page at a time through a cache
// of a bounded size (issue 45: the atlas's texel records and slot indices of a level of 10^8 texels take
// 2 GB; in pages they take the cache's few MiB, whatever the level).
//
// The file is made in a given directory (beside the bake's asset and tile file: the disk the user chose for
// it) and removed from the directory at once, kept open: nothing is left behind when the bake is killed, and
// nothing else finds it. Each page's checksum (XXH64) is kept in memory and checked when the page is read
// back: a page the disk gives back altered throws io::FormatError naming the file, as does any failed read
// or write (a full disk names it and how much it needed).
//
// In memory the items are kept in chunks of kChunkItems (no array is copied as it grows: what it holds is
// its items and at most one chunk more). Reads: each thread keeps the last few pages it read (kLocalPages,
// direct-mapped by page), the rest come from a cache shared by the threads (cache_pages, the oldest dropped
// first) or the file. A copy of a PagedArray shares its items (copy a finished one: a copy taken before
// finish() sees later appends but reads through read(), not inline).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace hemi::bake
{

class PagedStore
{
  public:
    static constexpr size_t kPageItems = 1024;
    static constexpr size_t kLocalPages = 8;
    static constexpr unsigned kChunkShift = 16;
    static constexpr size_t kChunkItems = size_t(1) << kChunkShift;

    PagedStore() = default;
    PagedStore(const PagedStore&) = default;
    PagedStore& operator=(const PagedStore&) = default;
    PagedStore(PagedStore&& o) noexcept
        : impl_(std::move(o.impl_)), chunks_(std::exchange(o.chunks_, nullptr))
    {
    }
    PagedStore& operator=(PagedStore&& o) noexcept
    {
        impl_ = std::move(o.impl_);
        chunks_ = std::exchange(o.chunks_, nullptr);
        return *this;
    }
    // In memory.
    explicit PagedStore(uint32_t item_bytes);
    // In a temporary file in `directory` (named after `name`, for messages), read back through a cache of
    // `cache_pages` pages of kPageItems items.
    PagedStore(uint32_t item_bytes, const std::filesystem::path& directory, const std::string& name,
               size_t cache_pages);

    // Appends whole items (a multiple of the item's bytes). Not after finish().
    void append(std::span<const std::byte> items);
    // After the last append: the items can be read from then on.
    void finish();

    size_t size() const;
    bool paged() const;
    uint32_t item_bytes() const;
    // Item i's bytes into `out`. From any thread, once finished.
    void read(size_t i, std::byte* out) const;
    // What reading holds at most beside what it reads: the shared cache and each thread's pages (0 in
    // memory).
    uint64_t cache_bytes(size_t threads) const;
    // The same items in memory (a finished store; read back in order from the file when paged).
    PagedStore in_memory() const;
    // The file's name as messages give it (empty in memory).
    std::filesystem::path path() const;
    // The items' chunks in memory, once finished (else nullptr): what PagedArray reads inline.
    const std::byte* const* chunks() const { return chunks_; }

  private:
    struct Impl;
    std::shared_ptr<Impl> impl_;
    const std::byte* const* chunks_ = nullptr;
};

// A PagedStore of trivially copyable T.
template <class T> class PagedArray
{
    static_assert(std::is_trivially_copyable_v<T>);

  public:
    PagedArray() : store_(sizeof(T)) {}
    explicit PagedArray(PagedStore store) : store_(std::move(store)) {}

    void push_back(const T& v) { store_.append(std::as_bytes(std::span(&v, 1))); }
    void append(std::span<const T> v) { store_.append(std::as_bytes(v)); }
    void finish() { store_.finish(); }

    size_t size() const { return store_.size(); }
    bool empty() const { return size() == 0; }
    T operator[](size_t i) const
    {
        T v;
        if (const std::byte* const* c = store_.chunks())
            std::memcpy(&v, c[i >> PagedStore::kChunkShift] + (i & (PagedStore::kChunkItems - 1)) * sizeof(T),
                        sizeof(T));
        else
            store_.read(i, reinterpret_cast<std::byte*>(&v));
        return v;
    }
    // Every item (tests, small arrays).
    std::vector<T> to_vector() const
    {
        std::vector<T> out(size());
        for (size_t i = 0; i < out.size(); ++i)
            out[i] = (*this)[i];
        return out;
    }
    const PagedStore& store() const { return store_; }
    PagedArray in_memory() const { return PagedArray(store_.in_memory()); }

  private:
    PagedStore store_;
};

} // namespace hemi::bake
