#include <hemi/bake/paged_array.h>
#include <hemi/io/image.h> // io::FormatError
#include <hemi/io/memory.h>

#include <tbb/enumerable_thread_specific.h>

#include <fcntl.h>
#include <unistd.h>
// Header-only xxHash (Debian libxxhash-dev), as io/asset.cpp uses it: no link dependency.
#define XXH_INLINE_ALL
#include <xxhash.h>

#include <array>
#include <cerrno>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace hemi::bake
{

using Page = std::vector<std::byte>;

struct PagedStore::Impl
{
    uint32_t item_bytes = 0;
    size_t items = 0;
    bool finished = false;
    // In memory: chunks of kChunkItems items, the last one filled up to `items`.
    std::vector<std::unique_ptr<std::byte[]>> chunks;
    std::vector<const std::byte*> chunk_pointers;
    // In a file.
    int fd = -1;
    std::filesystem::path path;
    size_t cache_pages = 0;
    Page pending; // the page being appended to
    std::vector<uint64_t> checksums;
    mutable std::mutex mutex;
    mutable std::unordered_map<size_t, std::shared_ptr<const Page>> cache;
    mutable std::deque<size_t> order; // the cached pages, oldest first
    struct Local
    {
        std::array<size_t, kLocalPages> page;
        std::array<std::shared_ptr<const Page>, kLocalPages> data;
        Local() { page.fill(SIZE_MAX); }
    };
    mutable tbb::enumerable_thread_specific<Local> local;

    ~Impl()
    {
        if (fd >= 0)
            ::close(fd);
    }

    size_t page_bytes() const { return kPageItems * item_bytes; }

    [[noreturn]] void fail(const std::string& what, int error) const
    {
        throw io::FormatError(path.string() + ": " + what + ": " +
                              (error ? std::strerror(error) : "unknown I/O error"));
    }

    void write_page(size_t p)
    {
        checksums.push_back(XXH64(pending.data(), pending.size(), 0));
        const uint64_t at = uint64_t(p) * page_bytes();
        size_t done = 0;
        while (done < pending.size())
        {
            errno = 0;
            const ssize_t w = ::pwrite(fd, pending.data() + done, pending.size() - done, off_t(at + done));
            if (w < 0 && errno == EINTR)
                continue;
            if (w <= 0)
                fail("writing " + std::to_string(pending.size()) + " bytes of the bake's temporary " +
                         "texel data at byte " + std::to_string(at + done) + " (" +
                         io::format_bytes(at + pending.size()) + " in all so far)",
                     errno);
            done += size_t(w);
        }
        pending.clear();
    }

    std::shared_ptr<const Page> load(size_t p) const
    {
        const size_t first = p * kPageItems;
        const size_t bytes = std::min(kPageItems, items - first) * item_bytes;
        auto page = std::make_shared<Page>(bytes);
        size_t done = 0;
        while (done < bytes)
        {
            errno = 0;
            const ssize_t r =
                ::pread(fd, page->data() + done, bytes - done, off_t(uint64_t(p) * page_bytes() + done));
            if (r < 0 && errno == EINTR)
                continue;
            if (r <= 0)
                fail("reading back the bake's temporary texel data (page " + std::to_string(p) + ")",
                     r == 0 ? EIO : errno);
            done += size_t(r);
        }
        if (XXH64(page->data(), page->size(), 0) != checksums[p])
            throw io::FormatError(path.string() +
                                  ": the bake's temporary texel data came back altered from " +
                                  "the disk (items " + std::to_string(first) + " to " +
                                  std::to_string(first + bytes / item_bytes - 1) + ")");
        return page;
    }

    std::shared_ptr<const Page> shared(size_t p) const
    {
        if (!finished)
            throw std::logic_error("PagedStore::read before finish");
        const std::lock_guard lock(mutex);
        if (auto it = cache.find(p); it != cache.end())
            return it->second;
        std::shared_ptr<const Page> page = load(p);
        cache.emplace(p, page);
        order.push_back(p);
        while (order.size() > cache_pages)
        {
            cache.erase(order.front());
            order.pop_front();
        }
        return page;
    }
};

PagedStore::PagedStore(uint32_t item_bytes) : impl_(std::make_shared<Impl>())
{
    impl_->item_bytes = item_bytes;
}

PagedStore::PagedStore(uint32_t item_bytes, const std::filesystem::path& directory, const std::string& name,
                       size_t cache_pages)
    : impl_(std::make_shared<Impl>())
{
    Impl& m = *impl_;
    m.item_bytes = item_bytes;
    m.cache_pages = std::max<size_t>(cache_pages, 1);
    std::string pattern =
        (directory.empty() ? std::filesystem::path(".") : directory).string() + "/.hemi-" + name + "-XXXXXX";
    errno = 0;
    m.fd = ::mkostemp(pattern.data(), O_CLOEXEC); // no child keeps the file alive
    m.path = pattern;
    if (m.fd < 0)
        m.fail("cannot make the bake's temporary file for its " + name, errno);
    // Gone from the directory at once: the open descriptor keeps it until the bake ends, however it ends.
    ::unlink(pattern.c_str());
    m.pending.reserve(m.page_bytes());
}

void PagedStore::append(std::span<const std::byte> bytes)
{
    Impl& m = *impl_;
    if (m.finished)
        throw std::logic_error("PagedStore::append after finish");
    if (bytes.size() % m.item_bytes)
        throw std::invalid_argument("PagedStore::append: not whole items");
    if (m.fd < 0)
    {
        const size_t chunk_bytes = kChunkItems * m.item_bytes;
        while (!bytes.empty())
        {
            const size_t at = m.items % kChunkItems;
            if (at == 0)
            {
                m.chunks.push_back(std::make_unique_for_overwrite<std::byte[]>(chunk_bytes));
                m.chunk_pointers.push_back(m.chunks.back().get());
            }
            const size_t take = std::min(bytes.size(), chunk_bytes - at * m.item_bytes);
            std::memcpy(m.chunks.back().get() + at * m.item_bytes, bytes.data(), take);
            m.items += take / m.item_bytes;
            bytes = bytes.subspan(take);
        }
        return;
    }
    m.items += bytes.size() / m.item_bytes;
    while (!bytes.empty())
    {
        const size_t take = std::min(bytes.size(), m.page_bytes() - m.pending.size());
        m.pending.insert(m.pending.end(), bytes.begin(), bytes.begin() + ptrdiff_t(take));
        bytes = bytes.subspan(take);
        if (m.pending.size() == m.page_bytes())
            m.write_page(m.checksums.size());
    }
}

void PagedStore::finish()
{
    Impl& m = *impl_;
    if (m.finished)
        return;
    if (m.fd >= 0 && !m.pending.empty())
        m.write_page(m.checksums.size());
    Page().swap(m.pending);
    m.finished = true;
    chunks_ = m.fd < 0 && !m.chunk_pointers.empty() ? m.chunk_pointers.data() : nullptr;
}

size_t PagedStore::size() const
{
    return impl_ ? impl_->items : 0;
}

bool PagedStore::paged() const
{
    return impl_ && impl_->fd >= 0;
}

uint32_t PagedStore::item_bytes() const
{
    return impl_ ? impl_->item_bytes : 0;
}

std::filesystem::path PagedStore::path() const
{
    return impl_ ? impl_->path : std::filesystem::path();
}

uint64_t PagedStore::cache_bytes(size_t threads) const
{
    if (!paged())
        return 0;
    return uint64_t(impl_->cache_pages + threads * kLocalPages) * impl_->page_bytes();
}

PagedStore PagedStore::in_memory() const
{
    if (!paged())
        return *this;
    const Impl& m = *impl_;
    PagedStore out(m.item_bytes);
    for (size_t p = 0; p * kPageItems < m.items; ++p)
    {
        const std::shared_ptr<const Page> page = m.shared(p);
        out.append(*page);
    }
    out.finish();
    return out;
}

void PagedStore::read(size_t i, std::byte* out) const
{
    const Impl& m = *impl_;
    if (m.fd < 0)
    {
        std::memcpy(out, m.chunk_pointers[i / kChunkItems] + (i % kChunkItems) * m.item_bytes, m.item_bytes);
        return;
    }
    const size_t p = i / kPageItems, slot = p % kLocalPages;
    Impl::Local& local = m.local.local();
    if (local.page[slot] != p)
    {
        local.data[slot] = m.shared(p);
        local.page[slot] = p;
    }
    std::memcpy(out, local.data[slot]->data() + (i - p * kPageItems) * m.item_bytes, m.item_bytes);
}

} // namespace hemi::bake
