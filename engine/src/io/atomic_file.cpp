#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <atomic>
#include <system_error>
#include <unistd.h>

namespace hemi::io
{

void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temporary)>& write)
{
    static std::atomic<unsigned> counter{0};
    std::filesystem::path tmp = path;
    tmp += ".tmp" + std::to_string(::getpid()) + "." + std::to_string(counter++);
    try
    {
        write(tmp);
    }
    catch (...)
    {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw;
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec)
    {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw FormatError(path.string() + ": cannot rename the finished temporary file into place: " + ec.message());
    }
}

} // namespace hemi::io
