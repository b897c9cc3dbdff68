// PNG and JPEG decoding (io::decode_image): the bytes glTF scenes and assets carry. The first byte picks the
// declared type, so both decoders and the mismatch path are reached from one corpus.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1)
        return 0;
    hemi::io::EncodedImage image;
    image.name = "fuzz image";
    image.mime_type = data[0] & 1 ? "image/jpeg" : "image/png";
    image.bytes.assign(data + 1, data + size);
    hemi::fuzz::expect_clean([&] { hemi::io::decode_image(image); });
    return 0;
}
