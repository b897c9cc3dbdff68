#include <hemi/io/asset.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

// Header-only xxHash (Debian libxxhash-dev): no link dependency for applications of the static library.
#define XXH_INLINE_ALL
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <unistd.h>
#include <vector>

namespace hemi::io
{
namespace
{
constexpr char kMagic[8] = {'H', 'E', 'M', 'I', 'A', 'S', 'E', 'T'};
constexpr size_t kNameBytes = 32;
constexpr size_t kHeaderBytes = 16;
constexpr size_t kEntryBytes = kNameBytes + 16;

template <typename T> T get(const std::vector<std::byte>& in, size_t at)
{
    T v;
    std::memcpy(&v, in.data() + at, sizeof(T));
    return v;
}
} // namespace

struct AssetWriter::Section
{
    std::string name;
    std::vector<std::byte> owned;     // add()'s copy, without a spool
    std::span<const std::byte> bytes; // what write() writes: owned, or add_view()'s; empty when spooled
    bool spooled = false;
    uint64_t spool_offset = 0, size = 0;
};

struct AssetWriter::Spool
{
    std::filesystem::path path;
    int fd = -1; // io::create_new_file's: made new, no link followed
    uint64_t size = 0;

    // The whole of `bytes` at `offset`, or fail(what).
    void write_at(uint64_t offset, std::span<const std::byte> bytes, const std::string& what) const
    {
        for (size_t done = 0; done < bytes.size();)
        {
            errno = 0;
            const ssize_t n = ::pwrite(fd, bytes.data() + done, bytes.size() - done, off_t(offset + done));
            if (n <= 0 && errno != EINTR)
                fail(what);
            done += n > 0 ? size_t(n) : 0;
        }
    }
    void read_at(uint64_t offset, std::span<std::byte> bytes, const std::string& what) const
    {
        for (size_t done = 0; done < bytes.size();)
        {
            errno = 0;
            const ssize_t n = ::pread(fd, bytes.data() + done, bytes.size() - done, off_t(offset + done));
            if (n <= 0 && errno != EINTR)
                fail(what);
            done += n > 0 ? size_t(n) : 0;
        }
    }

    [[noreturn]] void fail(const std::string& what) const
    {
        throw FormatError(path.string() + ": " + what + " (the asset writer's spool): " +
                          (errno ? std::strerror(errno) : "unknown I/O error"));
    }
};

AssetWriter::AssetWriter() = default;

AssetWriter::AssetWriter(const std::filesystem::path& spool) : spool_(std::make_unique<Spool>())
{
    spool_->path = spool;
    spool_->fd = create_new_file(spool);
}

AssetWriter::~AssetWriter()
{
    if (spool_)
    {
        ::close(spool_->fd);
        std::error_code ignored;
        std::filesystem::remove(spool_->path, ignored);
    }
}

void AssetWriter::check_name(const std::string& name) const
{
    if (name.empty() || name.size() >= kNameBytes)
        throw std::invalid_argument("hemi: asset section name '" + name + "' must have 1 to 31 bytes");
    for (const Section& s : sections_)
        if (s.name == name)
            throw std::invalid_argument("hemi: asset section '" + name + "' added twice");
}

void AssetWriter::add(const std::string& name, std::span<const std::byte> bytes)
{
    add_generated(name, bytes.size(),
                  [&](uint64_t offset, std::span<std::byte> out)
                  {
                      if (!out.empty())
                          std::memcpy(out.data(), bytes.data() + offset, out.size());
                  });
}

void AssetWriter::add_generated(const std::string& name, uint64_t size,
                                const std::function<void(uint64_t, std::span<std::byte>)>& fill)
{
    check_name(name);
    Section s;
    s.name = name;
    s.size = size;
    if (!spool_)
    {
        s.owned.resize(size_t(size));
        fill(0, s.owned);
        sections_.push_back(std::move(s));
        sections_.back().bytes = sections_.back().owned;
        return;
    }
    s.spooled = true;
    s.spool_offset = spool_->size;
    constexpr uint64_t kPiece = uint64_t(1) << 20;
    std::vector<std::byte> piece(size_t(std::min(size, kPiece)));
    for (uint64_t at = 0; at < size; at += kPiece)
    {
        const std::span<std::byte> out(piece.data(), size_t(std::min(kPiece, size - at)));
        fill(at, out);
        spool_->write_at(spool_->size + at, out, "writing section " + name + " failed");
    }
    spool_->size += size;
    sections_.push_back(std::move(s));
}

void AssetWriter::add_view(const std::string& name, std::span<const std::byte> bytes)
{
    check_name(name);
    Section s;
    s.name = name;
    s.bytes = bytes;
    s.size = bytes.size();
    sections_.push_back(std::move(s));
}

void AssetWriter::write(const std::filesystem::path& path) const
{
    write_atomically(path,
                     [&](const std::filesystem::path& tmp)
                     {
                         std::ofstream f(tmp, std::ios::binary);
                         errno = 0;
                         XXH64_state_t hash;
                         XXH64_reset(&hash, 0);
                         auto emit = [&](const void* p, size_t n)
                         {
                             if (n == 0)
                                 return;
                             XXH64_update(&hash, p, n);
                             f.write(static_cast<const char*>(p), std::streamsize(n));
                         };
                         // The header and the table, gathered first (one hash update rather than many small
                         // ones).
                         std::vector<std::byte> head(kHeaderBytes + kEntryBytes * sections_.size());
                         std::byte* at = head.data();
                         auto put = [&](const void* p, size_t n)
                         {
                             std::memcpy(at, p, n);
                             at += n;
                         };
                         const uint32_t version = kAssetVersion, count = uint32_t(sections_.size());
                         put(kMagic, 8);
                         put(&version, 4);
                         put(&count, 4);
                         uint64_t offset = head.size();
                         for (const Section& s : sections_)
                         {
                             char padded[kNameBytes] = {};
                             std::memcpy(padded, s.name.data(), s.name.size());
                             put(padded, kNameBytes);
                             put(&offset, 8);
                             put(&s.size, 8);
                             offset += s.size;
                         }
                         emit(head.data(), head.size());
                         std::vector<std::byte> piece;
                         for (const Section& s : sections_)
                         {
                             if (!s.spooled)
                             {
                                 emit(s.bytes.data(), s.bytes.size());
                                 continue;
                             }
                             constexpr uint64_t kPiece = uint64_t(1) << 20;
                             piece.resize(size_t(std::min(s.size, kPiece)));
                             for (uint64_t done = 0; done < s.size; done += kPiece)
                             {
                                 const size_t n = size_t(std::min(kPiece, s.size - done));
                                 spool_->read_at(s.spool_offset + done, std::span<std::byte>(piece.data(), n),
                                                 "reading section " + s.name + " back failed");
                                 emit(piece.data(), n);
                             }
                         }
                         const uint64_t digest = XXH64_digest(&hash);
                         f.write(reinterpret_cast<const char*>(&digest), sizeof digest);
                         f.close();
                         if (f.fail())
                             throw FormatError(path.string() + ": writing the asset failed: " +
                                               (errno ? std::strerror(errno) : "unknown I/O error"));
                     });
}

AssetReader::AssetReader(const std::filesystem::path& path) : file_(path.string())
{
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(path, ec);
    std::ifstream f(path, std::ios::binary);
    if (ec || !f)
        throw FormatError(file_ + ": no such file or not readable");
    // The head first: a file that is no hemi asset (or of another version) is refused from its first 12
    // bytes, before a byte more of it is read or held (a 6 GB file of zeros was read whole first).
    std::byte head[12] = {};
    f.read(reinterpret_cast<char*>(head), std::streamsize(std::min<uint64_t>(bytes, sizeof head)));
    check_head(std::span<const std::byte>(head, size_t(f.gcount())));
    f.seekg(0);
    data_.resize(size_t(bytes));
    f.read(reinterpret_cast<char*>(data_.data()), std::streamsize(bytes));
    if (size_t(f.gcount()) != data_.size())
        throw FormatError(file_ + ": read error");
    parse();
}

AssetReader::AssetReader(std::span<const std::byte> bytes, std::string name)
    : file_(std::move(name)), data_(bytes.begin(), bytes.end())
{
    parse();
}

void AssetReader::check_head(std::span<const std::byte> head) const
{
    if (head.size() < 8 || std::memcmp(head.data(), kMagic, 8) != 0)
        throw FormatError(file_ + ": not a hemi asset (wrong magic)");
    if (head.size() >= 12)
    {
        uint32_t version = 0;
        std::memcpy(&version, head.data() + 8, 4);
        if (version != kAssetVersion)
            throw FormatError(file_ + ": asset version " + std::to_string(version) +
                              " is not supported (this hemi reads " + std::to_string(kAssetVersion) + ")");
    }
}

void AssetReader::parse()
{
    check_head(data_);
    if (data_.size() < kHeaderBytes + 8)
        throw FormatError(file_ + ": truncated (" + std::to_string(data_.size()) + " bytes)");
    version_ = get<uint32_t>(data_, 8);
    const uint64_t stored = get<uint64_t>(data_, data_.size() - 8);
    if (XXH64(data_.data(), data_.size() - 8, 0) != stored)
        throw FormatError(file_ + ": checksum mismatch: the file is truncated or corrupted");
    const uint32_t count = get<uint32_t>(data_, 12);
    const uint64_t body_end = data_.size() - 8;
    if (kHeaderBytes + uint64_t(count) * kEntryBytes > body_end)
        throw FormatError(file_ + ": section table of " + std::to_string(count) +
                          " entries exceeds the file");
    for (uint32_t i = 0; i < count; ++i)
    {
        const size_t at = kHeaderBytes + size_t(i) * kEntryBytes;
        char name[kNameBytes + 1] = {};
        std::memcpy(name, data_.data() + at, kNameBytes);
        const uint64_t offset = get<uint64_t>(data_, at + kNameBytes),
                       size = get<uint64_t>(data_, at + kNameBytes + 8);
        const uint64_t table_end = kHeaderBytes + uint64_t(count) * kEntryBytes;
        if (offset < table_end || offset > body_end || size > body_end - offset)
            throw FormatError(file_ + ": section '" + name + "' lies outside the file's data");
        // The writer never writes two sections of one name or overlapping sections; a file that has them
        // was made by something else, and "the last one wins" would be silent garbage.
        if (!sections_.emplace(name, std::make_pair(offset, size)).second)
            throw FormatError(file_ + ": section '" + name + "' appears twice");
    }
    std::vector<std::pair<uint64_t, uint64_t>> ranges;
    for (const auto& [name, range] : sections_)
        ranges.push_back(range);
    std::sort(ranges.begin(), ranges.end());
    for (size_t i = 1; i < ranges.size(); ++i)
        if (ranges[i - 1].first + ranges[i - 1].second > ranges[i].first)
            throw FormatError(file_ + ": sections overlap (at byte " + std::to_string(ranges[i].first) + ")");
}

std::span<const std::byte> AssetReader::section(const std::string& name) const
{
    auto it = sections_.find(name);
    if (it == sections_.end())
        throw FormatError(file_ + ": section '" + name + "' is missing");
    return {data_.data() + it->second.first, size_t(it->second.second)};
}

void AssetReader::check_multiple(const std::string& name, size_t size, size_t element) const
{
    if (size % element != 0)
        throw FormatError(file_ + ": section '" + name + "' has " + std::to_string(size) +
                          " bytes, not a multiple of " + std::to_string(element));
}

} // namespace hemi::io
