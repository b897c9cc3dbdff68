#pragma once
// Running hemi's command-line tools from a test: a process with its exit status and what it printed, and
// paths quoted for the shell. Shared by the command-line tests (cli_test.cpp) and the real level's
// (real_level_test.cpp).
#include <sys/wait.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
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

// Halfway between what a lightmap bake needs in memory and in its least tiles, in KiB, from its refusal of a
// budget too small for either ("needs about 21.1 MiB of memory (15.4 MiB in tiles of ..."); 0 (and a test
// failure) when `refusal` does not say so. Both estimates count what the process holds (its code, the
// scene), which differs under the sanitizers and mpirun, and grows with the test binary: a budget between
// them makes the bake run in tiles wherever it runs. `fraction` places it from the least tiles (0) to the
// whole bake (1): an atlas whose texels cover its blocks sparsely needs less than halfway, since the
// estimates count every texel of the touched blocks.
inline uint64_t tiling_budget_kib(const std::string& refusal, double fraction = 0.5)
{
    const auto size_after = [&](const std::string& label, size_t from, size_t& end) -> double
    {
        const size_t at = refusal.find(label, from);
        if (at == std::string::npos)
            return 0.0;
        char* stop = nullptr;
        const char* begin = refusal.c_str() + at + label.size();
        const double value = std::strtod(begin, &stop);
        end = size_t(stop - refusal.c_str());
        const std::string unit = refusal.substr(end, 4);
        const double scale = unit == " GiB"   ? 1024.0 * 1024.0
                             : unit == " MiB" ? 1024.0
                             : unit == " KiB" ? 1.0
                                              : 0.0;
        return value * scale; // KiB
    };
    size_t end = 0;
    const double whole = size_after("needs about ", 0, end);
    const double least = whole > 0.0 ? size_after("of memory (", end, end) : 0.0;
    if (!(least > 0.0 && whole > least))
    {
        ADD_FAILURE() << "no estimate in the refusal of a small memory budget: " << refusal;
        return 0;
    }
    return uint64_t(least + (whole - least) * fraction);
}

// The same as hemi-bake's option (" --memory-budget <n>K"): `bake(extra)` runs the bake with `extra` on its
// command line, and its refusal of --memory-budget 1M names both estimates. "" when it does not.
inline std::string tiling_budget(const std::function<Result(const std::string&)>& bake, double fraction = 0.5)
{
    const Result r = bake(" --memory-budget 1M");
    if (r.status != 1)
    {
        ADD_FAILURE() << "hemi-bake did not refuse --memory-budget 1M: " << r.err;
        return "";
    }
    const uint64_t kib = tiling_budget_kib(r.err, fraction);
    return kib ? " --memory-budget " + std::to_string(kib) + "K" : "";
}

} // namespace hemi::test
