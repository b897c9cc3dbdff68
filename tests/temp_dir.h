#pragma once
// A scratch folder for one test file's outputs: under the system's temporary directory, named after the
// test file and the process, so that tests running in parallel (ctest -j) never share files.
#include <unistd.h>

#include <filesystem>
#include <string>

namespace hemi::test
{

inline std::filesystem::path temp_dir(const std::string& name)
{
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("hemi_" + name + "_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
}

} // namespace hemi::test
