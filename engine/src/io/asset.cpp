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
#include <vector>

namespace hemi::io
{
namespace
{
constexpr char kMagic[8] = {'H', 'E', 'M', 'I', 'A', 'S', 'E', 'T'};
constexpr size_t kNameBytes = 32;
constexpr size_t kHeaderBytes = 16;
constexpr size_t kEntryBytes = kNameBytes + 16;

// resize + memcpy rather than insert: GCC 12 warns falsely (-Wstringop-overflow) on inserting into an
// empty vector of std::byte.
void put_bytes(std::vector<std::byte>& out, const void* p, size_t n)
{
    const size_t at = out.size();
    out.resize(at + n);
    if (n)
        std::memcpy(out.data() + at, p, n);
}

template <typename T> void put(std::vector<std::byte>& out, T v)
{
    put_bytes(out, &v, sizeof(T));
}

template <typename T> T get(const std::vector<std::byte>& in, size_t at)
{
    T v;
    std::memcpy(&v, in.data() + at, sizeof(T));
    return v;
}
} // namespace

void AssetWriter::add(const std::string& name, std::span<const std::byte> bytes)
{
    if (name.empty() || name.size() >= kNameBytes)
        throw std::invalid_argument("hemi: asset section name '" + name + "' must have 1 to 31 bytes");
    for (const auto& s : sections_)
        if (s.first == name)
            throw std::invalid_argument("hemi: asset section '" + name + "' added twice");
    sections_.emplace_back(name, std::vector<std::byte>(bytes.begin(), bytes.end()));
}

void AssetWriter::write(const std::filesystem::path& path) const
{
    std::vector<std::byte> out;
    put_bytes(out, kMagic, 8);
    put<uint32_t>(out, kAssetVersion);
    put<uint32_t>(out, uint32_t(sections_.size()));
    uint64_t offset = kHeaderBytes + kEntryBytes * sections_.size();
    for (const auto& [name, bytes] : sections_)
    {
        char padded[kNameBytes] = {};
        std::memcpy(padded, name.data(), name.size());
        put_bytes(out, padded, kNameBytes);
        put<uint64_t>(out, offset);
        put<uint64_t>(out, bytes.size());
        offset += bytes.size();
    }
    for (const auto& s : sections_)
        put_bytes(out, s.second.data(), s.second.size());
    put<uint64_t>(out, XXH64(out.data(), out.size(), 0));
    write_atomically(path,
                     [&](const std::filesystem::path& tmp)
                     {
                         std::ofstream f(tmp, std::ios::binary);
                         errno = 0;
                         f.write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size()));
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

void AssetReader::parse()
{
    if (data_.size() < 8 || std::memcmp(data_.data(), kMagic, 8) != 0)
        throw FormatError(file_ + ": not a hemi asset (wrong magic)");
    if (data_.size() < kHeaderBytes + 8)
        throw FormatError(file_ + ": truncated (" + std::to_string(data_.size()) + " bytes)");
    version_ = get<uint32_t>(data_, 8);
    if (version_ != kAssetVersion)
        throw FormatError(file_ + ": asset version " + std::to_string(version_) +
                          " is not supported (this hemi reads " + std::to_string(kAssetVersion) + ")");
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
