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

// The temporary files write_atomically uses for `path` ("<name>.tmp<pid>.<n>" beside it) whose process no
// longer runs: what a write killed before its rename left. Removed by the next write of `path`.
std::vector<std::filesystem::path> stale_temporaries(const std::filesystem::path& path);

} // namespace hemi::io
