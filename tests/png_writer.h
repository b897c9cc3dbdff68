#pragma once
// PNGs of any bit depth and channel count for test inputs (stb_image_write writes 8-bit RGBA only): zlib's
// deflate and CRC, written from the PNG specification (signature, IHDR, one IDAT with filter 0, IEND).
#include <zlib.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::test
{

// samples: width * height * channels values, row-major from the top row, each < 2^bits. channels 1 (grey),
// 2 (grey + alpha), 3 (RGB) or 4 (RGBA); bits 8 or 16.
inline std::vector<uint8_t> encode_png_samples(uint32_t width, uint32_t height, int channels, int bits,
                                               const std::vector<uint16_t>& samples)
{
    static const uint8_t kColourType[5] = {0, 0, 4, 2, 6};
    std::vector<uint8_t> raw;
    const size_t bytes = size_t(bits / 8);
    for (uint32_t y = 0; y < height; ++y)
    {
        raw.push_back(0); // filter: none
        for (size_t i = 0; i < size_t(width) * size_t(channels); ++i)
        {
            const uint16_t v = samples[size_t(y) * width * size_t(channels) + i];
            if (bytes == 2)
                raw.push_back(uint8_t(v >> 8));
            raw.push_back(uint8_t(v & 0xff));
        }
    }
    uLongf packed_size = compressBound(uLong(raw.size()));
    std::vector<uint8_t> packed(packed_size);
    if (compress2(packed.data(), &packed_size, raw.data(), uLong(raw.size()), 6) != Z_OK)
        throw std::runtime_error("encode_png_samples: zlib failed");
    packed.resize(packed_size);
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    auto be32 = [](std::vector<uint8_t>& out, uint32_t v)
    {
        for (int s = 24; s >= 0; s -= 8)
            out.push_back(uint8_t(v >> s));
    };
    auto chunk = [&](const char* type, const std::vector<uint8_t>& data)
    {
        be32(png, uint32_t(data.size()));
        std::vector<uint8_t> body(type, type + 4);
        body.insert(body.end(), data.begin(), data.end());
        png.insert(png.end(), body.begin(), body.end());
        be32(png, uint32_t(crc32(0, body.data(), uInt(body.size()))));
    };
    std::vector<uint8_t> ihdr;
    be32(ihdr, width);
    be32(ihdr, height);
    ihdr.insert(ihdr.end(), {uint8_t(bits), kColourType[channels], 0, 0, 0});
    chunk("IHDR", ihdr);
    chunk("IDAT", packed);
    chunk("IEND", {});
    return png;
}

} // namespace hemi::test
