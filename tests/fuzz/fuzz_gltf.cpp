// glTF 2.0 (io::read_gltf): the first byte picks .glb or .gltf, the rest is the file; images the file
// embeds are decoded too, as a bake would.
#include "fuzz_common.h"

#include <hemi/io/gltf.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1)
        return 0;
    static const std::filesystem::path glb = hemi::fuzz::scratch(".glb"), gltf = hemi::fuzz::scratch(".gltf");
    const std::filesystem::path& file = data[0] & 1 ? glb : gltf;
    hemi::fuzz::write_file(file, data + 1, size - 1);
    hemi::fuzz::expect_clean(
        [&]
        {
            const hemi::io::GltfScene scene = hemi::io::read_gltf(file);
            for (const hemi::io::EncodedImage& image : scene.images)
                hemi::fuzz::expect_clean([&] { hemi::io::decode_image(image); });
        });
    return 0;
}
