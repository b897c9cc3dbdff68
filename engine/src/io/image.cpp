#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#include <stb/stb_image_write.h>
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>

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

ImageRgba read_exr(const std::filesystem::path& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw FormatError(path.string() + ": no such file");
    ImageRgba image;
    try
    {
        Imf::InputFile file(path.c_str());
        // The image is the display window; pixels outside the data window (auto-cropped files) read as 0.
        const Imath::Box2i dw = file.header().dataWindow();
        const Imath::Box2i disp = file.header().displayWindow();
        const long w = long(disp.max.x) - disp.min.x + 1, h = long(disp.max.y) - disp.min.y + 1;
        if (w <= 0 || h <= 0 || w * h > (1l << 28))
            throw FormatError(path.string() + ": EXR display window of " + std::to_string(w) + "x" + std::to_string(h) +
                              " is empty or larger than 2^28 pixels");
        if (dw.min.x < disp.min.x || dw.min.y < disp.min.y || dw.max.x > disp.max.x || dw.max.y > disp.max.y)
            throw FormatError(path.string() + ": EXR data window extends beyond the display window");
        image.width = uint32_t(w);
        image.height = uint32_t(h);
        image.pixels.assign(size_t(w) * h * 4, 0.0f);
        const Imf::ChannelList& channels = file.header().channels();
        const bool grey = !channels.findChannel("R") && channels.findChannel("Y");
        if (!grey && !channels.findChannel("R") && !channels.findChannel("G") && !channels.findChannel("B"))
            throw FormatError(path.string() + ": EXR has no R, G, B or Y channel (layered files are not supported)");
        const size_t xs = 4 * sizeof(float), ys = xs * size_t(w);
        // OpenEXR addresses pixel (x, y) at base + x * xs + y * ys: shift so that the display window's origin
        // is our first pixel.
        char* base =
            reinterpret_cast<char*>(image.pixels.data()) - (long(disp.min.x) * long(xs) + long(disp.min.y) * long(ys));
        Imf::FrameBuffer fb;
        const char* names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; ++c)
        {
            if (grey && (c == 1 || c == 2))
                continue;
            const char* name = grey && c == 0 ? "Y" : names[c];
            fb.insert(name, Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, c == 3 ? 1.0 : 0.0));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        if (grey) // a FrameBuffer holds one slice per name: copy Y into G and B
            for (size_t i = 0; i < image.pixels.size(); i += 4)
                image.pixels[i + 1] = image.pixels[i + 2] = image.pixels[i];
    }
    catch (const FormatError&)
    {
        throw;
    }
    catch (const std::exception& e)
    {
        throw FormatError(path.string() + ": not a readable EXR file: " + e.what());
    }
    for (size_t i = 0; i < image.pixels.size(); ++i)
        if (!std::isfinite(image.pixels[i]))
        {
            size_t p = i / 4;
            throw FormatError(path.string() + ": pixel (" + std::to_string(p % image.width) + ", " +
                              std::to_string(p / image.width) + ") is not finite");
        }
    return image;
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
            {
                Imf::OutputFile file(tmp.c_str(), header);
                Imf::FrameBuffer fb;
                const size_t xs = 4 * sizeof(float), ys = xs * image.width;
                char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()));
                const char* names[4] = {"R", "G", "B", "A"};
                for (int c = 0; c < 4; ++c)
                    fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
                file.setFrameBuffer(fb);
                file.writePixels(int(image.height));
            } // ~OutputFile writes the offset table and swallows its errors: verify by reading back
            if (!Imf::InputFile(tmp.c_str()).isComplete())
                throw FormatError(path.string() + ": writing EXR failed (incomplete file)");
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
    write_png(path, ImageRgba8{image.width, image.height, std::move(bytes)});
}

void write_png(const std::filesystem::path& path, const ImageRgba8& image)
{
    if (image.width == 0 || image.height == 0 || image.pixels.size() != size_t(image.width) * image.height * 4)
        throw FormatError(path.string() + ": RGBA8 image of " + std::to_string(image.width) + "x" +
                          std::to_string(image.height) + " has " + std::to_string(image.pixels.size()) + " bytes");
    int length = 0;
    unsigned char* png = stbi_write_png_to_mem(image.pixels.data(), int(image.width * 4), int(image.width),
                                               int(image.height), 4, &length);
    if (!png)
        throw FormatError(path.string() + ": encoding PNG failed (stb_image_write)");
    std::unique_ptr<unsigned char, void (*)(void*)> owner(png, std::free);
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream f(tmp, std::ios::binary);
        f.write(reinterpret_cast<const char*>(png), length);
        f.close();
        if (f.fail())
            throw FormatError(path.string() + ": writing PNG failed (disk full or not writable?)");
    });
}

ImageRgba8 read_png(const std::filesystem::path& path)
{
    std::ifstream f(path, std::ios::binary);
    if (!f)
        throw FormatError(path.string() + ": no such file or not readable");
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (bytes.size() < 8 || std::memcmp(bytes.data(), "\x89PNG\r\n\x1a\n", 8) != 0)
        throw FormatError(path.string() + ": not a PNG file");
    int w = 0, h = 0, channels = 0;
    unsigned char* data = stbi_load_from_memory(bytes.data(), int(bytes.size()), &w, &h, &channels, 4);
    if (!data)
        throw FormatError(path.string() + ": corrupt or truncated PNG (" + stbi_failure_reason() + ")");
    std::unique_ptr<unsigned char, void (*)(void*)> owner(data, stbi_image_free);
    ImageRgba8 out{uint32_t(w), uint32_t(h), {}};
    out.pixels.assign(data, data + size_t(w) * h * 4);
    return out;
}

} // namespace hemi::io
