#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <atomic>
#include <system_error>
#include <fcntl.h>
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
    // Durable before visible: the data reaches the disk before the rename publishes it.
    if (int fd = ::open(tmp.c_str(), O_RDONLY); fd >= 0)
    {
        int rc = ::fsync(fd);
        ::close(fd);
        if (rc != 0)
        {
            std::error_code ignored;
            std::filesystem::remove(tmp, ignored);
            throw FormatError(path.string() + ": writing failed (fsync)");
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec)
    {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw FormatError(path.string() + ": cannot rename the finished temporary file into place: " + ec.message());
    }
    std::filesystem::path dir = path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    if (int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY); fd >= 0)
    {
        ::fsync(fd); // best effort: the rename itself is already atomic
        ::close(fd);
    }
}

} // namespace hemi::io
