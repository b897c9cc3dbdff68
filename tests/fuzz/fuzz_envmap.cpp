// The environment asset (io::read_envmap_asset: hemi-bake envmap's output, read by the renderer). Like
// fuzz_asset, the target re-seals the container's checksum over the mutated bytes, so that the section table
// and the envmap sections' counts, sizes, extents and values are what the fuzzer explores.
#include "fuzz_common.h"

#include <hemi/io/envmap_asset.h>

#include <cstring>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static const std::filesystem::path file = hemi::fuzz::scratch(".hemi");
    hemi::fuzz::write_resealed(file, data, size);
    hemi::fuzz::expect_clean(
        [&]
        {
            const hemi::io::EnvmapAsset asset = hemi::io::read_envmap_asset(file);
            // What the reader returns is what the renderer accepts (render::EnvironmentLighting checks it).
            if (!hemi::io::envmap_problem(asset).empty())
            {
                std::fprintf(stderr, "read_envmap_asset returned an inconsistent asset: %s\n",
                             hemi::io::envmap_problem(asset).c_str());
                std::abort();
            }
        });
    return 0;
}
