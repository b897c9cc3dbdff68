#pragma once
// What the samples' figures share: tiles composed into one PNG with column and row labels, drawn by gnuplot.

#include <hemi/io/image.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hemi::samples
{

// Tiles (rows x columns, each tw x th pixels, row-major) composed into one PNG at `path` with a label over
// each column and one in each row's corner; linear radiance times `exposure`, clamped, sRGB. Throws what
// bake::run_gnuplot throws.
void write_labeled_grid(const std::string& path, const std::vector<io::ImageRgba>& tiles, uint32_t tw,
                        uint32_t th, const std::vector<std::string>& column_labels,
                        const std::vector<std::string>& row_labels, float exposure);

} // namespace hemi::samples
