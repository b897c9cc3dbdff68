#pragma once
// Shared by hemi's libFuzzer targets: the readers take paths (they name the file in every error), so each
// input is written to a per-process file in /dev/shm (or the temporary folder) and read back. A reader may
// throw hemi::io::FormatError (the documented failure) or std::invalid_argument from a documented check;
// anything else -- another exception type, a crash, a sanitizer report, a hang -- is a finding.
#include <hemi/io/image.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

namespace hemi::fuzz
{

inline std::filesystem::path scratch(const char* extension)
{
    const std::filesystem::path dir = std::filesystem::exists("/dev/shm")
                                          ? std::filesystem::path("/dev/shm")
                                          : std::filesystem::temp_directory_path();
    return dir / ("hemi_fuzz_" + std::to_string(getpid()) + extension);
}

inline void write_file(const std::filesystem::path& p, const uint8_t* data, size_t size)
{
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
}

// Writes a .hemi container with its trailing XXH64 recomputed over the mutated bytes: the checksum would
// turn away almost every mutation before the parsers behind it.
inline void write_resealed(const std::filesystem::path& p, const uint8_t* data, size_t size)
{
    std::vector<uint8_t> bytes(data, data + size);
    if (bytes.size() >= 24)
    {
        const uint64_t sum = XXH64(bytes.data(), bytes.size() - 8, 0);
        std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
    }
    write_file(p, bytes.data(), bytes.size());
}

// Runs `read`; returns normally for the documented failures, aborts (a finding) for anything else.
template <typename F> void expect_clean(F&& read)
{
    try
    {
        read();
    }
    catch (const io::FormatError&)
    {
    }
    catch (const std::invalid_argument&)
    {
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "undocumented exception: %s\n", e.what());
        std::abort();
    }
}

} // namespace hemi::fuzz
