#include <hemi/io/image.h>
#include <hemi/io/memory.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/resource.h>

#include <ImfHeader.h>
#include <ImfInputFile.h>

namespace hemi::io
{
namespace
{
// A field of /proc/self/status or /proc/meminfo, in bytes ("VmSize:  1234 kB"); 0 when absent.
uint64_t proc_field(const char* file, const std::string& key)
{
    std::ifstream in(file);
    for (std::string line; std::getline(in, line);)
        if (line.rfind(key + ":", 0) == 0)
        {
            std::istringstream fields(line.substr(key.size() + 1));
            uint64_t kib = 0;
            fields >> kib;
            return kib * 1024;
        }
    return 0;
}

// HEMI_MEMORY_BUDGET: bytes, or a number with K, M, G or T (binary units); 0 when unset or malformed.
uint64_t budget_from_environment()
{
    const char* text = std::getenv("HEMI_MEMORY_BUDGET");
    if (!text || !*text)
        return 0;
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    double scale = 1.0;
    switch (*end)
    {
    case 'K': case 'k': scale = 1024.0; ++end; break;
    case 'M': case 'm': scale = 1024.0 * 1024.0; ++end; break;
    case 'G': case 'g': scale = 1024.0 * 1024.0 * 1024.0; ++end; break;
    case 'T': case 't': scale = 1024.0 * 1024.0 * 1024.0 * 1024.0; ++end; break;
    default: break;
    }
    if (*end == 'i' || *end == 'B')
        ++end;
    if (*end == 'B')
        ++end;
    if (*end != '\0' || !(v > 0.0) || !(v * scale < 1.8e19))
        return 0;
    return uint64_t(v * scale);
}
} // namespace

uint64_t available_memory()
{
    uint64_t available = proc_field("/proc/meminfo", "MemAvailable");
    if (const uint64_t budget = budget_from_environment())
        available = available ? std::min(available, budget) : budget;
    auto lower = [&](int resource, const char* used_key)
    {
        rlimit limit{};
        if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
            return;
        const uint64_t used = proc_field("/proc/self/status", used_key);
        const uint64_t room = uint64_t(limit.rlim_cur) > used ? uint64_t(limit.rlim_cur) - used : 0;
        available = available ? std::min(available, room) : room;
    };
    lower(RLIMIT_AS, "VmSize");
    lower(RLIMIT_DATA, "VmData");
    return available;
}

std::string format_bytes(uint64_t bytes)
{
    char text[32];
    const double b = double(bytes);
    if (b >= 1024.0 * 1024.0 * 1024.0)
        std::snprintf(text, sizeof text, "%.2f GiB", b / (1024.0 * 1024.0 * 1024.0));
    else if (b >= 1024.0 * 1024.0)
        std::snprintf(text, sizeof text, "%.1f MiB", b / (1024.0 * 1024.0));
    else if (b >= 1024.0)
        std::snprintf(text, sizeof text, "%.1f KiB", b / 1024.0);
    else
        std::snprintf(text, sizeof text, "%llu B", (unsigned long long)bytes);
    return text;
}

void check_memory(uint64_t bytes, const std::string& what)
{
    const uint64_t available = available_memory();
    if (available != 0 && bytes > available)
        throw FormatError(what + ": needs about " + format_bytes(bytes) + " of memory, but only " +
                          format_bytes(available) + " is available");
}

uint64_t image_pixels(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    unsigned char head[24] = {};
    if (!in.read(reinterpret_cast<char*>(head), sizeof head))
        return 0;
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (std::equal(png, png + 8, head) && std::equal(head + 12, head + 16, "IHDR"))
    {
        auto be32 = [&](int at)
        { return uint64_t(head[at]) << 24 | uint64_t(head[at + 1]) << 16 | uint64_t(head[at + 2]) << 8 | head[at + 3]; };
        return be32(16) * be32(20);
    }
    if (head[0] == 0x76 && head[1] == 0x2f && head[2] == 0x31 && head[3] == 0x01)
    {
        try
        {
            const Imf::InputFile file(path.c_str());
            const Imath::Box2i w = file.header().dataWindow();
            if (w.max.x < w.min.x || w.max.y < w.min.y)
                return 0;
            return (uint64_t(int64_t(w.max.x) - w.min.x) + 1) * (uint64_t(int64_t(w.max.y) - w.min.y) + 1);
        }
        catch (...)
        {
            return 0; // the reader says what is wrong
        }
    }
    return 0;
}

} // namespace hemi::io
