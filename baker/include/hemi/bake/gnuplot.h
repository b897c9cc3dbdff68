#pragma once
// Drawing with gnuplot (pngcairo), the plotting tool behind every figure hemi writes: a script runs in a
// private temporary folder and its PNG replaces `png_path` atomically.

#include <filesystem>
#include <functional>
#include <ostream>

namespace hemi::bake
{

// `write` receives the temporary folder (for data files), the script stream and the path the script must
// `set output` to. Throws std::runtime_error naming `png_path` when gnuplot is missing or fails (with its
// message), or when the temporary folder's path cannot be quoted for the shell.
void run_gnuplot(const std::filesystem::path& png_path,
                 const std::function<void(const std::filesystem::path& folder, std::ostream& script,
                                          const std::filesystem::path& output)>& write);

} // namespace hemi::bake
