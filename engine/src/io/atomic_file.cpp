#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <system_error>
#include <unistd.h>

namespace hemi::io
{

std::string output_problem(const std::filesystem::path& path)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    if (!fs::exists(dir, ec))
        return "the folder " + dir.string() + " does not exist";
    if (!fs::is_directory(dir, ec))
        return dir.string() + " is not a folder";
    if (fs::is_directory(path, ec))
        return "it is a folder";
    // A device, FIFO or socket would be replaced by a regular file (the rename), or written with a partial
    // result: outputs are regular files only.
    if (fs::exists(path, ec) && !fs::is_regular_file(path, ec))
        return "it exists and is not a regular file (a device, FIFO or socket)";
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
        return "the folder " + dir.string() + " is not writable (" + std::strerror(errno) + ")";
    if (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0 && errno == EROFS)
        return "the file system is read-only";
    struct statvfs st
    {
    };
    if (::statvfs(dir.c_str(), &st) == 0 && st.f_bavail == 0)
        return "no space left on the device of " + dir.string();
    return {};
}

void check_writable(const std::filesystem::path& path)
{
    if (std::string problem = output_problem(path); !problem.empty())
        throw FormatError(path.string() + ": cannot write: " + problem);
}

std::filesystem::path OutputLock::lock_path(const std::filesystem::path& output)
{
    return output.string() + ".lock";
}

OutputLock::OutputLock(const std::filesystem::path& output) : path_(lock_path(output))
{
    // Open (or make) the lock file, take it, and check that the name still leads to the file taken: a holder
    // that finished removed its lock after another job opened it, and the taken file is then no one's.
    for (int attempt = 0; attempt < 100; ++attempt)
    {
        errno = 0;
        const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
        if (fd < 0)
            throw FormatError(path_.string() + ": cannot make the lock that keeps two jobs off " +
                              output.string() + ": " + std::strerror(errno));
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0)
        {
            const int error = errno;
            char text[32] = {};
            const ssize_t got = ::pread(fd, text, sizeof text - 1, 0);
            ::close(fd);
            if (error != EWOULDBLOCK)
                throw FormatError(path_.string() + ": cannot take the lock: " + std::strerror(error));
            const std::string holder = got > 0 ? std::string(text, size_t(got)) : std::string("?");
            throw FormatError(output.string() + ": is being written by process " +
                              holder.substr(0, holder.find_first_of("\n ")) +
                              " (another job with the same output, which holds " + path_.string() +
                              "): wait for it, or give this job another output");
        }
        struct stat held
        {
        }, named{};
        if (::fstat(fd, &held) == 0 && ::lstat(path_.c_str(), &named) == 0 && held.st_dev == named.st_dev &&
            held.st_ino == named.st_ino)
        {
            const std::string pid = std::to_string(::getpid()) + "\n";
            if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) != ssize_t(pid.size()))
            {
                const int error = errno;
                ::unlink(path_.c_str());
                ::close(fd);
                throw FormatError(path_.string() + ": cannot write the lock: " + std::strerror(error));
            }
            fd_ = fd;
            return;
        }
        ::close(fd); // removed or replaced under us: take the new one
    }
    throw FormatError(path_.string() + ": cannot take the lock: it keeps being replaced");
}

OutputLock::~OutputLock()
{
    if (fd_ < 0)
        return;
    ::unlink(path_.c_str()); // while still held, so that no other job takes the removed file
    ::close(fd_);
}

int create_new_file(const std::filesystem::path& path)
{
    struct stat st
    {
    };
    if (::lstat(path.c_str(), &st) == 0)
    {
        if (!S_ISREG(st.st_mode))
            throw FormatError(path.string() +
                              ": cannot create it: something that is not a regular file is in the way (" +
                              (S_ISLNK(st.st_mode) ? "a symbolic link" : "a folder, FIFO, device or socket") +
                              "); a temporary is made as a new file, never through a link: remove it");
        ::unlink(path.c_str()); // a temporary left by a job that was killed
    }
    errno = 0;
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0)
        throw FormatError(path.string() + ": cannot create it: " + std::strerror(errno));
    return fd;
}

void check_temporary(const std::filesystem::path& path)
{
    check_writable(path);
    struct stat st
    {
    };
    if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
        throw FormatError(path.string() + ": cannot write: " +
                          (S_ISLNK(st.st_mode) ? "it is a symbolic link" : "it is not a regular file") +
                          ", where a temporary is made as a new file, never through a link: remove it");
}

int open_existing_file(const std::filesystem::path& path)
{
    errno = 0;
    const int fd = ::open(path.c_str(), O_RDWR | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0)
        throw FormatError(path.string() + ": cannot open it: " +
                          (errno == ELOOP ? std::string("it is a symbolic link") : std::strerror(errno)));
    struct stat st
    {
    };
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))
    {
        ::close(fd);
        throw FormatError(path.string() + ": cannot open it: it is not a regular file");
    }
    return fd;
}

std::vector<std::filesystem::path> stale_temporaries(const std::filesystem::path& path)
{
    namespace fs = std::filesystem;
    std::vector<fs::path> out;
    const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const std::string prefix = path.filename().string() + ".tmp";
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    {
        const std::string name = it->path().filename().string();
        if (name.rfind(prefix, 0) != 0)
            continue;
        // "<pid>.<n>": digits, a dot, digits.
        const std::string rest = name.substr(prefix.size());
        const size_t dot = rest.find('.');
        if (dot == 0 || dot == std::string::npos || dot + 1 == rest.size() ||
            rest.find_first_not_of("0123456789.") != std::string::npos ||
            rest.find('.', dot + 1) != std::string::npos)
            continue;
        const long pid = std::strtol(rest.substr(0, dot).c_str(), nullptr, 10);
        if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH)
            out.push_back(it->path());
    }
    return out;
}

void write_text_atomically(const std::filesystem::path& path, std::string_view text)
{
    write_atomically(path,
                     [&](const std::filesystem::path& tmp)
                     {
                         std::ofstream f(tmp, std::ios::binary);
                         f.write(text.data(), std::streamsize(text.size()));
                         f.close();
                         if (f.fail())
                             throw FormatError(path.string() + ": cannot write the file (" +
                                               std::strerror(errno) + ")");
                     });
}

void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temporary)>& write)
{
    check_writable(path);
    for (const std::filesystem::path& stale : stale_temporaries(path))
    {
        std::error_code ignored;
        std::filesystem::remove(stale, ignored);
    }
    static std::atomic<unsigned> counter{0};
    std::filesystem::path tmp = path;
    tmp += ".tmp" + std::to_string(::getpid()) + "." + std::to_string(counter++);
    try
    {
        // Made new and exclusive first: the writer then truncates this process's own file, not whatever
        // a link planted at the name would point to.
        ::close(create_new_file(tmp));
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
        throw FormatError(path.string() +
                          ": cannot rename the finished temporary file into place: " + ec.message());
    }
    std::filesystem::path dir = path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    if (int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY); fd >= 0)
    {
        ::fsync(fd); // best effort: the rename itself is already atomic
        ::close(fd);
    }
}

} // namespace hemi::io
