#include <hemi/io/image.h>
#include <hemi/io/memory.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <sys/resource.h>
#include <thread>

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

} // namespace

uint64_t parse_bytes(std::string_view text)
{
    // Digits, an optional fraction, an optional unit K, M, G or T, then nothing, "B" or (after a unit) "iB":
    // nothing else (no sign, space, exponent, hexadecimal, "inf" or "nan" that strtod would take).
    size_t at = 0;
    auto digits = [&]
    {
        const size_t from = at;
        while (at < text.size() && text[at] >= '0' && text[at] <= '9')
            ++at;
        return at > from;
    };
    if (!digits())
        return 0;
    if (at < text.size() && text[at] == '.' && (++at, !digits()))
        return 0;
    const double v = std::strtod(std::string(text.substr(0, at)).c_str(), nullptr);
    double scale = 1.0;
    if (at < text.size())
        switch (text[at])
        {
        case 'K':
        case 'k':
            scale = 1024.0;
            break;
        case 'M':
        case 'm':
            scale = 1024.0 * 1024.0;
            break;
        case 'G':
        case 'g':
            scale = 1024.0 * 1024.0 * 1024.0;
            break;
        case 'T':
        case 't':
            scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
            break;
        default:
            break;
        }
    if (scale > 1.0)
        ++at;
    const std::string_view rest = text.substr(at);
    if (!(rest.empty() || rest == "B" || (scale > 1.0 && rest == "iB")))
        return 0;
    if (!(v > 0.0) || !(v * scale < 1.8e19) || v * scale < 1.0)
        return 0;
    return uint64_t(v * scale);
}

uint64_t available_memory()
{
    uint64_t available = proc_field("/proc/meminfo", "MemAvailable");
    if (const char* environment = std::getenv("HEMI_MEMORY_BUDGET"))
    {
        const uint64_t budget = parse_bytes(environment);
        if (!budget) // a budget that is not one is not ignored: the job would take all the machine has
            throw std::invalid_argument("HEMI_MEMORY_BUDGET=" + std::string(environment) +
                                        ": not a size (bytes, or a number with K, M, G or T: 8G, 1.5GiB)");
        available = available ? std::min(available, budget) : budget;
    }
    auto lower = [&](int resource, const char* used_key, uint64_t reserved)
    {
        rlimit limit{};
        if (getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
            return;
        const uint64_t used = proc_field("/proc/self/status", used_key) + reserved;
        const uint64_t room = uint64_t(limit.rlim_cur) > used ? uint64_t(limit.rlim_cur) - used : 0;
        available = available ? std::min(available, room) : room;
    };
    lower(RLIMIT_AS, "VmSize", reserved_address_space());
    lower(RLIMIT_DATA, "VmData", 0);
    return available;
}

uint64_t reserved_address_space()
{
    const uint64_t mib = uint64_t(1) << 20;
    const uint64_t threads = std::max(1u, std::thread::hardware_concurrency());
    rlimit stack{};
    const uint64_t stack_bytes = getrlimit(RLIMIT_STACK, &stack) == 0 && stack.rlim_cur != RLIM_INFINITY
                                     ? std::min<uint64_t>(stack.rlim_cur, 64 * mib)
                                     : 8 * mib;
    return 128 * mib + threads * stack_bytes;
}

uint64_t resident_memory()
{
    return proc_field("/proc/self/status", "VmRSS");
}

uint64_t peak_memory()
{
    if (const uint64_t hwm = proc_field("/proc/self/status", "VmHWM"))
        return hwm;
    rusage usage{};
    return getrusage(RUSAGE_SELF, &usage) == 0 ? uint64_t(usage.ru_maxrss) * 1024 : 0;
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
        {
            return uint64_t(head[at]) << 24 | uint64_t(head[at + 1]) << 16 | uint64_t(head[at + 2]) << 8 |
                   head[at + 3];
        };
        return be32(16) * be32(20);
    }
    if (head[0] == 0x76 && head[1] == 0x2f && head[2] == 0x31 && head[3] == 0x01)
    {
        // The first part's header, read as bytes: attributes "name\0type\0<int32 size><value>" until an
        // empty name; the data window is a box2i (four int32). Nothing is allocated from a declared size
        // (read_exr checks the rest of the file before OpenEXR sees it).
        in.clear();
        in.seekg(8);
        auto read_name = [&](std::string& out)
        {
            out.clear();
            for (char c; in.get(c);)
            {
                if (c == '\0')
                    return true;
                if (out.size() >= 255)
                    return false;
                out.push_back(c);
            }
            return false;
        };
        std::string name, type;
        uint64_t data = 0, display = 0; // the last of each, as OpenEXR keeps the last
        for (int attributes = 0; attributes < 4096 && read_name(name) && !name.empty(); ++attributes)
        {
            unsigned char size_bytes[4];
            if (!read_name(type) || !in.read(reinterpret_cast<char*>(size_bytes), 4))
                return 0;
            const uint32_t size = uint32_t(size_bytes[0]) | uint32_t(size_bytes[1]) << 8 |
                                  uint32_t(size_bytes[2]) << 16 | uint32_t(size_bytes[3]) << 24;
            if ((name == "dataWindow" || name == "displayWindow") && type == "box2i" && size == 16)
            {
                unsigned char box[16];
                if (!in.read(reinterpret_cast<char*>(box), 16))
                    return 0;
                auto i32 = [&](int at)
                {
                    return int32_t(uint32_t(box[at]) | uint32_t(box[at + 1]) << 8 |
                                   uint32_t(box[at + 2]) << 16 | uint32_t(box[at + 3]) << 24);
                };
                const int64_t w = int64_t(i32(8)) - i32(0) + 1, h = int64_t(i32(12)) - i32(4) + 1;
                (name == "dataWindow" ? data : display) = w > 0 && h > 0 ? uint64_t(w) * uint64_t(h) : 0;
                continue;
            }
            in.seekg(std::streamoff(size), std::ios::cur);
            if (!in)
                return 0;
        }
        // read_exr returns the display window (the data placed inside it): the larger is what it holds.
        return std::max(data, display);
    }
    return 0;
}

} // namespace hemi::io
