// OpenEXR reading (io::read_exr), with hemi's caps on the windows.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static const std::filesystem::path file = hemi::fuzz::scratch(".exr");
    hemi::fuzz::write_file(file, data, size);
    hemi::fuzz::expect_clean([&] { hemi::io::read_exr(file); });
    return 0;
}
