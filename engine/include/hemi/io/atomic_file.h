#pragma once
// Atomic file writing: the content goes to a temporary file beside the target, which is renamed over the
// target only once it is complete, so readers never see a half-written file.

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace hemi::io
{

// Checks `path` first (output_problem), removes temporaries that earlier writes of `path` left behind when
// their process was killed, then calls `write(temporary_path)`; on success renames the temporary to `path`,
// on an exception removes it and rethrows. Throws FormatError naming `path` and the cause when the target
// cannot be written or the rename fails.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temporary)>& write);

// Writes `text` to `path` atomically (a JSON report, a table). Throws FormatError naming `path` when it
// cannot.
void write_text_atomically(const std::filesystem::path& path, std::string_view text);

// Why a file cannot be written at `path`, or an empty string: its folder does not exist or is not a folder,
// `path` is a folder or another file that is not a regular one (a device, a FIFO), the folder is not
// writable, or its file system has no space left. Long jobs call this
// before they start (io::check_writable), so that they fail in a second, not after the work.
std::string output_problem(const std::filesystem::path& path);
// Throws FormatError("<path>: <output_problem>") when there is a problem.
void check_writable(const std::filesystem::path& path);

// A job's temporary file (a bake's tiles, an asset writer's spool, write_atomically's temporary) made new:
// a regular file already at `path` (a killed job's) is removed, anything else there (a symbolic link, a
// folder, a FIFO, a device) is refused, and the file is created with O_CREAT | O_EXCL | O_NOFOLLOW, so that
// no link planted at its name is followed and nothing but this process's own new file is written. Returns
// its descriptor (read and write, close-on-exec). Throws FormatError naming `path` and the cause.
int create_new_file(const std::filesystem::path& path);
// check_writable for a temporary that create_new_file will make: also refused when a symbolic link or
// another file that is not a regular one is at its name. Throws FormatError naming `path`.
void check_temporary(const std::filesystem::path& path);
// An existing temporary opened again (a resumed bake's tiles), read and write, without following a link at
// its name; refused, naming it, when it is not a regular file. Throws FormatError naming `path`.
int open_existing_file(const std::filesystem::path& path);

// A job's hold on its output: while it lives, no other job (in this or another process) takes the same
// output, nor its checkpoint, tiles and spool, which are named after it. The lock is "<output>.lock" beside
// it, created without following a link, held with flock (so a killed job's lock goes with its process) and
// holding the holder's process id; it is removed when the lock goes. Throws FormatError naming the output
// and the process that holds it ("is being written by process N: ...") when another job has it, or naming
// the lock file when it cannot be made.
class OutputLock
{
  public:
    explicit OutputLock(const std::filesystem::path& output);
    ~OutputLock();
    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;

    static std::filesystem::path lock_path(const std::filesystem::path& output);

  private:
    std::filesystem::path path_;
    int fd_ = -1;
};

// The temporary files write_atomically uses for `path` ("<name>.tmp<pid>.<n>" beside it) whose process no
// longer runs: what a write killed before its rename left. Removed by the next write of `path`.
std::vector<std::filesystem::path> stale_temporaries(const std::filesystem::path& path);

} // namespace hemi::io
