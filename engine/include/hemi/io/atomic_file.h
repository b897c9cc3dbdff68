#pragma once
// Atomic file writing: the content goes to a temporary file beside the target, which is renamed over the
// target only once it is complete, so readers never see a half-written file.

#include <filesystem>
#include <functional>

namespace hemi::io
{

// Calls `write(temporary_path)`; on success renames the temporary to `path`, on an exception removes it
// and rethrows. Throws FormatError when the rename fails.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temporary)>& write);

} // namespace hemi::io
