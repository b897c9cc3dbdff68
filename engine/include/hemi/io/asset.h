#pragma once
// The baked-asset container (.hemi): named binary sections in one versioned, checksummed file, written
// atomically. The techniques define what goes in the sections; this layer only guarantees that what is read
// is exactly what was written.
//
// Layout (little-endian):
//   header   : "HEMIASET" (8 bytes), version u32, section count u32
//   table    : per section: name (32 bytes, NUL-padded), offset u64 (from the file start), size u64
//   sections : the bytes of each section, in table order, packed
//   trailer  : XXH64 (seed 0) of every preceding byte, u64
// Any changed, missing or extra byte is detected: the trailer covers the whole file.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hemi::io
{

constexpr uint32_t kAssetVersion = 1;

class AssetWriter
{
  public:
    AssetWriter();
    // Sections added from here on go to the file `spool` as they are added, not to memory, and write()
    // copies them from there: the writer then holds no section's bytes (a bake's outputs, written one at a
    // time). The spool is created (or truncated) here and removed when the writer is destroyed. Throws
    // FormatError naming the spool when it cannot be created.
    explicit AssetWriter(const std::filesystem::path& spool);
    ~AssetWriter();
    AssetWriter(const AssetWriter&) = delete;
    AssetWriter& operator=(const AssetWriter&) = delete;

    // Throws std::invalid_argument for an empty or too long (> 31 bytes) name, or a duplicate.
    void add(const std::string& name, std::span<const std::byte> bytes);
    template <typename T> void add_array(const std::string& name, std::span<const T> values)
    {
        add(name, std::as_bytes(values));
    }
    // A section of `size` bytes that `fill(offset, out)` writes out.size() bytes of at a time (in pieces of
    // at most 1 MiB when spooling, so that its bytes never exist whole in memory; else in one piece).
    void add_generated(const std::string& name, uint64_t size,
                       const std::function<void(uint64_t offset, std::span<std::byte> out)>& fill);
    // A section whose bytes are not copied: the caller keeps them, unchanged, until write() returns (a
    // checkpoint's arrays).
    void add_view(const std::string& name, std::span<const std::byte> bytes);
    // Atomic (temporary file + rename), streamed: no copy of the file is made in memory. Throws FormatError
    // naming the file on I/O failure.
    void write(const std::filesystem::path& path) const;

  private:
    struct Section;
    struct Spool;
    void check_name(const std::string& name) const;
    std::vector<Section> sections_;
    std::unique_ptr<Spool> spool_;
};

class AssetReader
{
  public:
    // Reads and validates the whole file. Throws FormatError naming the file and the problem: missing file,
    // not a hemi asset (magic), unsupported version, truncated, checksum mismatch (corrupted), or a section
    // table that points outside the file.
    explicit AssetReader(const std::filesystem::path& path);
    // The same checks on bytes in memory (copied); `name` stands for the file in errors.
    AssetReader(std::span<const std::byte> bytes, std::string name);
    const std::string& name() const { return file_; }

    uint32_t version() const { return version_; }
    bool has(const std::string& name) const { return sections_.count(name) != 0; }
    // Every section name, sorted.
    std::vector<std::string> names() const
    {
        std::vector<std::string> out;
        for (const auto& entry : sections_)
            out.push_back(entry.first);
        return out;
    }
    // Throws FormatError naming the file when the section is missing.
    std::span<const std::byte> section(const std::string& name) const;
    // The section as an array of T; throws FormatError when its size is not a multiple of sizeof(T).
    template <typename T> std::vector<T> array(const std::string& name) const
    {
        std::span<const std::byte> b = section(name);
        check_multiple(name, b.size(), sizeof(T));
        std::vector<T> out(b.size() / sizeof(T));
        if (!b.empty())
            std::memcpy(out.data(), b.data(), b.size());
        return out;
    }

  private:
    // Refuses a head that is not a hemi asset of this version (FormatError naming the file).
    void check_head(std::span<const std::byte> head) const;
    void parse();
    void check_multiple(const std::string& name, size_t size, size_t element) const;

    std::string file_;
    uint32_t version_ = 0;
    std::vector<std::byte> data_;
    std::map<std::string, std::pair<uint64_t, uint64_t>> sections_; // offset, size
};

} // namespace hemi::io
