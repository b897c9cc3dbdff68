#pragma once
// Per-item arrays of a bake on disk instead of in memory: what lets a bake larger than the machine's memory
// run in tiles (hemi-bake lightmap --memory-budget). A bake that keeps, per item (texel, vertex), running
// sums over its passes holds only one tile of them at a time: it reads a tile's sums of the passes before,
// adds the tile's pass and writes them back.
//
// Two copies of every array, so that writing a tile is idempotent: pass p reads copy (p - 1) % 2 and writes
// copy p % 2. A bake killed after writing some tiles of pass p and resumed from its checkpoint (which
// records only tiles whose writes were synced to disk before it was saved) recomputes the tiles after the
// checkpoint's position from the same copy (p - 1) % 2, which pass p never writes: the same bytes as an
// uninterrupted bake.
//
// The file: a 64-byte header ("HEMITILE", format version, the bake's key, items, fields, copies, each
// field's bytes per item), then copy after copy, in each the fields' arrays one after the other, then a
// checksum (XXH64) per copy, array and block of kBlockItems items, updated by every write and checked by
// every read: a file altered between a kill and the resume (a disk's fault, another program) is refused,
// naming it and the items, instead of resuming to other bytes. Its blocks
// are allocated when it is created (posix_fallocate: a disk without room for it fails then, not halfway
// through a bake); I/O by pread / pwrite; a failure throws io::FormatError naming the file.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace hemi::bake
{

class TexelFile
{
  public:
    // Creates (or truncates) `path` for `items` items of arrays of `field_bytes` bytes per item each, in two
    // copies. With `resume`, opens the existing file instead, which must have been created with the same
    // key, items and fields (a checkpoint's companion); throws io::FormatError naming it otherwise.
    TexelFile(std::filesystem::path path, uint64_t key, uint32_t items, std::vector<uint32_t> field_bytes,
              bool resume);
    ~TexelFile(); // closes; removes the file unless keep() was called
    TexelFile(const TexelFile&) = delete;
    TexelFile& operator=(const TexelFile&) = delete;

    // Items [first, first + count) of array `field` in `copy` (0 or 1), from or to `bytes`
    // (count * field_bytes[field] bytes). read() throws io::FormatError naming the file when a block it
    // reads does not match its checksum, or was never written.
    void write(int copy, size_t field, uint32_t first, std::span<const std::byte> bytes);
    void read(int copy, size_t field, uint32_t first, std::span<std::byte> bytes) const;
    // Every write so far on disk (fdatasync): before a checkpoint says the tiles written are done.
    void sync();
    // Leave the file when this object goes (a checkpoint needs it to resume), or not.
    void keep(bool keep = true) { keep_ = keep; }

    const std::filesystem::path& path() const { return path_; }
    uint32_t items() const { return items_; }
    uint64_t bytes() const; // the file's size

    static constexpr uint64_t kBlockItems = 1024; // items per checksum

  private:
    uint64_t offset(int copy, size_t field, uint32_t first, size_t count) const;
    uint64_t blocks() const;
    uint64_t checksum_offset(int copy, size_t field, uint64_t block) const;
    void checksums(int copy, size_t field, uint32_t first, std::span<const std::byte> bytes,
                   std::vector<uint64_t>& out) const;
    std::filesystem::path path_;
    uint32_t items_;
    std::vector<uint32_t> field_bytes_;
    int fd_ = -1;
    bool keep_ = false;
};

} // namespace hemi::bake
