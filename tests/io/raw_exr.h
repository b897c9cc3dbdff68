#pragma once
// OpenEXR files made byte by byte (the layout of openexr.com's "OpenEXR File Layout"), for tests and fuzz
// seeds that need headers OpenEXR's writer would never produce: attributes of any type and size, any version
// flags, chunk tables of any length. A single-part scanline file of one HALF channel "R" without compression
// is what standard() makes; tests change one thing of it.
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hemi::test
{

struct RawExrChannel
{
    std::string name;
    int32_t type = 1; // 0 UINT, 1 HALF, 2 FLOAT
    int32_t x_sampling = 1, y_sampling = 1;
};

class RawExr
{
  public:
    std::vector<uint8_t> bytes;

    explicit RawExr(uint32_t version = 2)
    {
        u32(20000630u); // the magic number 76 2f 31 01
        u32(version);
    }

    RawExr& u8(uint8_t v)
    {
        bytes.push_back(v);
        return *this;
    }
    RawExr& u32(uint32_t v)
    {
        for (int i = 0; i < 4; ++i)
            bytes.push_back(uint8_t(v >> (8 * i)));
        return *this;
    }
    RawExr& u64(uint64_t v)
    {
        for (int i = 0; i < 8; ++i)
            bytes.push_back(uint8_t(v >> (8 * i)));
        return *this;
    }
    RawExr& name(const std::string& s)
    {
        bytes.insert(bytes.end(), s.begin(), s.end());
        bytes.push_back(0);
        return *this;
    }
    // One attribute; `size` is the size field (the value's size unless given).
    RawExr& attribute(const std::string& n, const std::string& type, const std::vector<uint8_t>& value,
                      std::optional<int32_t> size = std::nullopt)
    {
        name(n).name(type).u32(uint32_t(size ? *size : int32_t(value.size())));
        bytes.insert(bytes.end(), value.begin(), value.end());
        return *this;
    }
    RawExr& end_header() { return u8(0); }

    static std::vector<uint8_t> ints(std::initializer_list<int32_t> values)
    {
        std::vector<uint8_t> out;
        for (int32_t v : values)
            for (int i = 0; i < 4; ++i)
                out.push_back(uint8_t(uint32_t(v) >> (8 * i)));
        return out;
    }
    static std::vector<uint8_t> box(int32_t x0, int32_t y0, int32_t x1, int32_t y1)
    {
        return ints({x0, y0, x1, y1});
    }
    static std::vector<uint8_t> chlist(const std::vector<RawExrChannel>& channels)
    {
        std::vector<uint8_t> out;
        for (const RawExrChannel& c : channels)
        {
            out.insert(out.end(), c.name.begin(), c.name.end());
            out.push_back(0);
            const std::vector<uint8_t> fields = ints({c.type, 0, c.x_sampling, c.y_sampling});
            out.insert(out.end(), fields.begin(), fields.end());
        }
        out.push_back(0);
        return out;
    }
    static std::vector<uint8_t> text(const std::string& s)
    {
        return std::vector<uint8_t>(s.begin(), s.end());
    }

    // The attributes every image has, with a data window (0, 0) - (width - 1, height - 1) (display window
    // the same unless given) and `compression` (0 none).
    RawExr& image_attributes(int32_t width, int32_t height, uint8_t compression = 0,
                             const std::vector<RawExrChannel>& channels = {{"R"}})
    {
        attribute("channels", "chlist", chlist(channels));
        attribute("compression", "compression", {compression});
        attribute("dataWindow", "box2i", box(0, 0, width - 1, height - 1));
        attribute("displayWindow", "box2i", box(0, 0, width - 1, height - 1));
        attribute("lineOrder", "lineOrder", {0});
        const float one = 1.0f;
        std::vector<uint8_t> aspect(4);
        std::memcpy(aspect.data(), &one, 4);
        attribute("pixelAspectRatio", "float", aspect);
        attribute("screenWindowCenter", "v2f", std::vector<uint8_t>(8, 0));
        attribute("screenWindowWidth", "float", aspect);
        return *this;
    }

    // The offset table and the scanlines of an uncompressed width x height image of one HALF channel, every
    // sample `half_bits` (0x3c00: 1.0). The table's offsets count from the file's start, as here.
    RawExr& half_scanlines(int32_t width, int32_t height, uint16_t half_bits = 0x3c00)
    {
        const size_t table = bytes.size();
        bytes.resize(table + 8 * size_t(height));
        for (int32_t y = 0; y < height; ++y)
        {
            const uint64_t at = bytes.size();
            std::memcpy(&bytes[table + 8 * size_t(y)], &at, 8);
            u32(uint32_t(y)).u32(uint32_t(2 * width));
            for (int32_t x = 0; x < width; ++x)
                u8(uint8_t(half_bits)).u8(uint8_t(half_bits >> 8));
        }
        return *this;
    }

    // A complete, valid file: width x height, channel R = 1.0, no compression.
    static RawExr standard(int32_t width = 4, int32_t height = 3)
    {
        RawExr e;
        e.image_attributes(width, height).end_header().half_scanlines(width, height);
        return e;
    }
};

} // namespace hemi::test
