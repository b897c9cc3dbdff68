#pragma once
// Linear RGBA float images and their writers: EXR (linear float, the HDR format hemi reads and writes)
// and PNG (tone-mapped 8-bit sRGB, for people to look at). Both writers are atomic. And 8-bit textures: PNG
// and JPEG decoding (the images glTF scenes and baked assets carry) and encoding.

#include <hemi/io/material.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hemi::io
{

// Thrown by readers and writers; the message names the file and the problem.
class FormatError : public std::runtime_error
{
  public:
    using std::runtime_error::runtime_error;
};

struct ImageRgba
{
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<float> pixels; // width * height * 4, row-major from the top row, linear RGB + alpha

    const float* at(uint32_t x, uint32_t y) const { return pixels.data() + (size_t(y) * width + x) * 4; }
};

// How linear radiance becomes an 8-bit sRGB PNG: out = srgb_oetf(curve(exposure * linear)), per channel,
// where curve is a clamp to [0, 1] or Reinhard's x / (1 + x); alpha is written as is (clamped).
struct ToneMap
{
    enum class Curve
    {
        Clamp,
        Reinhard,
    };
    float exposure = 1.0f;
    Curve curve = Curve::Clamp;
};

// Reads an OpenEXR file (scanline or tiled, half or float) into linear RGBA over its display window (pixels
// outside the data window of an auto-cropped file read as 0, alpha 0 there): missing R/G/B read as 0 and a
// missing A as 1; a single-channel Y image is read as grey. Files with neither R, G, B nor Y are refused.
// Multi-part files are read from their first part, which must be a flat scanline or tiled image (deep data is
// refused). Throws FormatError naming `path` when the file is missing, not EXR, truncated or corrupt, or
// holds a non-finite pixel (with its position).
//
// Memory follows the file, not its header: the headers are walked before OpenEXR reads them, and a file is
// refused unless every attribute's value and the chunk offset tables lie in it and its data window's pixels
// (and any one chunk: a block of scanlines, a tile) can be coded in its bytes at the compression's largest
// expansion (none 1:1, RLE 64:1, ZIP 1032:1, PIZ 410:1, PXR24 1376:1, B44 11:1, DWA 66048:1, each with a
// margin of 2); a chunk may overhang the data window by at most 64 MiB of buffers beyond that. The pixels are
// then read in bands that grow with what has decoded.
ImageRgba read_exr(const std::filesystem::path& path);

// Radiance an environment image holds below zero. Real HDRIs (Poly Haven's, Blender's studio lights) hold a
// few slightly negative values left by their lossy compression or processing (every one of Blender's eight
// studio-light worlds does, down to -0.004): when the most negative is within `tolerance` of the image's mean
// colour value, the negative values are set to 0 and counted (a caller may warn); a larger negative value is
// an error in the image: std::invalid_argument naming `name` and the pixel. Alpha is not looked at.
struct NegativeRadiance
{
    size_t clamped = 0; // colour values set to 0
    float least = 0.0f; // the most negative of them
    float mean = 0.0f;  // of the finite colour values, negatives counted as 0
    float brightest = 0.0f;
};
NegativeRadiance clamp_negative_radiance(ImageRgba& image, const std::string& name, float tolerance = 0.01f);
// read_exr's caps: the display window holds at most 2^27 pixels (16384 x 8192, 2 GiB of RGBA floats), and
// one larger than 1024 x 1024 may be at most 64 times its data window (what auto-cropping pads with zeros).
constexpr uint64_t kMaxExrPixels = uint64_t(1) << 27;
constexpr uint64_t kMaxExrPaddedPixels = uint64_t(1024) * 1024;
constexpr uint64_t kMaxExrPadding = 64;

// Throws FormatError naming `path` when the image is inconsistent or the file cannot be written.
void write_exr(const std::filesystem::path& path, const ImageRgba& image);
void write_png(const std::filesystem::path& path, const ImageRgba& image, const ToneMap& tone_map = {});

// One channel of a multi-channel EXR: `data` holds width x height values, rows from the top, pixel i at
// data[i * stride]; stored as half when `half` (values are converted), else as float.
struct ExrChannel
{
    std::string name;
    const float* data = nullptr;
    size_t stride = 1;
    bool half = false;
};
// Writes any named channels plus string attributes (metadata an engine's own loader can read: layouts,
// bases, conventions), atomically. Values are written as they are (like write_exr, NaN included: the readers
// refuse them). Throws FormatError naming `path` for no channels or an I/O failure.
void write_exr_channels(const std::filesystem::path& path, uint32_t width, uint32_t height,
                        std::span<const ExrChannel> channels,
                        std::span<const std::pair<std::string, std::string>> attributes = {});

// 8-bit RGBA as stored: textures (sRGB base colour, linear normal maps), no conversion either way.
struct ImageRgba8
{
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<uint8_t> pixels; // width * height * 4, row-major from the top row
};

// Reads a PNG (any bit depth or channel count; 16-bit is reduced to 8, grey and RGB get alpha 255). Throws
// FormatError naming `path` when the file is missing, not a PNG, truncated or corrupt.
ImageRgba8 read_png(const std::filesystem::path& path);
// Decodes an image as glTF stores it (io/material.h): PNG (8 or 16 bit, 16 rounded to 8) or JPEG (baseline
// and progressive), grey/RGB get alpha 255. The container is checked before the decoder sees it: a PNG's
// chunks (lengths, critical chunks' CRCs, IHDR first, IEND present), a JPEG's segments up to its EOI marker;
// so a truncated or bit-flipped file is refused rather than decoded to garbage. Throws FormatError naming
// image.name when the bytes are empty, neither PNG nor JPEG, disagree with image.mime_type (when it is set),
// are truncated or corrupt, or the image is larger than 2^28 pixels.
ImageRgba8 decode_image(const EncodedImage& image);
// Reads a PNG or JPEG file into its encoded form (mime type from the bytes' signature, not the extension;
// name = the path). Throws FormatError naming `path` when it is missing or neither format.
EncodedImage read_encoded_image(const std::filesystem::path& path);
// An image read as data rather than colour (height maps, masks): a PNG's samples at their full bit depth (8
// or 16) scaled to [0, 1] with no sRGB decode, an EXR's values as read_exr gives them. pixels is always RGBA
// (grey is copied to R, G and B; a missing alpha reads 1).
struct DataImage
{
    uint32_t width = 0;
    uint32_t height = 0;
    int channels = 0; // what the file stores: PNG 1 (grey), 2 (grey + alpha), 3 (RGB), 4 (RGBA); EXR 4
    int bits = 0;     // PNG 8 or 16; EXR 32 (half and float both read as float)
    // width * height * channels, row-major from the top row: only the channels the file has (a 16384^2 grey
    // height map is 1 GiB of floats, not the 4 GiB of RGBA; issue 41).
    std::vector<float> pixels;

    // Channel c (0 red, 1 green, 2 blue, 3 alpha) of pixel i (y * width + x) as RGBA: grey in red, green and
    // blue; alpha 1 where the file has none.
    float rgba(size_t i, int c) const
    {
        const float* p = pixels.data() + i * size_t(channels);
        if (channels >= 3)
            return c < 3 ? p[c] : channels == 4 ? p[3] : 1.0f;
        return c < 3 ? p[0] : channels == 2 ? p[1] : 1.0f;
    }
};
// Reads a PNG (checked as decode_image checks it) or an OpenEXR file (read_exr) by its signature. Throws
// FormatError naming `path` when it is missing, empty, a JPEG (lossy: not data), neither format, truncated or
// corrupt, or when decoding it would need more memory than is available (io::check_memory, from the size its
// header declares, before decoding).
DataImage read_data_image(const std::filesystem::path& path);

// Encodes 8-bit RGBA (stb_image_write): PNG losslessly; JPEG at `quality` in [1, 100], alpha dropped. Throws
// std::invalid_argument for an empty or inconsistent image or a bad quality.
std::vector<uint8_t> encode_png(const ImageRgba8& image);
std::vector<uint8_t> encode_jpeg(const ImageRgba8& image, int quality = 90);

// Writes the bytes as they are (atomic). Throws FormatError naming `path` on a size mismatch or I/O failure.
void write_png(const std::filesystem::path& path, const ImageRgba8& image);

// sRGB transfer function (IEC 61966-2-1) for one linear value in [0, 1].
float srgb_oetf(float linear);
// Its inverse: the linear value of an sRGB-encoded one in [0, 1].
float srgb_eotf(float encoded);

} // namespace hemi::io
