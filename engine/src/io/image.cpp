#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>
#include <hemi/io/memory.h>

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

#include <jerror.h>
#include <jpeglib.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
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

namespace
{
// ---- read_exr: a look at the file before OpenEXR's ----
// OpenEXR 3.1 allocates what a header claims before it reads what the claim is about: every attribute's value
// at its declared size (a string is zero-filled to it), the chunk offset table, one chunk's line or tile
// buffers and its compressor's; and read_exr's own image follows the header's windows. A few hundred hostile
// bytes could so make it allocate and fault gigabytes (tests/fuzz/fuzz_exr ran at 4 executions a second under
// AddressSanitizer, nearly all of it faulting in the pages of attribute values a header claimed). So the
// headers are walked here first, as OpenEXR will read them, and a file is refused unless what they claim can
// be there: every attribute's value and the offset tables lie in the file, and the data window's pixels (and
// any one chunk) can be coded in the file's bytes at the compression's largest expansion. The pixels are
// then read in bands that grow with what has decoded, never with what the header says.

// Per compression (Imf::Compression 0-9): the scanlines in a chunk, twice the largest expansion the method
// can achieve (decoded bytes per stored byte), and a name. NONE stores the bytes as they are; RLE codes at
// most 128 equal bytes in 2; deflate (ZIPS, ZIP) at most 1032:1, PXR24 deflates 24 of a float's 32 bits
// (1376:1); PIZ's Huffman coder spends at least 10 bits on a run of 256 16-bit values (410:1); B44A stores a
// flat 4x4 block of halves in 3 bytes (10.7:1); DWAA/DWAB deflate the RLE (64:1) of some channels (66048:1).
constexpr int kExrCompressions = 10;
constexpr uint64_t kExrChunkLines[kExrCompressions] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
constexpr uint64_t kExrExpansion[kExrCompressions] = {1, 128, 2064, 2064, 820, 2752, 22, 22, 132096, 132096};
const char* const kExrCompressionNames[kExrCompressions] = {"no compression", "RLE", "ZIPS", "ZIP",  "PIZ",
                                                            "PXR24",          "B44", "B44A", "DWAA", "DWAB"};
// A chunk's buffers (OpenEXR's, for a chunk of every channel; read_exr's, of RGBA floats) may overhang the
// data window (a tile larger than the image, a block of scanlines taller than it) by this much.
constexpr uint64_t kExrChunkOverhangBytes = uint64_t(64) << 20;

uint64_t mul_sat(uint64_t a, uint64_t b)
{
    return a != 0 && b > UINT64_MAX / a ? UINT64_MAX : a * b;
}

uint64_t add_sat(uint64_t a, uint64_t b)
{
    return b > UINT64_MAX - a ? UINT64_MAX : a + b;
}

struct ExrBox
{
    int64_t x0 = 0, y0 = 0, x1 = 63, y1 = 63; // OpenEXR's default windows, for a header without them
    int64_t width() const { return x1 - x0 + 1; }
    int64_t height() const { return y1 - y0 + 1; }
    bool operator==(const ExrBox&) const = default;
};

struct ExrChannelInfo
{
    std::string name;
    int32_t type = 0;
    int32_t x_sampling = 1, y_sampling = 1;
};

struct ExrPart
{
    std::map<std::string, std::string> types; // attribute name -> type name, as OpenEXR's Header holds them
    ExrBox data, display;
    int compression = 3; // OpenEXR's default: ZIP
    std::vector<ExrChannelInfo> channels;
    bool has_tiles = false;
    uint64_t tile_width = 0, tile_height = 0;
    int level_mode = 0, rounding = 0;
    std::string type;
    bool has_type = false;
    int64_t chunk_count = -1;
};

struct ExrLayout
{
    bool multipart = false, tiled = false, non_image = false;
    std::vector<ExrPart> parts;
    uint64_t header_end = 0, file_size = 0;
};

// Walks an EXR's headers exactly as OpenEXR 3.1's Header::readFrom consumes them, refusing what OpenEXR would
// allocate for without the file holding it. Reads nothing but the headers, and allocates only what they hold.
class ExrHeaderScan
{
  public:
    ExrHeaderScan(const std::filesystem::path& path, const std::string& file)
        : file_(file), in_(path, std::ios::binary)
    {
        std::error_code ec;
        size_ = std::filesystem::file_size(path, ec);
        if (ec || !in_)
            throw FormatError(file_ + ": no such file or not readable");
    }

    ExrLayout scan()
    {
        ExrLayout layout;
        layout.file_size = size_;
        const uint32_t magic = u32();
        if (magic != 20000630u)
            fail("no EXR magic number");
        const uint32_t version = u32();
        if ((version & 0xFF) != 2 || (version & ~uint32_t(0x1EFF)) != 0)
            fail("EXR version field " + std::to_string(version) + " is not one OpenEXR 2 reads");
        layout.tiled = version & 0x200;
        layout.non_image = version & 0x800;
        layout.multipart = version & 0x1000;
        if (!layout.multipart)
            layout.parts.push_back(header());
        else
            while (peek() != 0)
                layout.parts.push_back(header());
        if (layout.multipart)
            u8(); // the empty header that ends the list
        if (layout.parts.empty())
            fail("a multi-part file of no parts");
        layout.header_end = at_;
        return layout;
    }

  private:
    [[noreturn]] void fail(const std::string& what) const
    {
        throw FormatError(file_ + ": not a readable EXR file: " + what);
    }
    uint64_t left() const { return size_ - at_; }
    void read(void* out, uint64_t n, const char* what)
    {
        if (n > left())
            fail(std::string("truncated header (") + what + " at byte " + std::to_string(at_) + ")");
        in_.read(static_cast<char*>(out), std::streamsize(n));
        if (!in_)
            fail("read error in the header");
        at_ += n;
    }
    void skip(uint64_t n)
    {
        in_.seekg(std::streamoff(n), std::ios::cur);
        at_ += n;
    }
    uint8_t peek()
    {
        uint8_t b = 0;
        read(&b, 1, "the next header");
        in_.seekg(-1, std::ios::cur);
        --at_;
        return b;
    }
    uint8_t u8()
    {
        uint8_t b = 0;
        read(&b, 1, "a byte");
        return b;
    }
    uint32_t u32()
    {
        uint8_t b[4];
        read(b, 4, "an integer");
        return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
    }
    int32_t i32() { return int32_t(u32()); }
    // A NUL-terminated name of at most 255 bytes (OpenEXR's Name).
    std::string name(const char* what)
    {
        std::string s;
        for (char c = char(u8()); c != 0; c = char(u8()))
        {
            if (s.size() == 255)
                fail(std::string(what) + " of more than 255 bytes");
            s.push_back(c);
        }
        return s;
    }
    ExrBox box()
    {
        ExrBox b;
        b.x0 = i32(), b.y0 = i32(), b.x1 = i32(), b.y1 = i32();
        return b;
    }

    ExrPart header()
    {
        // The attributes a default-constructed Imf::Header has: a file's attribute of one of these names must
        // have its type.
        ExrPart part;
        part.types = {{"displayWindow", "box2i"},     {"dataWindow", "box2i"},
                      {"pixelAspectRatio", "float"},  {"screenWindowCenter", "v2f"},
                      {"screenWindowWidth", "float"}, {"lineOrder", "lineOrder"},
                      {"compression", "compression"}, {"channels", "chlist"}};
        // OpenEXR 3.1's attribute types that read a fixed number of bytes, whatever the size field says.
        static const std::map<std::string, uint64_t> fixed = {{"box2i", 16},
                                                              {"box2f", 16},
                                                              {"chromaticities", 32},
                                                              {"compression", 1},
                                                              {"deepImageState", 1},
                                                              {"double", 8},
                                                              {"envmap", 1},
                                                              {"float", 4},
                                                              {"int", 4},
                                                              {"keycode", 28},
                                                              {"lineOrder", 1},
                                                              {"m33d", 72},
                                                              {"m33f", 36},
                                                              {"m44d", 128},
                                                              {"m44f", 64},
                                                              {"rational", 8},
                                                              {"tiledesc", 9},
                                                              {"timecode", 8},
                                                              {"v2d", 16},
                                                              {"v2f", 8},
                                                              {"v2i", 8},
                                                              {"v3d", 24},
                                                              {"v3f", 12},
                                                              {"v3i", 12}};
        while (true)
        {
            const std::string attribute = name("an attribute name");
            if (attribute.empty())
                return part;
            const std::string type = name("an attribute type name");
            const int32_t size = i32();
            const std::string what = "header attribute '" + attribute + "' (" + type + ")";
            if (size < 0 || uint64_t(size) > left())
                fail(what + " claims " + std::to_string(size) + " bytes, the file has " +
                     std::to_string(left()) + " after it: truncated, or a hostile header");
            if (const auto [it, added] = part.types.emplace(attribute, type); !added && it->second != type)
                fail(what + " was declared of type '" + it->second + "'");
            const uint64_t start = at_;
            if (const auto f = fixed.find(type); f != fixed.end() && uint64_t(size) != f->second)
                fail(what + " has " + std::to_string(size) + " bytes, not " + std::to_string(f->second));
            if (type == "chlist")
            {
                std::vector<ExrChannelInfo> channels;
                while (true)
                {
                    const std::string channel = name("a channel name");
                    if (channel.empty())
                        break;
                    ExrChannelInfo c;
                    c.name = channel;
                    c.type = i32();
                    skip_checked(4);
                    c.x_sampling = i32();
                    c.y_sampling = i32();
                    channels.push_back(c);
                    if (at_ - start > uint64_t(size))
                        break;
                }
                if (at_ - start != uint64_t(size))
                    fail(what + " has " + std::to_string(size) + " bytes, but its channels take " +
                         std::to_string(at_ - start));
                // OpenEXR merges a repeated channel list into the one it has (a name already there is
                // replaced): so does the scan, so that what it bounds is what OpenEXR will allocate for.
                if (attribute == "channels")
                    for (ExrChannelInfo& c : channels)
                    {
                        auto same = std::find_if(part.channels.begin(), part.channels.end(),
                                                 [&](const ExrChannelInfo& e) { return e.name == c.name; });
                        if (same != part.channels.end())
                            *same = std::move(c);
                        else
                            part.channels.push_back(std::move(c));
                    }
                continue;
            }
            if (type == "preview")
            {
                // OpenEXR allocates width x height pixels before it reads them.
                const int64_t w = size >= 8 ? i32() : -1, h = size >= 8 ? i32() : -1;
                if (w < 0 || h < 0 || uint64_t(w) * uint64_t(h) * 4 + 8 != uint64_t(size))
                    fail(what + " of " + std::to_string(size) + " bytes does not hold its preview image");
                skip(uint64_t(size) - 8);
                continue;
            }
            if (type == "floatvector" && size % 4 != 0)
                fail(what + " of " + std::to_string(size) + " bytes is no whole number of floats");
            if (type == "idmanifest")
            {
                // OpenEXR 3.1.5 reads an 8-byte size and then size - 4 bytes.
                if (size < 4 || uint64_t(size) + 4 > left())
                    fail(what + " of " + std::to_string(size) + " bytes is truncated");
                skip(uint64_t(size) + 4);
                continue;
            }
            if (attribute == "dataWindow")
                part.data = box();
            else if (attribute == "displayWindow")
                part.display = box();
            else if (attribute == "compression")
                part.compression = u8();
            else if (attribute == "tiles" && type == "tiledesc")
            {
                part.has_tiles = true;
                part.tile_width = u32();
                part.tile_height = u32();
                const uint8_t mode = u8();
                part.level_mode = mode & 0x0F;
                part.rounding = mode >> 4;
            }
            else if (attribute == "type" && type == "string")
            {
                part.type.resize(size_t(size));
                read(part.type.data(), uint64_t(size), "the type attribute");
                part.has_type = true;
            }
            else if (attribute == "chunkCount" && type == "int")
                part.chunk_count = i32();
            else
                skip(uint64_t(size));
            if (at_ - start != uint64_t(size))
                skip(uint64_t(size) - (at_ - start));
        }
    }
    void skip_checked(uint64_t n)
    {
        if (n > left())
            fail("truncated header (a channel at byte " + std::to_string(at_) + ")");
        skip(n);
    }

    const std::string& file_;
    std::ifstream in_;
    uint64_t size_ = 0, at_ = 0;
};

// OpenEXR's level count along an axis of `size` pixels: log2 rounded down (rounding 0) or up, plus one.
uint64_t exr_levels(uint64_t size, int rounding)
{
    uint64_t floor_log = 0;
    while (floor_log < 63 && (uint64_t(2) << floor_log) <= size)
        ++floor_log;
    const bool exact = (uint64_t(1) << floor_log) == size;
    return (rounding == 1 && !exact ? floor_log + 1 : floor_log) + 1;
}

uint64_t exr_level_tiles(uint64_t size, uint64_t level, int rounding, uint64_t tile)
{
    uint64_t s = level < 64 ? size >> level : 0;
    if (rounding == 1 && level < 64 && (s << level) < size)
        ++s;
    s = std::max<uint64_t>(s, 1);
    return (s + tile - 1) / tile;
}

// The number of chunks (entries in the offset table) of a flat or deep part, as OpenEXR counts them.
uint64_t exr_chunks(const ExrPart& part, bool tiled, const std::string& file)
{
    auto fail = [&](const std::string& what)
    { return FormatError(file + ": not a readable EXR file: " + what); };
    if (part.data.x0 > part.data.x1 || part.data.y0 > part.data.y1)
        throw fail("invalid data window (" + std::to_string(part.data.x0) + ", " +
                   std::to_string(part.data.y0) + ") - (" + std::to_string(part.data.x1) + ", " +
                   std::to_string(part.data.y1) + ")");
    if (part.compression >= kExrCompressions)
        throw fail("unknown compression method " + std::to_string(part.compression));
    const uint64_t w = uint64_t(part.data.width()), h = uint64_t(part.data.height());
    if (!tiled)
        return (h + kExrChunkLines[part.compression] - 1) / kExrChunkLines[part.compression];
    if (!part.has_tiles || part.tile_width == 0 || part.tile_height == 0 || part.tile_width > INT_MAX ||
        part.tile_height > INT_MAX || part.level_mode > 2 || part.rounding > 1)
        throw fail("a tiled image without a valid tile description");
    const uint64_t tw = part.tile_width, th = part.tile_height;
    if (part.level_mode == 0)
        return mul_sat((w + tw - 1) / tw, (h + th - 1) / th);
    if (part.level_mode == 1)
    {
        uint64_t n = 0;
        for (uint64_t l = 0, levels = exr_levels(std::max(w, h), part.rounding); l < levels; ++l)
            n = add_sat(n, mul_sat(exr_level_tiles(w, l, part.rounding, tw),
                                   exr_level_tiles(h, l, part.rounding, th)));
        return n;
    }
    uint64_t nx = 0, ny = 0;
    for (uint64_t l = 0, levels = exr_levels(w, part.rounding); l < levels; ++l)
        nx = add_sat(nx, exr_level_tiles(w, l, part.rounding, tw));
    for (uint64_t l = 0, levels = exr_levels(h, part.rounding); l < levels; ++l)
        ny = add_sat(ny, exr_level_tiles(h, l, part.rounding, th));
    return mul_sat(nx, ny);
}

struct ExrPlan
{
    bool grey = false;
    bool tiled = false;
    uint64_t chunk_rows = 1; // scanlines of a chunk, or a tile's height
};

// read_exr's refusals of a header, before OpenEXR reads it (io/image.h's caps, and what the file can hold).
ExrPlan check_exr_layout(const ExrLayout& layout, const std::string& file)
{
    auto fail = [&](const std::string& what) { return FormatError(file + ": " + what); };
    const ExrPart& part = layout.parts[0];
    ExrPlan plan;
    plan.tiled = layout.multipart ? part.type == "tiledimage" : layout.tiled;
    const bool flat =
        layout.multipart ? (part.type == "scanlineimage" || part.type == "tiledimage") : !layout.non_image;
    if (!flat)
        throw fail("EXR holds deep data or an unknown kind of part (type '" + part.type +
                   "'): only flat scanline and tiled images are read");
    exr_chunks(part, plan.tiled, file); // a valid data window, compression and tile description
    // The display window: at most kMaxExrPixels, holding the data window, at most kMaxExrPadding times it
    // unless small (an auto-cropped file pads with zeros; a hostile one of a few hundred bytes would
    // otherwise make us zero-fill gigabytes).
    const ExrBox& dw = part.data;
    const ExrBox& disp = part.display;
    const int64_t w = disp.width(), h = disp.height();
    if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > kMaxExrPixels)
        throw fail("EXR display window of " + std::to_string(w) + "x" + std::to_string(h) +
                   " is empty or larger than " + std::to_string(kMaxExrPixels) + " pixels");
    if (dw.x0 < disp.x0 || dw.y0 < disp.y0 || dw.x1 > disp.x1 || dw.y1 > disp.y1)
        throw fail("EXR data window extends beyond the display window");
    const uint64_t data = uint64_t(dw.width()) * uint64_t(dw.height());
    if (uint64_t(w) * uint64_t(h) > kMaxExrPaddedPixels && uint64_t(w) * uint64_t(h) > data * kMaxExrPadding)
        throw fail("EXR display window of " + std::to_string(w) + "x" + std::to_string(h) + " is more than " +
                   std::to_string(kMaxExrPadding) + " times its data window (" + std::to_string(data) +
                   " pixels): refused rather than zero-filled");
    bool r = false, g = false, b = false, y = false;
    double bytes_per_pixel = 0.0;
    for (const ExrChannelInfo& c : part.channels)
    {
        if (c.type < 0 || c.type > 2 || c.x_sampling < 1 || c.y_sampling < 1)
            throw fail("not a readable EXR file: channel '" + c.name + "' has pixel type " +
                       std::to_string(c.type) + " and sampling " + std::to_string(c.x_sampling) + "x" +
                       std::to_string(c.y_sampling));
        const bool read = c.name == "R" || c.name == "G" || c.name == "B" || c.name == "A" || c.name == "Y";
        if (read && (c.x_sampling != 1 || c.y_sampling != 1))
            throw fail("EXR channel '" + c.name + "' is subsampled (" + std::to_string(c.x_sampling) + "x" +
                       std::to_string(c.y_sampling) + "): not supported");
        r |= c.name == "R", g |= c.name == "G", b |= c.name == "B", y |= c.name == "Y";
        bytes_per_pixel += double(c.type == 1 ? 2 : 4) / (double(c.x_sampling) * double(c.y_sampling));
    }
    plan.grey = !r && y;
    if (!plan.grey && !r && !g && !b)
        throw fail("EXR has no R, G, B or Y channel (layered files are not supported)");
    // The chunk offset tables of every part come after the headers.
    uint64_t chunks = 0;
    for (size_t i = 0; i < layout.parts.size(); ++i)
    {
        const ExrPart& p = layout.parts[i];
        static const char* const known[] = {"scanlineimage", "tiledimage", "deepscanline", "deeptile"};
        const bool supported =
            !p.has_type || std::find(std::begin(known), std::end(known), p.type) != std::end(known);
        uint64_t n = 0;
        if (!supported && layout.multipart)
        {
            if (p.chunk_count < 0)
                throw fail("not a readable EXR file: part " + std::to_string(i) + " of type '" + p.type +
                           "' has no chunk count");
            n = uint64_t(p.chunk_count);
        }
        else
            n = exr_chunks(
                p, layout.multipart ? (p.type == "tiledimage" || p.type == "deeptile") : layout.tiled, file);
        chunks = add_sat(chunks, n);
    }
    // What the file must hold: the offset tables, and the data window's pixels coded at no more than the
    // compression's expansion (so OpenEXR's tables and buffers, and ours, are bounded by the file's size).
    const uint64_t after_headers = layout.file_size - layout.header_end;
    if (mul_sat(chunks, 8) > after_headers)
        throw fail("EXR offset tables of " + std::to_string(chunks) + " chunks (" +
                   std::to_string(mul_sat(chunks, 8)) + " bytes) do not fit in the file's " +
                   std::to_string(after_headers) + " bytes after its header: truncated, or a hostile header");
    const double expansion = double(kExrExpansion[part.compression]);
    const double capacity = expansion * double(layout.file_size);
    const double coded = double(data) * bytes_per_pixel;
    const std::string method = kExrCompressionNames[part.compression];
    if (coded > capacity)
        throw fail("EXR data window of " + std::to_string(dw.width()) + "x" + std::to_string(dw.height()) +
                   " pixels (" + std::to_string(uint64_t(coded)) + " bytes) cannot be coded in " +
                   std::to_string(layout.file_size) + " bytes with " + method +
                   ": a corrupt or hostile header");
    // One chunk's buffers: OpenEXR's line or tile buffer (every channel), InputFile's row of tiles and our
    // band (RGBA floats) span the chunk's full size even where it overhangs the data window.
    plan.chunk_rows = plan.tiled ? part.tile_height : kExrChunkLines[part.compression];
    const uint64_t chunk_width =
        plan.tiled ? std::max<uint64_t>(uint64_t(dw.width()), part.tile_width) : uint64_t(dw.width());
    const double chunk_pixels = double(chunk_width) * double(plan.chunk_rows);
    if (chunk_pixels * std::max(bytes_per_pixel, 16.0) > double(kExrChunkOverhangBytes) &&
        chunk_pixels * bytes_per_pixel > capacity)
        throw fail("EXR chunks of " + std::to_string(chunk_width) + "x" + std::to_string(plan.chunk_rows) +
                   " pixels cannot be coded in " + std::to_string(layout.file_size) + " bytes with " +
                   method + ", and overhang the data window of " + std::to_string(dw.width()) + "x" +
                   std::to_string(dw.height()) + ": a corrupt or hostile header");
    return plan;
}

// Rows of a band read_exr decodes at once, once the first chunks have decoded: about 16 MiB of RGBA floats.
constexpr uint64_t kExrBandBytes = uint64_t(16) << 20;

} // namespace

NegativeRadiance clamp_negative_radiance(ImageRgba& image, const std::string& name, float tolerance)
{
    NegativeRadiance r;
    size_t worst = 0, values = 0;
    double sum = 0.0;
    for (size_t i = 0; i < image.pixels.size(); ++i)
        if (i % 4 != 3 && std::isfinite(image.pixels[i]))
        {
            sum += std::max(image.pixels[i], 0.0f);
            ++values;
            r.brightest = std::max(r.brightest, image.pixels[i]);
            if (image.pixels[i] < r.least)
            {
                r.least = image.pixels[i];
                worst = i;
            }
        }
    if (r.least == 0.0f)
        return r;
    r.mean = values ? float(sum / double(values)) : 0.0f;
    if (-r.least > tolerance * r.mean)
        throw std::invalid_argument(
            name + ": pixel (" + std::to_string(worst / 4 % std::max(image.width, 1u)) + ", " +
            std::to_string(worst / 4 / std::max(image.width, 1u)) + ") holds a negative radiance, " +
            std::to_string(r.least) + " (the image's mean value is " + std::to_string(r.mean) + ")");
    for (size_t i = 0; i < image.pixels.size(); ++i)
        if (i % 4 != 3 && image.pixels[i] < 0.0f)
        {
            image.pixels[i] = 0.0f;
            ++r.clamped;
        }
    return r;
}

ImageRgba read_exr(const std::filesystem::path& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw FormatError(path.string() + ": no such file");
    const std::string file = path.string();
    const ExrLayout layout = ExrHeaderScan(path, file).scan();
    const ExrPlan plan = check_exr_layout(layout, file);
    const ExrPart& part = layout.parts[0];
    ImageRgba image;
    try
    {
        Imf::InputFile in(path.c_str());
        const Imath::Box2i dw = in.header().dataWindow();
        const Imath::Box2i disp = in.header().displayWindow();
        // What OpenEXR read is what was checked (else the file changed, or the walk is out of step with it).
        if (ExrBox{dw.min.x, dw.min.y, dw.max.x, dw.max.y} != part.data ||
            ExrBox{disp.min.x, disp.min.y, disp.max.x, disp.max.y} != part.display ||
            int(in.header().compression()) != part.compression ||
            (plan.tiled &&
             (!in.header().hasTileDescription() || in.header().tileDescription().ySize != part.tile_height)))
            throw FormatError(file +
                              ": not a readable EXR file: its header reads differently on a second look");
        // The data window, in bands of whole chunks that start at one chunk and grow to kExrBandBytes: memory
        // follows what decodes. OpenEXR addresses pixel (x, y) at base + x * xs + y * ys; the base of a band
        // starting at row y0 is its first pixel shifted back by (min.x, y0) (computed as an integer: it may
        // lie outside any object).
        const uint64_t width = uint64_t(part.data.width());
        const size_t xs = 4 * sizeof(float), ys = xs * width;
        std::vector<std::vector<float>> bands;
        uint64_t rows = std::min<uint64_t>(plan.chunk_rows, uint64_t(part.data.height()));
        for (int64_t y0 = dw.min.y; y0 <= dw.max.y;)
        {
            const uint64_t n = std::min<uint64_t>(rows, uint64_t(int64_t(dw.max.y) - y0 + 1));
            std::vector<float>& band = bands.emplace_back(size_t(width * n * 4), 0.0f);
            char* base = reinterpret_cast<char*>(reinterpret_cast<uintptr_t>(band.data()) -
                                                 (uintptr_t(int64_t(dw.min.x)) * xs + uintptr_t(y0) * ys));
            Imf::FrameBuffer fb;
            const char* names[4] = {"R", "G", "B", "A"};
            for (int c = 0; c < 4; ++c)
            {
                if (plan.grey && (c == 1 || c == 2))
                    continue;
                const char* name = plan.grey && c == 0 ? "Y" : names[c];
                fb.insert(name,
                          Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, c == 3 ? 1.0 : 0.0));
            }
            in.setFrameBuffer(fb);
            in.readPixels(int(y0), int(y0 + int64_t(n) - 1));
            for (size_t i = 0; i < band.size(); i += 4)
            {
                if (plan.grey) // a FrameBuffer holds one slice per name: copy Y into G and B
                    band[i + 1] = band[i + 2] = band[i];
                for (size_t c = 0; c < 4; ++c)
                    if (!std::isfinite(band[i + c]))
                    {
                        const uint64_t p = i / 4;
                        throw FormatError(
                            file + ": pixel (" + std::to_string(dw.min.x + int64_t(p % width) - disp.min.x) +
                            ", " + std::to_string(y0 + int64_t(p / width) - disp.min.y) + ") is not finite");
                    }
            }
            y0 += int64_t(n);
            if (rows * width * xs < kExrBandBytes)
                rows *= 2;
        }
        // The display window: the bands where the data window lies, zeros (alpha 0 too) around it. The bands
        // are freed as they are copied.
        const uint64_t w = uint64_t(part.display.width()), h = uint64_t(part.display.height());
        image.width = uint32_t(w);
        image.height = uint32_t(h);
        image.pixels.reserve(size_t(w * h * 4));
        const size_t left = size_t(dw.min.x - disp.min.x) * 4, right = size_t(disp.max.x - dw.max.x) * 4;
        image.pixels.insert(image.pixels.end(), size_t(dw.min.y - disp.min.y) * w * 4, 0.0f);
        for (std::vector<float>& band : bands)
        {
            if (left == 0 && right == 0)
                image.pixels.insert(image.pixels.end(), band.begin(), band.end());
            else
                for (size_t at = 0; at < band.size(); at += width * 4)
                {
                    image.pixels.insert(image.pixels.end(), left, 0.0f);
                    image.pixels.insert(image.pixels.end(), band.begin() + long(at),
                                        band.begin() + long(at + width * 4));
                    image.pixels.insert(image.pixels.end(), right, 0.0f);
                }
            std::vector<float>().swap(band);
        }
        image.pixels.insert(image.pixels.end(), size_t(disp.max.y - dw.max.y) * w * 4, 0.0f);
    }
    catch (const FormatError&)
    {
        throw;
    }
    catch (const std::exception& e)
    {
        throw FormatError(file + ": not a readable EXR file: " + e.what());
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

namespace
{
// libjpeg's errors end the decode by a jump back to it (decode_jpeg_rgba); its warnings (corrupt entropy
// data, a premature end) are kept, so that a damaged file is refused rather than decoded into garbage.
struct JpegErrors
{
    jpeg_error_mgr mgr;
    std::jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
    bool warned;
};

[[noreturn]] void jpeg_error_exit(j_common_ptr cinfo)
{
    JpegErrors* e = reinterpret_cast<JpegErrors*>(cinfo->err);
    (*cinfo->err->format_message)(cinfo, e->message);
    std::longjmp(e->jump, 1);
}

void jpeg_emit_message(j_common_ptr cinfo, int level)
{
    JpegErrors* e = reinterpret_cast<JpegErrors*>(cinfo->err);
    // Level -1 is a warning. Stray bytes before a marker (some cameras' files) leave the image intact.
    if (level < 0 && cinfo->err->msg_code != JWRN_EXTRANEOUS_DATA && !e->warned)
    {
        (*cinfo->err->format_message)(cinfo, e->message);
        e->warned = true;
    }
}

// Decodes a JPEG into RGBA (libjpeg-turbo, Debian's libjpeg62-turbo). `pixels` holds width x height x 4
// bytes for the size the header gave. Returns libjpeg's message when it fails or warns, else an empty
// string. No object with a destructor lives in this frame across the jump.
std::string decode_jpeg_rgba(const uint8_t* data, size_t size, uint32_t width, uint32_t height,
                             uint8_t* pixels)
{
    jpeg_decompress_struct cinfo;
    JpegErrors errors;
    cinfo.err = jpeg_std_error(&errors.mgr);
    errors.mgr.error_exit = jpeg_error_exit;
    errors.mgr.emit_message = jpeg_emit_message;
    errors.message[0] = 0;
    errors.warned = false;
    if (setjmp(errors.jump))
    {
        jpeg_destroy_decompress(&cinfo);
        return errors.message[0] ? errors.message : "libjpeg failed";
    }
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
    jpeg_read_header(&cinfo, TRUE);
    cinfo.out_color_space = JCS_EXT_RGBA;
    jpeg_start_decompress(&cinfo);
    if (cinfo.output_width != width || cinfo.output_height != height || cinfo.output_components != 4)
    {
        jpeg_destroy_decompress(&cinfo);
        return "its frame is not the size its header gave";
    }
    while (cinfo.output_scanline < cinfo.output_height)
    {
        JSAMPROW row = pixels + size_t(cinfo.output_scanline) * width * 4;
        jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
    jpeg_destroy_decompress(&cinfo);
    return errors.warned ? errors.message : "";
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
    if (c.mime == "image/jpeg")
    {
        // libjpeg-turbo, not stb_image: a damaged entropy-coded segment made stb_image shift by more than
        // 31 bits (undefined behaviour, found by tests/fuzz/fuzz_image); libjpeg reports it.
        const std::string problem =
            decode_jpeg_rgba(data.data(), data.size(), out.width, out.height, out.pixels.data());
        if (!problem.empty())
            throw FormatError(name + ": corrupt or unsupported jpeg (libjpeg: " + problem + ")");
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
    const std::vector<uint8_t>& data = c.data();
    const int size = int(data.size());
    out.bits = stbi_is_16_bit_from_memory(data.data(), size) ? 16 : 8;
    // Decoded at the file's own channel count: stb's samples (1 or 2 bytes each) and the floats (4).
    const size_t samples = size_t(c.width) * size_t(c.height) * size_t(c.channels);
    check_memory(samples * (size_t(out.bits / 8) + sizeof(float)), path.string() + " (a " +
                                                                       std::to_string(c.width) + "x" +
                                                                       std::to_string(c.height) + " image)");
    int w = 0, h = 0, channels = 0;
    out.pixels.resize(samples);
    if (out.bits == 16)
    {
        stbi_us* wide = stbi_load_16_from_memory(data.data(), size, &w, &h, &channels, c.channels);
        if (!wide)
            throw FormatError(image.name + ": corrupt PNG (" + std::string(stbi_failure_reason()) + ")");
        std::unique_ptr<stbi_us, void (*)(void*)> owner(wide, stbi_image_free);
        for (size_t i = 0; i < samples; ++i)
            out.pixels[i] = float(wide[i]) / 65535.0f;
        return out;
    }
    unsigned char* narrow = stbi_load_from_memory(data.data(), size, &w, &h, &channels, c.channels);
    if (!narrow)
        throw FormatError(image.name + ": corrupt PNG (" + std::string(stbi_failure_reason()) + ")");
    std::unique_ptr<unsigned char, void (*)(void*)> owner(narrow, stbi_image_free);
    for (size_t i = 0; i < samples; ++i)
        out.pixels[i] = float(narrow[i]) / 255.0f;
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
