// The samples' labelled figures (figure.h).
#include "figure.h"

#include <hemi/bake/gnuplot.h>

#include <ostream>

namespace hemi::samples
{

void write_labeled_grid(const std::string& path, const std::vector<io::ImageRgba>& tiles, uint32_t tw,
                        uint32_t th, const std::vector<std::string>& column_labels,
                        const std::vector<std::string>& row_labels, float exposure)
{
    const uint32_t columns = uint32_t(column_labels.size()), rows = uint32_t(row_labels.size());
    io::ImageRgba grid{tw * columns, th * rows,
                       std::vector<float>(size_t(tw) * columns * th * rows * 4, 0.0f)};
    for (uint32_t r = 0; r < rows; ++r)
        for (uint32_t c = 0; c < columns; ++c)
            for (uint32_t y = 0; y < th; ++y)
                for (uint32_t x = 0; x < tw; ++x)
                    for (int k = 0; k < 4; ++k)
                        grid.pixels[((size_t(r) * th + y) * grid.width + c * tw + x) * 4 + k] =
                            k == 3 ? 1.0f : tiles[r * columns + c].at(x, y)[k];
    bake::run_gnuplot(
        path,
        [&](const std::filesystem::path& folder, std::ostream& script, const std::filesystem::path& output)
        {
            io::write_png(folder / "grid.png", grid, {exposure, io::ToneMap::Curve::Clamp});
            const int header = 26, w = int(grid.width), h = int(grid.height);
            script << "set terminal pngcairo size " << w << "," << h + header
                   << " noenhanced font 'Sans,11' background rgb 'black'\n"
                   << "set output '" << output.string() << "'\n"
                   << "unset border\nunset tics\nunset key\n"
                   << "set lmargin at screen 0\nset rmargin at screen 1\nset bmargin at screen 0\n"
                   << "set tmargin at screen " << double(h) / (h + header) << "\n"
                   << "set xrange [-0.5:" << w - 0.5 << "]\nset yrange [-0.5:" << h - 0.5 << "]\n";
            for (uint32_t c = 0; c < columns; ++c)
                script << "set label '" << column_labels[c] << "' at screen " << (c + 0.5) / columns
                       << ", screen " << 1.0 - 0.5 * header / (h + header) << " center tc rgb 'white'\n";
            for (uint32_t r = 0; r < rows; ++r)
                script << "set label '" << row_labels[r] << "' at screen 0.004, screen "
                       << (double(h) * (1.0 - double(r) / rows) - 14.0) / (h + header)
                       << " left front tc rgb '#c0c0c0'\n";
            script << "plot '" << (folder / "grid.png").string() << "' binary filetype=png with rgbimage\n";
        });
}

} // namespace hemi::samples
