#pragma once
// Running hemi's command-line tools from a test: a process with its exit status and what it printed, and
// paths quoted for the shell. Shared by the command-line tests (cli_test.cpp) and the real level's
// (real_level_test.cpp).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace hemi::test
{

struct Result
{
    int status;
    std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

// Quoted for the shell (built up, not with operator+ on a literal: GCC 12 warns falsely there).
inline std::string q(const std::filesystem::path& p)
{
    std::string quoted(1, '\'');
    quoted.append(p.string());
    quoted.push_back('\'');
    return quoted;
}

// `exe args` with `environment` (VAR=value ...) before it; stdout and stderr go through files in `dir`.
inline Result run(const std::filesystem::path& dir, const std::string& exe, const std::string& args,
                  const std::string& environment = "")
{
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string command = environment + " '" + exe + "' " + args + " > " + q(out) + " 2> " + q(err);
    const int raw = std::system(command.c_str());
    return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

} // namespace hemi::test
