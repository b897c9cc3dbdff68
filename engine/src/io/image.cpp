#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#include <stb/stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <algorithm>
#include <cmath>

namespace hemi::io
{
namespace
{
void check_image(const std::filesystem::path& path, const ImageRgba& image)
{
    if (image.width == 0 || image.height == 0)
        throw FormatError(path.string() + ": cannot write an empty image");
    if (image.pixels.size() != size_t(image.width) * image.height * 4)
        throw FormatError(path.string() + ": image has " + std::to_string(image.pixels.size()) +
                          " floats, expected width*height*4 = " +
                          std::to_string(size_t(image.width) * image.height * 4));
}
} // namespace

float srgb_oetf(float x)
{
    x = std::clamp(x, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

void write_exr(const std::filesystem::path& path, const ImageRgba& image)
{
    check_image(path, image);
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        try
        {
            Imf::Header header(int(image.width), int(image.height));
            for (const char* c : {"R", "G", "B", "A"})
                header.channels().insert(c, Imf::Channel(Imf::FLOAT));
            Imf::OutputFile file(tmp.c_str(), header);
            Imf::FrameBuffer fb;
            const size_t xs = 4 * sizeof(float), ys = xs * image.width;
            char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()));
            const char* names[4] = {"R", "G", "B", "A"};
            for (int c = 0; c < 4; ++c)
                fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
            file.setFrameBuffer(fb);
            file.writePixels(int(image.height));
        }
        catch (const std::exception& e)
        {
            throw FormatError(path.string() + ": writing EXR failed: " + e.what());
        }
    });
}

void write_png(const std::filesystem::path& path, const ImageRgba& image, const ToneMap& tone_map)
{
    check_image(path, image);
    std::vector<unsigned char> bytes(size_t(image.width) * image.height * 4);
    for (size_t i = 0; i < bytes.size(); ++i)
    {
        float v = image.pixels[i];
        if (i % 4 == 3)
            v = std::clamp(v, 0.0f, 1.0f);
        else
        {
            v = std::isfinite(v) ? std::max(0.0f, v * tone_map.exposure) : 0.0f;
            if (tone_map.curve == ToneMap::Curve::Reinhard)
                v = v / (1.0f + v);
            v = srgb_oetf(v);
        }
        bytes[i] = static_cast<unsigned char>(std::lround(v * 255.0f));
    }
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        if (!stbi_write_png(tmp.c_str(), int(image.width), int(image.height), 4, bytes.data(), int(image.width * 4)))
            throw FormatError(path.string() + ": writing PNG failed (stb_image_write)");
    });
}

} // namespace hemi::io
