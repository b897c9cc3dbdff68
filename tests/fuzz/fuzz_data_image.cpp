// Data images (io::read_data_image: height and normal maps, by their signature a PNG at full bit depth or an
// OpenEXR file; JPEGs refused). The PNG and EXR decoders have targets of their own (fuzz_image, fuzz_exr);
// this one reaches the dispatch, the 16-bit path and the conversions behind it from whole files.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static const std::filesystem::path file = hemi::fuzz::scratch(".img");
    hemi::fuzz::write_file(file, data, size);
    hemi::fuzz::expect_clean([&] { hemi::io::read_data_image(file); });
    return 0;
}
