#pragma once
// What hemi's command-line tools (hemi-bake, hemi-render) share: strict parsing of option values, the
// checks every option of a kind gets, one exit status for every usage error, and errors that name the file
// they are about. Header-only and not installed: a tool's building block, not part of the library.
//
// The rules, the same for every option of their kind:
//   - A number is the whole option text (no trailing junk), finite, and inside the option's range.
//   - A list is comma-separated numbers of one of the allowed counts; a size is W or WxH of whole numbers.
//   - A usage error (an unknown option, a missing or malformed value, a missing input file) exits 1, like
//     every other error; --help exits 0.
//   - An output must not be one of the command's inputs or another of its outputs.
#include <hemi/io/atomic_file.h>
#include <hemi/io/memory.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <malloc.h>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>
#include <sys/resource.h>
#include <utility>
#include <vector>

namespace hemi::tool
{

// One number, the whole of `text`, finite and in [lo, hi]; `option` names it in the error.
inline double parse_number(std::string_view text, std::string_view option, double lo = -HUGE_VAL,
                           double hi = HUGE_VAL)
{
    const std::string s(text);
    char* end = nullptr;
    errno = 0;
    const double v = s.empty() || std::isspace((unsigned char)s[0]) ? NAN : std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v) || errno == ERANGE)
        throw std::invalid_argument(std::string(option) + " expects a finite number, got '" + s + "'");
    if (v < lo || v > hi)
    {
        char range[96];
        std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
        throw std::invalid_argument(std::string(option) + " " + s + " is outside " + range);
    }
    return v;
}

// Comma-separated numbers, each as parse_number; their count must be one of `counts` (empty: any count
// from 1). `form` shows the expected form in the error, e.g. "X,Y,Z,R,G,B[,DIAMETER]".
inline std::vector<double> parse_numbers(std::string_view text, std::string_view option,
                                         std::string_view form, std::vector<size_t> counts = {})
{
    std::vector<double> out;
    const std::string s(text);
    size_t start = 0;
    while (true)
    {
        const size_t comma = s.find(',', start);
        const std::string item =
            s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        try
        {
            out.push_back(parse_number(item, option));
        }
        catch (const std::invalid_argument&)
        {
            throw std::invalid_argument(std::string(option) + " expects " + std::string(form) + ", got '" +
                                        s + "' ('" + item + "' is not a finite number)");
        }
        if (comma == std::string::npos)
            break;
        start = comma + 1;
    }
    bool count_ok = counts.empty();
    for (size_t c : counts)
        count_ok = count_ok || out.size() == c;
    if (!count_ok)
        throw std::invalid_argument(std::string(option) + " expects " + std::string(form) + ", got '" + s +
                                    "' (" + std::to_string(out.size()) + " number(s))");
    return out;
}

// A whole number, the whole of `text` (digits only), in [lo, hi].
inline uint64_t parse_count(std::string_view text, std::string_view option, uint64_t lo, uint64_t hi)
{
    const std::string s(text);
    if (s.empty() || s.size() > 19 || s.find_first_not_of("0123456789") != std::string::npos)
        throw std::invalid_argument(std::string(option) + " expects a whole number, got '" + s + "'");
    const uint64_t v = std::strtoull(s.c_str(), nullptr, 10);
    if (v < lo || v > hi)
        throw std::invalid_argument(std::string(option) + " " + s + " is outside [" + std::to_string(lo) +
                                    ", " + std::to_string(hi) + "]");
    return v;
}

// Whole numbers separated by `separator` ('x' for sizes and CPCA's CLUSTERSxVECTORS, ',' for grids); their
// count must be one of `counts`; each in [lo, hi].
inline std::vector<uint64_t> parse_counts(std::string_view text, std::string_view option,
                                          std::string_view form, char separator, std::vector<size_t> counts,
                                          uint64_t lo, uint64_t hi)
{
    std::vector<uint64_t> out;
    const std::string s(text);
    size_t start = 0;
    while (true)
    {
        const size_t sep = s.find(separator, start);
        const std::string item = s.substr(start, sep == std::string::npos ? std::string::npos : sep - start);
        try
        {
            out.push_back(parse_count(item, option, lo, hi));
        }
        catch (const std::invalid_argument& e)
        {
            throw std::invalid_argument(std::string(option) + " expects " + std::string(form) + ", got '" +
                                        s + "': " + e.what());
        }
        if (sep == std::string::npos)
            break;
        start = sep + 1;
    }
    bool count_ok = false;
    for (size_t c : counts)
        count_ok = count_ok || out.size() == c;
    if (!count_ok)
        throw std::invalid_argument(std::string(option) + " expects " + std::string(form) + ", got '" + s +
                                    "'");
    return out;
}

// W or WxH, each side in [1, max_side].
inline std::pair<uint32_t, uint32_t> parse_size(std::string_view text, std::string_view option,
                                                uint32_t max_side = 16384, bool square_allowed = true)
{
    const std::vector<uint64_t> v =
        parse_counts(text, option, square_allowed ? "W or WxH (e.g. 1024x512)" : "WxH (e.g. 800x600)", 'x',
                     square_allowed ? std::vector<size_t>{1, 2} : std::vector<size_t>{2}, 1, max_side);
    return {uint32_t(v[0]), uint32_t(v.size() == 2 ? v[1] : v[0])};
}

// A CLI11 check for numeric options: the value is a finite number in [lo, hi] (CLI::Range lets NaN through).
inline CLI::Validator finite(double lo = -HUGE_VAL, double hi = HUGE_VAL)
{
    return CLI::Validator(
        [lo, hi](std::string& value) -> std::string
        {
            try
            {
                parse_number(value, "the value", lo, hi);
            }
            catch (const std::invalid_argument& e)
            {
                return e.what();
            }
            return {};
        },
        lo == -HUGE_VAL && hi == HUGE_VAL
            ? "FINITE"
            : "FINITE in [" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]");
}

// Comma-separated names, none twice and none empty.
inline std::vector<std::string> parse_names(std::string_view text, std::string_view option)
{
    std::vector<std::string> out;
    const std::string s(text);
    size_t start = 0;
    while (true)
    {
        const size_t comma = s.find(',', start);
        std::string item = s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        if (item.empty())
            throw std::invalid_argument(std::string(option) + " '" + s + "' has an empty name");
        for (const std::string& seen : out)
            if (seen == item)
                throw std::invalid_argument(std::string(option) + " names '" + item + "' twice");
        out.push_back(std::move(item));
        if (comma == std::string::npos)
            break;
        start = comma + 1;
    }
    return out;
}

// The files of one command: each input and output with the option that names it. check() refuses an
// output that is also an input or another output (the same path, or another name of the same file), and
// checks that every output can be written (io::check_writable: its folder, a regular file or none, space).
class Files
{
  public:
    void input(std::string role, const std::filesystem::path& path)
    {
        if (!path.empty())
            inputs_.push_back({std::move(role), path});
    }
    // A glTF scene and the files it refers to (buffers and images by relative URI): all are inputs.
    void scene(std::string role, const std::filesystem::path& path)
    {
        input(role, path);
        if (path.extension() != ".gltf")
            return;
        std::ifstream in(path);
        const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
        if (j.is_discarded() || !j.is_object())
            return; // the scene reader says what is wrong
        for (const char* array : {"buffers", "images"})
            if (j.contains(array) && j[array].is_array())
                for (const nlohmann::json& item : j[array])
                    if (item.is_object() && item.contains("uri") && item["uri"].is_string())
                    {
                        const std::string uri = item["uri"].get<std::string>();
                        if (uri.rfind("data:", 0) != 0 && !uri.empty())
                            input(role + "'s " + std::string(array) + " file", path.parent_path() / uri);
                    }
    }
    void output(std::string role, const std::filesystem::path& path)
    {
        if (!path.empty())
            outputs_.push_back({std::move(role), path});
    }
    void check() const
    {
        for (size_t i = 0; i < outputs_.size(); ++i)
        {
            for (const Named& in : inputs_)
                if (same_file(outputs_[i].path, in.path))
                    throw std::invalid_argument(outputs_[i].role + " " + outputs_[i].path.string() +
                                                " is the input " + in.role + " " + in.path.string() +
                                                ": the output would overwrite it");
            for (size_t j = 0; j < i; ++j)
                if (same_file(outputs_[i].path, outputs_[j].path))
                    throw std::invalid_argument(outputs_[i].role + " " + outputs_[i].path.string() + " and " +
                                                outputs_[j].role + " " + outputs_[j].path.string() +
                                                " are the same file");
            io::check_writable(outputs_[i].path);
        }
    }
    // Every path the command names, for naming_input's test of whether a message names a file.
    std::vector<std::filesystem::path> all() const
    {
        std::vector<std::filesystem::path> out;
        for (const Named& n : inputs_)
            out.push_back(n.path);
        for (const Named& n : outputs_)
            out.push_back(n.path);
        return out;
    }

  private:
    struct Named
    {
        std::string role;
        std::filesystem::path path;
    };
    static bool same_file(const std::filesystem::path& a, const std::filesystem::path& b)
    {
        std::error_code ea, eb;
        if (std::filesystem::exists(a, ea) && std::filesystem::exists(b, eb))
            return std::filesystem::equivalent(a, b, ea) && !ea;
        // Not both there yet: compare the absolute, normalised paths (weakly_canonical keeps a path
        // relative when none of it exists). A path that cannot be resolved is left to check_writable.
        const std::filesystem::path x =
            std::filesystem::weakly_canonical(std::filesystem::absolute(a, ea), ea);
        const std::filesystem::path y =
            std::filesystem::weakly_canonical(std::filesystem::absolute(b, eb), eb);
        return !ea && !eb && x == y;
    }
    std::vector<Named> inputs_, outputs_;
};

// Creates an output folder (and its parents) before the work, so that one that cannot be made fails now.
inline void make_folder(const std::filesystem::path& dir, std::string_view option)
{
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir))
        throw std::invalid_argument(
            std::string(option) + " " + dir.string() + ": cannot make the folder" +
            (ec ? " (" + ec.message() + ")" : std::string(" (a file is in the way)")));
}

// What the tool is doing now ("pass 2/3 (bounce 1)", "writing the outputs"), for the message of a job that
// runs out of memory; the progress lines set it as they go. Safe from any thread.
inline std::mutex& stage_mutex()
{
    static std::mutex m;
    return m;
}
inline std::string& stage_text()
{
    static std::string text;
    return text;
}
inline void set_stage(std::string what)
{
    const std::lock_guard lock(stage_mutex());
    stage_text() = std::move(what);
}
inline std::string stage()
{
    const std::lock_guard lock(stage_mutex());
    return stage_text();
}
// What a user can do about it, appended to the out-of-memory message ("; a smaller --memory-budget ...").
inline std::string& out_of_memory_advice()
{
    static std::string text;
    return text;
}

// "<input>: out of memory while <stage>: the process held <peak> at its peak and <available> more was free":
// what a job that the machine could not give memory says, instead of only that it ran out.
inline std::string out_of_memory_message(const std::filesystem::path& input)
{
    const std::string what = stage();
    const uint64_t available = io::available_memory();
    return input.string() + ": out of memory" + (what.empty() ? std::string() : " while " + what) +
           ": the process held " + io::format_bytes(io::peak_memory()) + " at its peak" +
           (available ? " and " + io::format_bytes(available) + " more was free" : std::string()) +
           out_of_memory_advice();
}

// Thrown in place of std::bad_alloc once the input and the stage are known (naming_input): run() prints it.
struct OutOfMemory : std::runtime_error
{
    using std::runtime_error::runtime_error;
};

// Runs `work` on the data of `input`; an error whose message names none of the command's files is
// re-thrown as "<input>: <message>", so that every error says which file it is about; running out of memory
// says which file, at which stage and at what size (out_of_memory_message).
template <class F> auto naming_input(const std::filesystem::path& input, const Files& files, F&& work)
{
    try
    {
        return work();
    }
    catch (const std::bad_alloc&)
    {
        throw OutOfMemory(out_of_memory_message(input));
    }
    catch (const OutOfMemory&)
    {
        throw;
    }
    catch (const std::exception& e)
    {
        const std::string message = e.what();
        for (const std::filesystem::path& p : files.all())
            if (message.find(p.string()) != std::string::npos ||
                (!p.filename().empty() && message.find(p.filename().string()) != std::string::npos))
                throw;
        throw std::runtime_error(input.string() + ": " + message);
    }
}

// Parses the command line and runs `body`: usage errors print CLI11's message and exit 1 (--help exits 0);
// an exception from `body` prints "<tool> <subcommand>: <message>" and exits 1; running out of memory says
// so.
inline int run(CLI::App& app, int argc, char** argv, const std::string& tool,
               const std::function<int()>& body)
{
    // A write past the file-size limit (ulimit -f) fails with EFBIG and is reported as a full disk is,
    // naming the file, instead of the process being killed by SIGXFSZ with its temporaries left behind.
    std::signal(SIGXFSZ, SIG_IGN);
    // Under an address-space limit (ulimit -v), one malloc arena: glibc reserves 64 MiB of address space for
    // each arena it adds for a thread, which the limit counts though nothing is used (io::available_memory
    // counts the rest of what is reserved and not used).
    if (rlimit as{}; getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY)
        mallopt(M_ARENA_MAX, 1);
    try
    {
        app.parse(argc, argv);
    }
    catch (const CLI::ParseError& e)
    {
        const int code = app.exit(e);
        return code == 0 ? 0 : 1;
    }
    std::string name = tool;
    for (const CLI::App* sub : app.get_subcommands())
        name += " " + sub->get_name();
    try
    {
        return body();
    }
    catch (const std::bad_alloc&)
    {
        const std::string what = stage();
        std::fprintf(stderr, "\n%s: out of memory%s%s: the process held %s at its peak\n", name.c_str(),
                     what.empty() ? "" : " while ", what.c_str(),
                     io::format_bytes(io::peak_memory()).c_str());
    }
    catch (const std::exception& e)
    {
        std::fprintf(stderr, "\n%s: %s\n", name.c_str(), e.what());
    }
    return 1;
}

} // namespace hemi::tool
