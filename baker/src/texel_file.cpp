#include <hemi/bake/texel_file.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h> // io::FormatError

#include <fcntl.h>
#include <unistd.h>
// Header-only xxHash (Debian libxxhash-dev), as io/asset.cpp uses it: no link dependency.
#define XXH_INLINE_ALL
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::bake
{
namespace
{
constexpr char kMagic[8] = {'H', 'E', 'M', 'I', 'T', 'I', 'L', 'E'};
constexpr uint32_t kVersion = 2; // 2: a checksum per block of items
constexpr uint64_t kHeaderBytes = 64;
constexpr size_t kMaxFields = 8;
constexpr int kCopies = 2;

struct Header
{
    char magic[8];
    uint32_t version, items;
    uint64_t key;
    uint32_t fields, copies;
    uint32_t field_bytes[kMaxFields];
};
static_assert(sizeof(Header) == kHeaderBytes);

std::string errno_text()
{
    return errno ? std::strerror(errno) : "unknown I/O error";
}
} // namespace

TexelFile::TexelFile(std::filesystem::path path, uint64_t key, uint32_t items,
                     std::vector<uint32_t> field_bytes, bool resume)
    : path_(std::move(path)), items_(items), field_bytes_(std::move(field_bytes))
{
    if (field_bytes_.empty() || field_bytes_.size() > kMaxFields)
        throw std::invalid_argument("a texel file holds 1 to 8 arrays");
    Header header{};
    std::memcpy(header.magic, kMagic, 8);
    header.version = kVersion;
    header.items = items;
    header.key = key;
    header.fields = uint32_t(field_bytes_.size());
    header.copies = kCopies;
    for (size_t f = 0; f < field_bytes_.size(); ++f)
        header.field_bytes[f] = field_bytes_[f];
    errno = 0;
    if (resume)
    {
        std::string open_error;
        try
        {
            fd_ = io::open_existing_file(path_); // no link at its name followed
        }
        catch (const io::FormatError& e)
        {
            fd_ = -1;
            open_error = e.what();
        }
        Header found{};
        if (fd_ < 0 || ::pread(fd_, &found, sizeof found, 0) != ssize_t(sizeof found) ||
            std::memcmp(&found, &header, sizeof header) != 0 || bytes() > uint64_t(lseek(fd_, 0, SEEK_END)))
        {
            const std::string why = fd_ < 0 ? "missing or not a regular file (" + open_error + ")"
                                            : "from another bake or cut short";
            if (fd_ >= 0)
                ::close(fd_);
            fd_ = -1;
            keep_ = true;
            throw io::FormatError(path_.string() + ": the checkpoint's tiles are " + why +
                                  "; remove the checkpoint (ASSET.partial) to bake afresh");
        }
        return;
    }
    try
    {
        fd_ = io::create_new_file(path_); // new and exclusive: no link planted at its name is followed
    }
    catch (const io::FormatError& e)
    {
        keep_ = true; // nothing of ours to remove
        throw io::FormatError(std::string(e.what()) + " (the bake's tile file)");
    }
    int allocated = 0;
    if (::pwrite(fd_, &header, sizeof header, 0) != ssize_t(sizeof header) ||
        (allocated = ::posix_fallocate(fd_, 0, off_t(bytes()))) != 0)
    {
        const std::string why = allocated ? std::strerror(allocated) : errno_text();
        ::close(fd_);
        fd_ = -1;
        std::error_code ignored;
        std::filesystem::remove(path_, ignored);
        keep_ = true;
        throw io::FormatError(path_.string() + ": cannot make room for the bake's tiles (" +
                              std::to_string(bytes() >> 20) + " MiB): " + why);
    }
}

TexelFile::~TexelFile()
{
    if (fd_ >= 0)
        ::close(fd_);
    if (!keep_)
    {
        std::error_code ignored;
        std::filesystem::remove(path_, ignored);
    }
}

uint64_t TexelFile::blocks() const
{
    return (uint64_t(items_) + kBlockItems - 1) / kBlockItems;
}

uint64_t TexelFile::bytes() const
{
    uint64_t per_item = 0;
    for (uint32_t b : field_bytes_)
        per_item += b;
    return kHeaderBytes + kCopies * per_item * items_ + kCopies * field_bytes_.size() * blocks() * 8;
}

uint64_t TexelFile::checksum_offset(int copy, size_t field, uint64_t block) const
{
    uint64_t per_item = 0;
    for (uint32_t b : field_bytes_)
        per_item += b;
    return kHeaderBytes + kCopies * per_item * items_ +
           ((uint64_t(copy) * field_bytes_.size() + field) * blocks() + block) * 8;
}

uint64_t TexelFile::offset(int copy, size_t field, uint32_t first, size_t count) const
{
    if (copy < 0 || copy >= kCopies || field >= field_bytes_.size() || uint64_t(first) + count > items_)
        throw std::out_of_range(path_.string() + ": items out of the tile file's range");
    uint64_t per_item = 0, before = 0;
    for (size_t f = 0; f < field_bytes_.size(); ++f)
    {
        per_item += field_bytes_[f];
        if (f < field)
            before += field_bytes_[f];
    }
    return kHeaderBytes + uint64_t(copy) * per_item * items_ + before * items_ +
           uint64_t(first) * field_bytes_[field];
}

namespace
{
// All `size` bytes at `at` through pread or pwrite (`move`), again after a signal or a short transfer; a
// failure, or the end of the file, throws naming `path` and `what` was done.
template <typename Move, typename Byte>
void transfer(int fd, Byte* data, size_t size, uint64_t at, Move move, const std::filesystem::path& path,
              const char* what)
{
    for (size_t done = 0; done < size;)
    {
        errno = 0;
        const ssize_t n = move(fd, data + done, size - done, off_t(at));
        if (n <= 0)
        {
            if (n < 0 && errno == EINTR)
                continue;
            throw io::FormatError(path.string() + ": " + what + " failed: " +
                                  (n == 0 ? std::string("the file is cut short") : errno_text()));
        }
        done += size_t(n);
        at += uint64_t(n);
    }
}
} // namespace

namespace
{
// A block's checksum as stored: 0 is kept for a block never written.
uint64_t block_checksum(const std::byte* data, size_t size)
{
    const uint64_t h = XXH64(data, size, 0);
    return h ? h : 1;
}
} // namespace

// The checksums of the blocks that items [first, first + count) touch, in `out` (blocks first / kBlockItems
// on): from `bytes` (those items' bytes) where a block lies inside them, else from the block read whole.
void TexelFile::checksums(int copy, size_t field, uint32_t first, std::span<const std::byte> bytes,
                          std::vector<uint64_t>& out) const
{
    const size_t item_bytes = field_bytes_[field];
    const uint64_t count = bytes.size() / item_bytes;
    out.clear();
    std::vector<std::byte> whole;
    for (uint64_t b = first / kBlockItems; b * kBlockItems < uint64_t(first) + count; ++b)
    {
        const uint64_t lo = b * kBlockItems, hi = std::min<uint64_t>(lo + kBlockItems, items_);
        if (lo >= first && hi <= uint64_t(first) + count)
            out.push_back(block_checksum(bytes.data() + (lo - first) * item_bytes, (hi - lo) * item_bytes));
        else
        {
            whole.resize((hi - lo) * item_bytes);
            transfer(fd_, whole.data(), whole.size(), offset(copy, field, uint32_t(lo), hi - lo), ::pread,
                     path_, "reading the bake's tiles back");
            out.push_back(block_checksum(whole.data(), whole.size()));
        }
    }
}

void TexelFile::write(int copy, size_t field, uint32_t first, std::span<const std::byte> bytes)
{
    const uint64_t at = offset(copy, field, first, bytes.size() / field_bytes_.at(field));
    transfer(fd_, bytes.data(), bytes.size(), at, ::pwrite, path_, "writing the bake's tiles");
    // Then the checksums of the blocks it touched (a block it covers in part is hashed whole, as written).
    std::vector<uint64_t> sums;
    checksums(copy, field, first, bytes, sums);
    if (!sums.empty())
        transfer(fd_, reinterpret_cast<const std::byte*>(sums.data()), sums.size() * 8,
                 checksum_offset(copy, field, first / kBlockItems), ::pwrite, path_,
                 "writing the bake's tiles");
}

void TexelFile::read(int copy, size_t field, uint32_t first, std::span<std::byte> bytes) const
{
    const uint64_t at = offset(copy, field, first, bytes.size() / field_bytes_.at(field));
    transfer(fd_, bytes.data(), bytes.size(), at, ::pread, path_, "reading the bake's tiles back");
    std::vector<uint64_t> sums, stored;
    checksums(copy, field, first, bytes, sums);
    stored.resize(sums.size());
    if (!sums.empty())
        transfer(fd_, reinterpret_cast<std::byte*>(stored.data()), stored.size() * 8,
                 checksum_offset(copy, field, first / kBlockItems), ::pread, path_,
                 "reading the bake's tiles back");
    for (size_t i = 0; i < sums.size(); ++i)
        if (sums[i] != stored[i])
        {
            const uint64_t lo = (first / kBlockItems + i) * kBlockItems;
            throw io::FormatError(path_.string() + ": the bake's tiles are damaged (copy " +
                                  std::to_string(copy) + ", array " + std::to_string(field) + ", items " +
                                  std::to_string(lo) + " to " +
                                  std::to_string(std::min<uint64_t>(lo + kBlockItems, items_) - 1) +
                                  (stored[i] ? " do not match their checksum" : " were never written") +
                                  "); remove the checkpoint (ASSET.partial) and the tiles to bake afresh");
        }
}

void TexelFile::sync()
{
    errno = 0;
    if (::fdatasync(fd_) != 0)
        throw io::FormatError(path_.string() + ": syncing the bake's tiles to disk failed: " + errno_text());
}

} // namespace hemi::bake
