// The .hemi container and the assets on it (io::read_prt_asset, io::read_lightmap_asset and
// io::read_envmap_asset: every input is read as each kind, as a user may mix them up; fuzz_envmap explores
// the environment asset from its own seeds). The container's XXH64 would turn away almost every mutation
// before the parsers behind it, so the target re-seals the input: it recomputes the checksum over the mutated
// bytes, and the section table, the sections' sizes and values, the materials' JSON and the embedded images
// are what the fuzzer explores.
#include "fuzz_common.h"

#include <hemi/io/envmap_asset.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>

#include <cstring>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static const std::filesystem::path file = hemi::fuzz::scratch(".hemi");
    hemi::fuzz::write_resealed(file, data, size);
    hemi::fuzz::expect_clean(
        [&]
        {
            const hemi::io::PrtAsset asset = hemi::io::read_prt_asset(file);
            for (const hemi::io::EncodedImage& image : asset.images)
                hemi::fuzz::expect_clean([&] { hemi::io::decode_image(image); });
        });
    hemi::fuzz::expect_clean([&] { hemi::io::read_lightmap_asset(file); });
    hemi::fuzz::expect_clean([&] { hemi::io::read_envmap_asset(file); });
    return 0;
}
