#pragma once
// Memory a long job can count on, so that it refuses an input it cannot hold before it starts (naming the
// input and the estimate) instead of failing with std::bad_alloc, or being killed, after hours.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace hemi::io
{

// Bytes this process can still allocate: the kernel's MemAvailable (/proc/meminfo), lowered by the room
// left under RLIMIT_AS (less reserved_address_space()) or RLIMIT_DATA when one is set, and by the environment
// variable HEMI_MEMORY_BUDGET when it is set (bytes, or a number with K, M, G or T: "8G"; a share of a
// machine that runs other jobs). 0 when none of them can be read. Throws std::invalid_argument when
// HEMI_MEMORY_BUDGET is set to what parse_bytes does not read as a size.
uint64_t available_memory();

// Address space a bake reserves beyond what it touches, which counts against RLIMIT_AS (ulimit -v, prlimit
// --as) though not against the machine's memory: Embree's device maps 128 MiB when it is created (measured,
// Embree 3.13), and each worker thread its stack (RLIMIT_STACK, 8 MiB by default; one thread per core).
// glibc's malloc also reserves 64 MiB of address space for each arena it adds for a thread; hemi's tools
// keep to one arena when RLIMIT_AS is set (tool_options.h), and a program that links hemi under such a
// limit should set MALLOC_ARENA_MAX=1 (or mallopt(M_ARENA_MAX, 1)) likewise.
uint64_t reserved_address_space();

// The memory this process holds now (VmRSS), in bytes; 0 when unknown. What a budget for the whole
// process's peak (--memory-budget) has spent before a job's own estimate.
uint64_t resident_memory();

// The most resident memory this process has held so far (getrusage's ru_maxrss), in bytes; 0 when unknown.
uint64_t peak_memory();

// A size in bytes as a person writes it: a number of bytes (digits, an optional fraction), or one with K, M,
// G or T (binary units, optionally followed by "iB" or "B": "8G", "1.5GiB", "512M", "4096B"); 0 when `text`
// is not one (a sign, a space, an exponent, hexadecimal, "8GBB", "4Gb"), or not at least one byte.
uint64_t parse_bytes(std::string_view text);

// "1.50 GiB", "12.0 MiB", "512 B".
std::string format_bytes(uint64_t bytes);

// Throws FormatError("<what>: needs about <bytes> of memory, but only <available> is available") when an
// estimate exceeds available_memory() (nothing is refused when that is unknown).
void check_memory(uint64_t bytes, const std::string& what);

// The pixel count a PNG or EXR file declares in its header (PNG's IHDR, EXR's data window), read without
// decoding, so that a job can estimate its memory before it reads the image; 0 when the file is neither
// or its header cannot be read (the reader then says why).
uint64_t image_pixels(const std::filesystem::path& path);

} // namespace hemi::io
