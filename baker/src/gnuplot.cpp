#include <hemi/bake/gnuplot.h>
#include <hemi/io/atomic_file.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

void run_gnuplot(const std::filesystem::path& png_path,
                 const std::function<void(const std::filesystem::path&, std::ostream&,
                                          const std::filesystem::path&)>& write)
{
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("hemi_plot_" + std::to_string(std::random_device{}()));
    // The paths are quoted for the shell; a temporary directory with a quote in its name is refused.
    if (dir.string().find('\'') != std::string::npos)
        throw std::runtime_error(png_path.string() +
                                 ": the temporary directory's path contains a quote: " + dir.string());
    fs::create_directories(dir);
    struct Cleanup
    {
        fs::path dir;
        ~Cleanup()
        {
            std::error_code ignored;
            fs::remove_all(dir, ignored);
        }
    } cleanup{dir};
    const fs::path script_path = dir / "plot.gp", output = dir / "plot.png", errors = dir / "err.txt";
    {
        std::ofstream script(script_path);
        write(dir, script, output);
    }
    const std::string cmd = "gnuplot '" + script_path.string() + "' 2>'" + errors.string() + "'";
    const int rc = std::system(cmd.c_str());
    if (rc != 0 || !fs::exists(output))
    {
        std::ifstream err(errors);
        std::string msg((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
        throw std::runtime_error(png_path.string() +
                                 ": gnuplot failed (is gnuplot installed? cmake/install_deps.sh): " + msg);
    }
    io::write_atomically(png_path, [&](const fs::path& tmp)
                         { fs::copy_file(output, tmp, fs::copy_options::overwrite_existing); });
}

} // namespace hemi::bake
