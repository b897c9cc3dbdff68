#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <half.h>

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
#define STBI_ONLY_JPEG
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>

namespace hemi::io
{
namespace
{
void check_image(const std::filesystem::path& path, const ImageRgba& image)
{
    if (image.width == 0 || image.height == 0)
        throw FormatError(path.string() + ": cannot write an empty image");
    if (image.pixels.size() != size_t(image.width) * image.height * 4)
        throw FormatError(
            path.string() + ": image has " + std::to_string(image.pixels.size()) +
            " floats, expected width*height*4 = " + std::to_string(size_t(image.width) * image.height * 4));
}
} // namespace

float srgb_oetf(float x)
{
    x = std::clamp(x, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

float srgb_eotf(float c)
{
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
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
        // Caps (io/image.h): the display window at most kMaxExrPixels, and at most kMaxExrPadding times the
        // data window unless it is small: an auto-cropped file pads with zeros, a hostile one of a few
        // hundred bytes would otherwise make us zero-fill gigabytes.
        if (w <= 0 || h <= 0 || w * h > long(kMaxExrPixels))
            throw FormatError(path.string() + ": EXR display window of " + std::to_string(w) + "x" +
                              std::to_string(h) + " is empty or larger than " +
                              std::to_string(kMaxExrPixels) + " pixels");
        if (dw.min.x < disp.min.x || dw.min.y < disp.min.y || dw.max.x > disp.max.x || dw.max.y > disp.max.y)
            throw FormatError(path.string() + ": EXR data window extends beyond the display window");
        const long data = (long(dw.max.x) - dw.min.x + 1) * (long(dw.max.y) - dw.min.y + 1);
        if (w * h > long(kMaxExrPaddedPixels) && w * h > data * long(kMaxExrPadding))
            throw FormatError(path.string() + ": EXR display window of " + std::to_string(w) + "x" +
                              std::to_string(h) + " is more than " + std::to_string(kMaxExrPadding) +
                              " times its data window (" + std::to_string(data) +
                              " pixels): refused rather than zero-filled");
        image.width = uint32_t(w);
        image.height = uint32_t(h);
        image.pixels.assign(size_t(w) * h * 4, 0.0f);
        const Imf::ChannelList& channels = file.header().channels();
        const bool grey = !channels.findChannel("R") && channels.findChannel("Y");
        if (!grey && !channels.findChannel("R") && !channels.findChannel("G") && !channels.findChannel("B"))
            throw FormatError(path.string() +
                              ": EXR has no R, G, B or Y channel (layered files are not supported)");
        const size_t xs = 4 * sizeof(float), ys = xs * size_t(w);
        // OpenEXR addresses pixel (x, y) at base + x * xs + y * ys: shift so that the display window's origin
        // is our first pixel.
        char* base = reinterpret_cast<char*>(image.pixels.data()) -
                     (long(disp.min.x) * long(xs) + long(disp.min.y) * long(ys));
        Imf::FrameBuffer fb;
        const char* names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; ++c)
        {
            if (grey && (c == 1 || c == 2))
                continue;
            const char* name = grey && c == 0 ? "Y" : names[c];
            fb.insert(name,
                      Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, c == 3 ? 1.0 : 0.0));
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

void write_exr_channels(const std::filesystem::path& path, uint32_t width, uint32_t height,
                        std::span<const ExrChannel> channels,
                        std::span<const std::pair<std::string, std::string>> attributes)
{
    if (width == 0 || height == 0 || channels.empty())
        throw FormatError(path.string() + ": an EXR needs a size and at least one channel");
    for (const ExrChannel& c : channels)
    {
        if (c.name.empty() || !c.data || c.stride == 0)
            throw FormatError(path.string() + ": EXR channel '" + c.name + "' has no name or no data");
    }
    write_atomically(
        path,
        [&](const std::filesystem::path& tmp)
        {
            try
            {
                Imf::Header header(static_cast<int>(width), static_cast<int>(height));
                for (const ExrChannel& c : channels)
                    header.channels().insert(c.name, Imf::Channel(c.half ? Imf::HALF : Imf::FLOAT));
                for (const auto& [key, value] : attributes)
                    header.insert(key, Imf::StringAttribute(value));
                // OpenEXR converts pixel types when it reads, not when it writes: half channels get half
                // data.
                std::vector<std::vector<half>> halves;
                {
                    Imf::OutputFile file(tmp.c_str(), header);
                    Imf::FrameBuffer fb;
                    for (const ExrChannel& c : channels)
                    {
                        if (c.half)
                        {
                            std::vector<half>& h = halves.emplace_back(size_t(width) * height);
                            for (size_t i = 0; i < h.size(); ++i)
                                h[i] = half(c.data[i * c.stride]);
                            fb.insert(c.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(h.data()),
                                                         sizeof(half), sizeof(half) * width));
                            continue;
                        }
                        const size_t xs = c.stride * sizeof(float), ys = xs * width;
                        fb.insert(c.name,
                                  Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(c.data)),
                                             xs, ys));
                    }
                    file.setFrameBuffer(fb);
                    file.writePixels(int(height));
                } // ~OutputFile writes the offset table and swallows its errors: verify by reading back
                if (!Imf::InputFile(tmp.c_str()).isComplete())
                    throw FormatError(path.string() + ": writing EXR failed (incomplete file)");
            }
            catch (const FormatError&)
            {
                throw;
            }
            catch (const std::exception& e)
            {
                throw FormatError(path.string() + ": writing EXR failed: " + e.what());
            }
        });
}

void write_exr(const std::filesystem::path& path, const ImageRgba& image)
{
    check_image(path, image);
    const char* names[4] = {"R", "G", "B", "A"};
    std::vector<ExrChannel> channels;
    for (int c = 0; c < 4; ++c)
        channels.push_back({names[c], image.pixels.data() + c, 4, false});
    write_exr_channels(path, image.width, image.height, channels);
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
    if (image.width == 0 || image.height == 0 ||
        image.pixels.size() != size_t(image.width) * image.height * 4)
        throw FormatError(path.string() + ": RGBA8 image of " + std::to_string(image.width) + "x" +
                          std::to_string(image.height) + " has " + std::to_string(image.pixels.size()) +
                          " bytes");
    int length = 0;
    unsigned char* png = stbi_write_png_to_mem(image.pixels.data(), int(image.width * 4), int(image.width),
                                               int(image.height), 4, &length);
    if (!png)
        throw FormatError(path.string() + ": encoding PNG failed (stb_image_write)");
    std::unique_ptr<unsigned char, void (*)(void*)> owner(png, std::free);
    write_atomically(path,
                     [&](const std::filesystem::path& tmp)
                     {
                         std::ofstream f(tmp, std::ios::binary);
                         f.write(reinterpret_cast<const char*>(png), length);
                         f.close();
                         if (f.fail())
                             throw FormatError(path.string() +
                                               ": writing PNG failed (disk full or not writable?)");
                     });
}

namespace
{

std::vector<uint8_t> read_file(const std::filesystem::path& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw FormatError(path.string() + ": no such file or not readable");
    std::ifstream f(path, std::ios::binary);
    if (!f)
        throw FormatError(path.string() + ": no such file or not readable");
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (f.bad())
        throw FormatError(path.string() + ": read error");
    return bytes;
}

uint32_t be32(const uint8_t* p)
{
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

uint32_t crc32(const uint8_t* p, size_t n)
{
    static const std::array<uint32_t, 256> table = []
    {
        std::array<uint32_t, 256> t{};
        for (uint32_t i = 0; i < 256; ++i)
        {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k)
                c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i)
        c = table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

// Walks a PNG's chunks before stb_image sees them. stb trusts the container: it does not check CRCs (a
// flipped bit decodes to a wrong image) and a zero-length IDAT before any image data makes it copy zero bytes
// to a null pointer (undefined behaviour). Like libpng, a bad CRC fails critical chunks and is ignored in
// ancillary ones. Returns a copy without the empty IDAT chunks when there are any (legal, but rare), else
// nothing.
std::optional<std::vector<uint8_t>> check_png(const std::vector<uint8_t>& b, const std::string& name)
{
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(name + ": " + what); };
    const size_t n = b.size();
    size_t pos = 8;
    bool idat = false;
    std::vector<size_t> empty_idat;
    for (bool first = true;; first = false)
    {
        if (n - pos < 12)
            throw fail("truncated PNG (" + std::to_string(n) + " bytes, no IEND chunk)");
        const uint32_t length = be32(&b[pos]);
        const uint8_t* type = &b[pos + 4];
        const std::string tag(reinterpret_cast<const char*>(type), 4);
        for (int i = 0; i < 4; ++i)
            if (!((type[i] >= 'A' && type[i] <= 'Z') || (type[i] >= 'a' && type[i] <= 'z')))
                throw fail("corrupt PNG: invalid chunk type at byte " + std::to_string(pos));
        if (length > 0x7FFFFFFFu)
            throw fail("corrupt PNG: chunk '" + tag + "' at byte " + std::to_string(pos) + " claims " +
                       std::to_string(length) + " bytes");
        if (length > n - pos - 12)
            throw fail("truncated PNG: chunk '" + tag + "' at byte " + std::to_string(pos) + " needs " +
                       std::to_string(length) + " bytes, the file ends first");
        const bool critical = type[0] >= 'A' && type[0] <= 'Z'; // bit 5 of the first letter clear
        if (critical && crc32(type, 4 + size_t(length)) != be32(&b[pos + 8 + length]))
            throw fail("corrupt PNG: chunk '" + tag + "' at byte " + std::to_string(pos) +
                       " fails its CRC check");
        if (first)
        {
            if (tag != "IHDR" || length != 13)
                throw fail("corrupt PNG: the first chunk is not a 13-byte IHDR");
            const uint32_t w = be32(&b[pos + 8]), h = be32(&b[pos + 12]);
            if (w == 0 || h == 0)
                throw fail("PNG of " + std::to_string(w) + "x" + std::to_string(h) + " pixels (empty)");
        }
        if (tag == "IDAT")
        {
            idat = true;
            if (length == 0)
                empty_idat.push_back(pos);
        }
        if (tag == "IEND")
            break;
        pos += 12 + size_t(length);
    }
    if (!idat)
        throw fail("corrupt PNG: no IDAT chunk (no image data)");
    if (empty_idat.empty())
        return std::nullopt;
    std::vector<uint8_t> out;
    out.reserve(n);
    size_t from = 0;
    for (size_t at : empty_idat)
    {
        out.insert(out.end(), b.begin() + long(from), b.begin() + long(at));
        from = at + 12;
    }
    out.insert(out.end(), b.begin() + long(from), b.end());
    return out;
}

// Walks a JPEG's segments to its EOI marker: stb_image reads past the end of a truncated JPEG as zeros and
// returns an image whose lower part is garbage, so truncation is caught here. Entropy-coded data after each
// SOS (several in a progressive JPEG) is skipped to the next marker (FF not followed by 00, FF or RSTn).
void check_jpeg(const std::vector<uint8_t>& b, const std::string& name)
{
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(name + ": " + what); };
    auto truncated = [&]
    { return fail("truncated JPEG (" + std::to_string(b.size()) + " bytes, no EOI marker)"); };
    const size_t n = b.size();
    size_t pos = 2; // after SOI
    bool frame = false, scan = false, progressive = false;
    bool defined[2][4] = {}; // Huffman tables defined so far: [class: 0 DC, 1 AC][id]
    while (true)
    {
        if (pos >= n)
            throw truncated();
        if (b[pos] != 0xFF)
            throw fail("corrupt JPEG: no marker at byte " + std::to_string(pos));
        while (pos < n && b[pos] == 0xFF) // fill bytes
            ++pos;
        if (pos >= n)
            throw truncated();
        const uint8_t marker = b[pos++];
        if (marker == 0xD9) // EOI
            break;
        if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) // TEM, RSTn: no length
            continue;
        if (marker == 0x00 || marker == 0xD8)
            throw fail("corrupt JPEG: unexpected marker at byte " + std::to_string(pos - 1));
        if (n - pos < 2)
            throw truncated();
        const size_t length = size_t(b[pos]) << 8 | b[pos + 1];
        if (length < 2)
            throw fail("corrupt JPEG: segment of length " + std::to_string(length) + " at byte " +
                       std::to_string(pos));
        if (length > n - pos)
            throw truncated();
        // SOF0..SOF15, except DHT (C4), JPG (C8) and DAC (CC).
        if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC)
        {
            frame = true;
            // SOF2, 6, 10, 14: progressive (stb_image reads SOF2); the others sequential.
            progressive = marker == 0xC2 || marker == 0xC6 || marker == 0xCA || marker == 0xCE;
        }
        if (marker == 0xC4)
        {
            // DHT: tables of 1 byte class/id, 16 code counts, then that many symbols. Debian's stb_image
            // builds each table into 257 bytes without checking that the counts sum to at most 256 (found by
            // tests/fuzz/fuzz_image): a corrupt table would write past them.
            size_t at = pos + 2;
            const size_t end = pos + length;
            while (at < end)
            {
                if (end - at < 17)
                    throw fail("corrupt JPEG: truncated Huffman table at byte " + std::to_string(at));
                size_t symbols = 0;
                uint64_t code_space = 0; // Kraft: the lengths of a prefix code use at most 2^16 of 2^16
                for (size_t i = 1; i <= 16; ++i)
                {
                    symbols += b[at + i];
                    code_space += uint64_t(b[at + i]) << (16 - i);
                }
                // An over-subscribed table is no prefix code: stb_image 2.27 then indexes its tables with
                // negative numbers (found by tests/fuzz/fuzz_image).
                if (code_space > (uint64_t(1) << 16))
                    throw fail("corrupt JPEG: Huffman table is not a prefix code (its code lengths "
                               "over-subscribe) at "
                               "byte " +
                               std::to_string(at));
                if (symbols > 256)
                    throw fail("corrupt JPEG: Huffman table of " + std::to_string(symbols) +
                               " codes (at most 256) at byte " + std::to_string(at));
                if (end - at - 17 < symbols)
                    throw fail("corrupt JPEG: Huffman table overruns its segment at byte " +
                               std::to_string(at));
                const uint8_t table_class = b[at] >> 4, table_id = b[at] & 0x0F;
                if (table_class > 1 || table_id > 3)
                    throw fail("corrupt JPEG: Huffman table of class " + std::to_string(table_class) +
                               " and id " + std::to_string(table_id) + " at byte " + std::to_string(at));
                defined[table_class][table_id] = true;
                at += 17 + symbols;
            }
        }
        if (marker == 0xDA)
        {
            // SOS: every component's tables must be defined before the scan that decodes with them. stb_image
            // decodes with a zeroed table otherwise and indexes its symbols out of bounds (found by
            // tests/fuzz/fuzz_image). A sequential scan decodes every coefficient with both tables, whatever
            // its Ss and Se say (found by the fuzzer: Se = 0 in a baseline scan); in a progressive frame a
            // first DC scan (Ss = 0, Ah = 0) uses DC tables, a scan of AC coefficients (Se > 0) AC tables,
            // and a DC refinement reads plain bits.
            const size_t components = length >= 3 ? b[pos + 2] : 0;
            if (components == 0 || length != 6 + 2 * components)
                throw fail("corrupt JPEG: scan header of length " + std::to_string(length) + " at byte " +
                           std::to_string(pos));
            const size_t tail = pos + 3 + 2 * components;
            const uint8_t ss = b[tail], se = b[tail + 1], ah = b[tail + 2] >> 4;
            for (size_t c = 0; c < components; ++c)
            {
                const uint8_t tables = b[pos + 4 + 2 * c], dc = tables >> 4, ac = tables & 0x0F;
                const bool uses_dc = !progressive || (ss == 0 && ah == 0), uses_ac = !progressive || se > 0;
                if ((uses_dc && (dc > 3 || !defined[0][dc])) || (uses_ac && (ac > 3 || !defined[1][ac])))
                    throw fail("corrupt JPEG: the scan at byte " + std::to_string(pos) +
                               " decodes with a Huffman table that is not defined (DC " + std::to_string(dc) +
                               ", AC " + std::to_string(ac) + ")");
            }
        }
        pos += length;
        if (marker != 0xDA) // SOS: entropy-coded data follows
            continue;
        if (!frame)
            throw fail("corrupt JPEG: a scan before the frame header");
        scan = true;
        while (true)
        {
            const void* ff = pos < n ? std::memchr(&b[pos], 0xFF, n - pos) : nullptr;
            if (!ff)
                throw truncated();
            pos = size_t(static_cast<const uint8_t*>(ff) - b.data());
            if (pos + 1 >= n)
                throw truncated();
            const uint8_t next = b[pos + 1];
            if (next == 0x00 || (next >= 0xD0 && next <= 0xD7))
                pos += 2;
            else if (next == 0xFF)
                pos += 1;
            else
                break; // a marker: the outer loop reads it
        }
    }
    if (!frame || !scan)
        throw fail("corrupt JPEG: no frame header or no scan before EOI");
}

void check_rgba8(const ImageRgba8& image, const char* what)
{
    if (image.width == 0 || image.height == 0 || image.width > (1u << 24) || image.height > (1u << 24) ||
        image.pixels.size() != size_t(image.width) * image.height * 4)
        throw std::invalid_argument(std::string("hemi: ") + what + ": RGBA8 image of " +
                                    std::to_string(image.width) + "x" + std::to_string(image.height) +
                                    " has " + std::to_string(image.pixels.size()) + " bytes");
}

void append_bytes(void* context, void* data, int size)
{
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    const auto* p = static_cast<const uint8_t*>(data);
    out->insert(out->end(), p, p + size);
}

} // namespace

namespace
{

// The bytes of a checked PNG or JPEG as stb_image is to see them (a PNG's ancillary chunks may be cleaned),
// with the size and channel count its header declares.
struct CheckedImage
{
    std::optional<std::vector<uint8_t>> cleaned;
    const std::vector<uint8_t>* bytes = nullptr;
    std::string mime;
    int width = 0, height = 0, channels = 0;

    const std::vector<uint8_t>& data() const { return cleaned ? *cleaned : *bytes; }
};

CheckedImage check_encoded_image(const EncodedImage& image, const std::string& name)
{
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(name + ": " + what); };
    const std::vector<uint8_t>& bytes = image.bytes;
    if (bytes.empty())
        throw fail("empty image (0 bytes)");
    CheckedImage c;
    c.bytes = &bytes;
    c.mime = sniff_image_mime_type(bytes.data(), bytes.size());
    if (c.mime.empty())
        throw fail("neither a PNG nor a JPEG image (unknown signature)");
    if (!image.mime_type.empty() && image.mime_type != c.mime)
        throw fail("declared " + image.mime_type + ", but the bytes are " + c.mime);
    if (bytes.size() > size_t(INT_MAX))
        throw fail("larger than 2 GiB");
    if (c.mime == "image/png")
        c.cleaned = check_png(bytes, name);
    else
        check_jpeg(bytes, name);
    const std::vector<uint8_t>& data = c.data();
    const int size = int(data.size());
    int& w = c.width;
    int& h = c.height;
    if (!stbi_info_from_memory(data.data(), size, &w, &h, &c.channels))
        throw fail("corrupt or unsupported " + c.mime.substr(6) + " (" + stbi_failure_reason() + ")");
    if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > (uint64_t(1) << 28))
        throw fail(std::to_string(w) + "x" + std::to_string(h) +
                   " pixels is empty or larger than 2^28 pixels");
    // A few hundred bytes must not make us decode hundreds of megapixels (seconds and gigabytes, found by
    // tests/fuzz/fuzz_image): a header's size has to be plausible for the bytes that follow it. Deflate
    // compresses at most 1032:1 and a PNG row holds at least a filter byte and one bit a pixel; a baseline or
    // progressive JPEG (stb reads no arithmetic coding) spends at least one bit on every 8x8 luma block.
    // Both bounds are lower than any real file's, by a margin of 2.
    const uint64_t pixels_w = uint64_t(w), pixels_h = uint64_t(h);
    const uint64_t least = c.mime == "image/png" ? pixels_h * (1 + (pixels_w + 7) / 8) / 1032 / 2
                                                 : ((pixels_w + 7) / 8) * ((pixels_h + 7) / 8) / 8 / 2;
    if (uint64_t(data.size()) < least)
        throw fail(std::to_string(w) + "x" + std::to_string(h) + " pixels cannot be coded in " +
                   std::to_string(data.size()) + " bytes (at least " + std::to_string(least) +
                   "): a corrupt or hostile header");
    return c;
}

// RGBA samples at 16 bits (8-bit images scaled by 257, so 255 -> 65535), and the stored bit depth.
std::vector<uint16_t> decode_rgba16(const CheckedImage& c, const std::string& name, int& bits)
{
    const std::vector<uint8_t>& data = c.data();
    const int size = int(data.size());
    int w = 0, h = 0, channels = 0;
    std::vector<uint16_t> out(size_t(c.width) * size_t(c.height) * 4);
    if (c.mime == "image/png" && stbi_is_16_bit_from_memory(data.data(), size))
    {
        bits = 16;
        stbi_us* wide = stbi_load_16_from_memory(data.data(), size, &w, &h, &channels, 4);
        if (!wide)
            throw FormatError(name + ": corrupt PNG (" + std::string(stbi_failure_reason()) + ")");
        std::unique_ptr<stbi_us, void (*)(void*)> owner(wide, stbi_image_free);
        std::memcpy(out.data(), wide, out.size() * sizeof(uint16_t));
        return out;
    }
    bits = 8;
    unsigned char* narrow = stbi_load_from_memory(data.data(), size, &w, &h, &channels, 4);
    if (!narrow)
        throw FormatError(name + ": corrupt or unsupported " + c.mime.substr(6) + " (" +
                          stbi_failure_reason() + ")");
    std::unique_ptr<unsigned char, void (*)(void*)> owner(narrow, stbi_image_free);
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = uint16_t(narrow[i] * 257u);
    return out;
}

} // namespace

ImageRgba8 decode_image(const EncodedImage& image)
{
    const std::string name = image.name.empty() ? std::string("unnamed image") : image.name;
    const CheckedImage c = check_encoded_image(image, name);
    const std::vector<uint8_t>& data = c.data();
    const int size = int(data.size());
    int w = 0, h = 0, channels = 0;
    ImageRgba8 out{uint32_t(c.width), uint32_t(c.height),
                   std::vector<uint8_t>(size_t(c.width) * size_t(c.height) * 4)};
    if (c.mime == "image/png" && stbi_is_16_bit_from_memory(data.data(), size))
    {
        // stb reduces 16 to 8 bits by dropping the low byte; round instead (65535 -> 255, 32896 -> 128).
        int bits = 0;
        const std::vector<uint16_t> wide = decode_rgba16(c, name, bits);
        for (size_t i = 0; i < out.pixels.size(); ++i)
            out.pixels[i] = uint8_t((uint32_t(wide[i]) * 255u + 32767u) / 65535u);
        return out;
    }
    unsigned char* narrow = stbi_load_from_memory(data.data(), size, &w, &h, &channels, 4);
    if (!narrow)
        throw FormatError(name + ": corrupt or unsupported " + c.mime.substr(6) + " (" +
                          stbi_failure_reason() + ")");
    std::unique_ptr<unsigned char, void (*)(void*)> owner(narrow, stbi_image_free);
    std::memcpy(out.pixels.data(), narrow, out.pixels.size());
    return out;
}

DataImage read_data_image(const std::filesystem::path& path)
{
    std::vector<uint8_t> head = read_file(path);
    static const uint8_t exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};
    if (head.size() >= 4 && std::memcmp(head.data(), exr_magic, 4) == 0)
    {
        head.clear();
        ImageRgba rgba = read_exr(path);
        DataImage out;
        out.width = rgba.width;
        out.height = rgba.height;
        out.channels = 4;
        out.bits = 32;
        out.pixels = std::move(rgba.pixels);
        return out;
    }
    EncodedImage image;
    image.name = path.string();
    image.bytes = std::move(head);
    image.mime_type = sniff_image_mime_type(image.bytes.data(), image.bytes.size());
    if (image.mime_type != "image/png")
        throw FormatError(path.string() + ": " +
                          (image.mime_type.empty()
                               ? std::string("neither a PNG nor an EXR file")
                               : "a JPEG: data images (height maps) must be PNG or EXR, whose "
                                 "values are exact (JPEG's are not)") +
                          (image.bytes.empty() ? std::string(" (empty)") : std::string()));
    const CheckedImage c = check_encoded_image(image, image.name);
    DataImage out;
    out.width = uint32_t(c.width);
    out.height = uint32_t(c.height);
    out.channels = c.channels;
    const std::vector<uint16_t> samples = decode_rgba16(c, image.name, out.bits);
    out.pixels.resize(samples.size());
    for (size_t i = 0; i < samples.size(); ++i)
        out.pixels[i] = float(samples[i]) / 65535.0f;
    return out;
}

EncodedImage read_encoded_image(const std::filesystem::path& path)
{
    EncodedImage image;
    image.name = path.string();
    image.bytes = read_file(path);
    image.mime_type = sniff_image_mime_type(image.bytes.data(), image.bytes.size());
    if (image.mime_type.empty())
        throw FormatError(path.string() + ": neither a PNG nor a JPEG file" +
                          (image.bytes.empty() ? std::string(" (empty)") : std::string()));
    return image;
}

ImageRgba8 read_png(const std::filesystem::path& path)
{
    EncodedImage image;
    image.name = path.string();
    image.bytes = read_file(path);
    if (sniff_image_mime_type(image.bytes.data(), image.bytes.size()) != "image/png")
        throw FormatError(path.string() + ": not a PNG file");
    image.mime_type = "image/png";
    return decode_image(image);
}

std::vector<uint8_t> encode_png(const ImageRgba8& image)
{
    check_rgba8(image, "encode_png");
    std::vector<uint8_t> out;
    if (!stbi_write_png_to_func(append_bytes, &out, int(image.width), int(image.height), 4,
                                image.pixels.data(), int(image.width * 4)))
        throw std::runtime_error("hemi: encoding PNG failed (stb_image_write)");
    return out;
}

std::vector<uint8_t> encode_jpeg(const ImageRgba8& image, int quality)
{
    check_rgba8(image, "encode_jpeg");
    if (quality < 1 || quality > 100)
        throw std::invalid_argument("hemi: encode_jpeg: quality " + std::to_string(quality) +
                                    " is not in [1, 100]");
    std::vector<uint8_t> out;
    if (!stbi_write_jpg_to_func(append_bytes, &out, int(image.width), int(image.height), 4,
                                image.pixels.data(), quality))
        throw std::runtime_error("hemi: encoding JPEG failed (stb_image_write)");
    return out;
}

} // namespace hemi::io
