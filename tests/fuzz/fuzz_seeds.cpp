// Writes the fuzz targets' seed corpora and the regression inputs of the reliability issue, made in code:
//   <out>/<target>/corpus/       small valid inputs of each reader
//   <out>/<target>/regressions/  the hostile inputs that once got through (each must stay a clean refusal)
// Usage: fuzz_seeds OUT_DIR
#include <hemi/io/asset.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>

#include "../hostile_inputs.h"
#include "../io/raw_exr.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace hemi;

namespace
{

std::vector<uint8_t> slurp(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void put(const fs::path& p, const std::vector<uint8_t>& bytes, int prefix = -1)
{
    fs::create_directories(p.parent_path());
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    if (prefix >= 0)
        f.put(char(prefix));
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

void put_text(const fs::path& p, const std::string& text, int prefix)
{
    put(p, std::vector<uint8_t>(text.begin(), text.end()), prefix);
}

io::ImageRgba8 pattern(uint32_t w, uint32_t h)
{
    io::ImageRgba8 img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (size_t i = 0; i < img.pixels.size(); ++i)
        img.pixels[i] = uint8_t(i * 37 + (i >> 4));
    return img;
}

uint32_t crc32(const uint8_t* p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; ++i)
    {
        c ^= p[i];
        for (int k = 0; k < 8; ++k)
            c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return ~c;
}

// A valid PNG with a zero-length IDAT chunk (correct CRC) inserted before its first IDAT.
std::vector<uint8_t> png_with_empty_idat(std::vector<uint8_t> png)
{
    size_t at = 8;
    while (at + 8 <= png.size() && std::memcmp(&png[at + 4], "IDAT", 4) != 0)
        at +=
            12 + (size_t(png[at]) << 24 | size_t(png[at + 1]) << 16 | size_t(png[at + 2]) << 8 | png[at + 3]);
    uint8_t chunk[12] = {0, 0, 0, 0, 'I', 'D', 'A', 'T'};
    const uint32_t crc = crc32(chunk + 4, 4);
    chunk[8] = uint8_t(crc >> 24), chunk[9] = uint8_t(crc >> 16), chunk[10] = uint8_t(crc >> 8),
    chunk[11] = uint8_t(crc);
    png.insert(png.begin() + long(at), chunk, chunk + 12);
    return png;
}

io::GltfScene tiny_scene()
{
    io::GltfScene s;
    s.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    s.mesh.normals.assign(3, glm::vec3(0, 0, 1));
    s.mesh.tangents.assign(3, glm::vec4(1, 0, 0, 1));
    s.mesh.uvs = {{0, 0}, {1, 0}, {0, 1}};
    s.mesh.indices = {0, 1, 2};
    s.images.push_back({"tex.png", "image/png", io::encode_png(pattern(4, 4))});
    io::Material m;
    m.name = "m";
    m.base_color.image = 0;
    s.materials = {m};
    s.primitives = {{0, 3, 0}};
    return s;
}

void exr(const fs::path& p, int display, int data_w, int data_h = -1)
{
    data_h = data_h < 0 ? data_w : data_h;
    fs::create_directories(p.parent_path());
    Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(display - 1, display - 1)),
                       Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(data_w - 1, data_h - 1)));
    header.channels().insert("R", Imf::Channel(Imf::HALF));
    header.channels().insert("G", Imf::Channel(Imf::FLOAT));
    std::vector<uint16_t> r(size_t(data_w) * data_h, 0x3c00); // half 1.0
    std::vector<float> g(size_t(data_w) * data_h, 0.5f);
    Imf::OutputFile file(p.c_str(), header);
    Imf::FrameBuffer fb;
    fb.insert("R", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(r.data()), 2, 2 * size_t(data_w)));
    fb.insert("G", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(g.data()), 4, 4 * size_t(data_w)));
    file.setFrameBuffer(fb);
    file.writePixels(data_h);
}

// A 12 x 10 tiled EXR (4 x 4 tiles, mipmapped, PIZ) of a gradient in R, G, B.
void tiled_exr(const fs::path& p)
{
    fs::create_directories(p.parent_path());
    Imf::Header header(12, 10);
    header.compression() = Imf::PIZ_COMPRESSION;
    for (const char* c : {"R", "G", "B"})
        header.channels().insert(c, Imf::Channel(Imf::HALF));
    header.setTileDescription(Imf::TileDescription(4, 4, Imf::MIPMAP_LEVELS));
    std::vector<uint16_t> v(12 * 10 * 3);
    for (size_t i = 0; i < v.size(); ++i)
        v[i] = uint16_t(0x3000 + i * 7); // half values between 0.125 and 1
    Imf::TiledOutputFile file(p.c_str(), header);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c)
        fb.insert(c == 0   ? "R"
                  : c == 1 ? "G"
                           : "B",
                  Imf::Slice(Imf::HALF, reinterpret_cast<char*>(v.data() + c), 6, 6 * 12));
    file.setFrameBuffer(fb);
    for (int level = 0; level < file.numLevels(); ++level)
        file.writeTiles(0, file.numXTiles(level) - 1, 0, file.numYTiles(level) - 1, level);
}

// The hand-made EXR (tests/io/raw_exr.h) with `extra` attributes after the image's, on `rows` scanlines of
// `width` pixels of data (whatever the attributes claim), with the version field `version`.
std::vector<uint8_t> raw_exr(const std::function<void(test::RawExr&)>& extra, int width = 4, int rows = 3,
                             uint32_t version = 2)
{
    test::RawExr e(version);
    e.image_attributes(4, 3);
    extra(e);
    e.end_header().half_scanlines(width, rows);
    return e.bytes;
}

math::ParabolicImage parabolic(uint32_t size, float value)
{
    math::ParabolicImage m;
    m.size = size;
    m.extent = size > 2 ? double(size) / double(size - 2) : 1.0;
    m.rgb.assign(size_t(2) * size * size * 3, value);
    for (size_t i = 0; i < m.rgb.size(); ++i)
        m.rgb[i] += 0.01f * float(i % 17);
    return m;
}

// A small environment asset: a mirror chain from `size`, `glossy` glossy maps, `tables` Fresnel tables of 5
// samples.
io::EnvmapAsset envmap(uint32_t size, int glossy, int tables)
{
    io::EnvmapAsset a;
    a.source_width = 16;
    a.source_height = 8;
    for (uint32_t s = size; s >= 1; s /= 2)
        a.mirror.push_back(parabolic(s, 1.0f / float(s)));
    for (int i = 0; i < glossy; ++i)
    {
        a.exponents.push_back(float(10 * (i + 1)));
        a.glossy.push_back(parabolic(size, 0.5f));
    }
    a.diffuse = parabolic(2, 0.25f);
    a.fresnel_samples = 5;
    for (int i = 0; i < tables; ++i)
    {
        a.iors.push_back(1.5f + float(i));
        for (int k = 0; k < 5; ++k)
            a.fresnel.push_back(1.0f - 0.2f * float(k));
    }
    return a;
}

// The sections of the asset at `valid`, changed by `change`, in a new container (checksum sealed).
std::vector<uint8_t>
changed_asset(const fs::path& valid, const fs::path& scratch,
              const std::function<void(std::map<std::string, std::vector<std::byte>>&)>& change)
{
    std::map<std::string, std::vector<std::byte>> sections;
    {
        const io::AssetReader r(valid);
        for (const std::string& name : r.names())
        {
            const std::span<const std::byte> b = r.section(name);
            sections[name].assign(b.begin(), b.end());
        }
    }
    change(sections);
    io::AssetWriter w;
    for (const auto& [name, bytes] : sections)
        w.add(name, bytes);
    w.write(scratch);
    return slurp(scratch);
}

template <typename T> void set(std::vector<std::byte>& section, size_t at, T v)
{
    std::memcpy(section.data() + at, &v, sizeof v);
}

} // namespace

int main(int argc, char** argv)
{
    if (argc != 2)
    {
        std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR\n");
        return 2;
    }
    const fs::path out = argv[1];
    const fs::path scratch = out / "scratch";
    fs::create_directories(scratch);

    // image: the first byte picks PNG (0) or JPEG (1).
    const std::vector<uint8_t> png = io::encode_png(pattern(8, 8));
    put(out / "image/corpus/png", png, 0);
    put(out / "image/corpus/jpeg", io::encode_jpeg(pattern(16, 8), 80), 1);
    put(out / "image/regressions/png_zero_length_idat", png_with_empty_idat(png), 0);
    put(out / "image/regressions/jpeg_huge_frame_in_few_bytes",
        test::jpeg_with_frame_size(io::encode_jpeg(pattern(16, 8), 80), 16392, 9488), 1);
    put(out / "image/regressions/jpeg_oversubscribed_huffman_table",
        test::jpeg_with_oversubscribed_huffman_table(io::encode_jpeg(pattern(16, 8), 80)), 1);
    put(out / "image/regressions/jpeg_oversized_huffman_table",
        test::jpeg_with_oversized_huffman_table(io::encode_jpeg(pattern(16, 8), 80)), 1);
    put(out / "image/regressions/jpeg_undefined_huffman_table",
        test::jpeg_with_undefined_huffman_table(io::encode_jpeg(pattern(16, 8), 80)), 1);
    put(out / "image/regressions/jpeg_undefined_ac_table_in_a_baseline_scan",
        test::jpeg_with_undefined_ac_table_in_a_baseline_scan(io::encode_jpeg(pattern(16, 8), 80)), 1);
    put(out / "image/regressions/jpeg_damaged_entropy_data",
        test::jpeg_with_damaged_entropy_data(io::encode_jpeg(pattern(16, 8), 80)), 1);

    // exr
    exr(out / "exr/corpus/small.exr", 4, 4);
    exr(out / "exr/corpus/cropped.exr", 16, 2);
    exr(out / "exr/regressions/huge_display_window.exr", 16384, 1);
    put(out / "exr/corpus/hand_made.exr", test::RawExr::standard(5, 3).bytes);
    tiled_exr(out / "exr/corpus/tiled.exr");
    // Each refused by one rule of read_exr alone (tests/io/image_test.cpp, ExrReader): a display window 64.2
    // times its data window under the 2^27-pixel cap; header claims the file cannot hold (OpenEXR 3.1 would
    // allocate them: a 1 GiB string attribute, a preview of a million pixels, an 8 MiB offset table, the
    // buffers of a 2^20-pixel row or of a 4096 x 4096 tile around one pixel).
    exr(out / "exr/regressions/display_window_64.2_times_data.exr", 2048, 255, 256);
    put(out / "exr/regressions/string_attribute_of_1_gib.exr",
        raw_exr([](test::RawExr& e)
                { e.attribute("comment", "string", test::RawExr::text("hi"), 1 << 30); }));
    put(out / "exr/regressions/preview_of_a_million_pixels_in_8_bytes.exr",
        raw_exr(
            [](test::RawExr& e) {
                e.attribute("preview", "preview", test::RawExr::ints({1000, 1000}));
            }));
    put(out / "exr/regressions/offset_table_of_8_mib.exr",
        raw_exr(
            [](test::RawExr& e)
            {
                e.attribute("dataWindow", "box2i", test::RawExr::box(0, 0, 0, (1 << 20) - 1));
                e.attribute("displayWindow", "box2i", test::RawExr::box(0, 0, 0, (1 << 20) - 1));
            },
            1, 1));
    put(out / "exr/regressions/row_of_2_20_pixels_in_2_kib.exr",
        raw_exr(
            [](test::RawExr& e)
            {
                e.attribute("dataWindow", "box2i", test::RawExr::box(0, 0, (1 << 20) - 1, 0));
                e.attribute("displayWindow", "box2i", test::RawExr::box(0, 0, (1 << 20) - 1, 0));
            },
            1000, 1));
    {
        std::vector<uint8_t> tiles = test::RawExr::ints({4096, 4096});
        tiles.push_back(0);
        put(out / "exr/regressions/tile_of_16_megapixels_around_one_pixel.exr",
            raw_exr(
                [&](test::RawExr& e)
                {
                    e.attribute("dataWindow", "box2i", test::RawExr::box(0, 0, 0, 0));
                    e.attribute("displayWindow", "box2i", test::RawExr::box(0, 0, 0, 0));
                    e.attribute("tiles", "tiledesc", tiles);
                },
                1, 1, 2 | 0x200));
    }

    // gltf: the first byte picks .glb (1) or .gltf (0).
    io::write_gltf(scratch / "tiny.glb", tiny_scene(), io::ImageStorage::BufferView);
    put(out / "gltf/corpus/tiny.glb", slurp(scratch / "tiny.glb"), 1);
    io::write_gltf(scratch / "tiny.gltf", tiny_scene(), io::ImageStorage::DataUri);
    put(out / "gltf/corpus/tiny.gltf", slurp(scratch / "tiny.gltf"), 0);
    {
        // Every node lists the next one twice: 2^N visits for a reader that walks it as a tree.
        std::string nodes;
        const int n = 24;
        for (int i = 0; i < n; ++i)
            nodes += std::string(i ? "," : "") + (i + 1 < n ? "{\"children\":[" + std::to_string(i + 1) +
                                                                  "," + std::to_string(i + 1) + "]}"
                                                            : "{\"mesh\":0}");
        const std::string b64 = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"; // 3 vec3 positions
        put_text(
            out / "gltf/regressions/node_graph_not_a_tree.gltf",
            "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[" + nodes +
                "],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
                "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
                "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64," +
                b64 + "\"}]}",
            0);
        put_text(out / "gltf/regressions/accessor_count_2_62.gltf",
                 "{\"asset\":{\"version\":\"2.0\"},\"meshes\":[{\"primitives\":[{\"attributes\":{"
                 "\"POSITION\":0}}]}],"
                 "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4611686018427387904,"
                 "\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                 "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64," +
                     b64 + "\"}]}",
                 0);
    }

    // asset: a one-triangle PRT asset with a material and an image.
    io::PrtAsset a;
    const io::GltfScene s = tiny_scene();
    a.mesh = s.mesh;
    a.order = 3;
    a.transfer_kind = 0;
    a.materials = s.materials;
    a.images = s.images;
    a.primitives = s.primitives;
    io::PrtTechnique t;
    t.name = "gs";
    t.k = 9;
    t.matrices.assign(3 * 9 * 9, 0.25f);
    a.techniques.push_back(t);
    io::write_prt_asset(scratch / "tiny.hemi", a);
    const std::vector<uint8_t> asset = slurp(scratch / "tiny.hemi");
    put(out / "asset/corpus/tiny.hemi", asset);
    {
        // The second section renamed to the first's name, checksum re-sealed: a duplicate section.
        std::vector<uint8_t> dup = asset;
        std::memcpy(&dup[16 + 48], &dup[16], 32);
        const uint64_t sum = XXH64(dup.data(), dup.size() - 8, 0);
        std::memcpy(dup.data() + dup.size() - 8, &sum, 8);
        put(out / "asset/regressions/duplicate_section.hemi", dup);
    }
    {
        // A lightmap asset of the same scene: a 20 x 12 atlas (6 blocks of 8 x 8, partial ones included), one
        // output of each kind's size: `plain` in two of the blocks, `h4` in all of them.
        io::LightmapAsset l;
        l.mesh = s.mesh;
        l.mesh.uvs1 = l.mesh.uvs;
        l.materials = s.materials;
        l.images = s.images;
        l.primitives = s.primitives;
        l.width = 20;
        l.height = 12;
        std::vector<float> plain(20 * 12 * 3, 0.0f);
        plain[(1 * 20 + 2) * 3] = 0.5f;
        plain[(10 * 20 + 17) * 3 + 1] = 0.25f;
        l.outputs.push_back({"plain", 1, io::BlockMaps::from_dense(20, 12, 1, plain)});
        l.outputs.push_back(
            {"h4", 4, io::BlockMaps::from_dense(20, 12, 4, std::vector<float>(4 * 20 * 12 * 3, 0.25f))});
        io::write_lightmap_asset(scratch / "tiny_lightmap.hemi", l);
        put(out / "asset/corpus/tiny_lightmap.hemi", slurp(scratch / "tiny_lightmap.hemi"));
        // The same with a mixed sun, a realtime lamp and their shadowmask (lightmap.lights and
        // lightmap.shadowmask).
        io::LightmapLight sun, lamp;
        sun.light.type = io::PunctualLight::Type::Directional;
        sun.light.name = "sun";
        sun.light.mode = io::LightMode::Mixed;
        sun.channel = 0;
        lamp.light.name = "lamp";
        lamp.light.mode = io::LightMode::Realtime;
        l.lights = {sun, lamp};
        std::vector<float> mask(4 * 20 * 12 * 3, 1.0f);
        mask[(1 * 20 + 2) * 3] = mask[(1 * 20 + 2) * 3 + 1] = mask[(1 * 20 + 2) * 3 + 2] = 0.5f;
        l.shadowmask = io::BlockMaps::from_dense(20, 12, 4, mask);
        io::write_lightmap_asset(scratch / "mixed_lightmap.hemi", l);
        put(out / "asset/corpus/mixed_lightmap.hemi", slurp(scratch / "mixed_lightmap.hemi"));
    }
    {
        // envmap: two small environment assets; hostile ones each refused by one check of the reader.
        io::write_envmap_asset(scratch / "envmap4.hemi", envmap(4, 2, 2));
        const std::vector<uint8_t> envmap4 = slurp(scratch / "envmap4.hemi");
        put(out / "envmap/corpus/envmap4.hemi", envmap4);
        put(out / "asset/corpus/envmap4.hemi", envmap4);
        io::write_envmap_asset(scratch / "envmap2.hemi", envmap(2, 0, 0));
        put(out / "envmap/corpus/envmap2_plain.hemi", slurp(scratch / "envmap2.hemi"));
        const fs::path valid = scratch / "envmap4.hemi", changed = scratch / "changed.hemi";
        using Sections = std::map<std::string, std::vector<std::byte>>;
        // A mirror map of 8192^2 (1.6 GB of floats) claimed, 4^2 there.
        put(out / "envmap/regressions/mirror_8192_claimed.hemi",
            changed_asset(valid, changed,
                          [](Sections& s)
                          {
                              set(s["envmap.info"], 4, uint32_t(8192));
                              set(s["envmap.info"], 8, uint32_t(14));
                          }));
        // 64 glossy maps of 8192^2 claimed in a section of two 4^2 maps.
        put(out / "envmap/regressions/glossy_8192_claimed.hemi",
            changed_asset(valid, changed,
                          [](Sections& s)
                          {
                              set(s["envmap.info"], 12, uint32_t(64));
                              set(s["envmap.glossy"], 4, uint32_t(8192));
                          }));
        put(out / "envmap/regressions/fresnel_65536_samples_claimed.hemi",
            changed_asset(valid, changed, [](Sections& s) { set(s["envmap.info"], 20, uint32_t(65536)); }));
        put(out / "envmap/regressions/nan_in_the_diffuse_map.hemi",
            changed_asset(valid, changed, [](Sections& s) { set(s["envmap.diffuse"], 12, NAN); }));
        put(out / "envmap/regressions/index_of_refraction_1.hemi",
            changed_asset(valid, changed, [](Sections& s) { set(s["envmap.fresnel"], 0, 1.0f); }));
        put(out / "envmap/regressions/a_prt_asset.hemi", asset);
    }

    // data_image: PNG and EXR files, as height and normal maps are read.
    put(out / "data_image/corpus/png", png);
    put(out / "data_image/corpus/exr", slurp(out / "exr/corpus/small.exr"));
    put(out / "data_image/corpus/tiled_exr", slurp(out / "exr/corpus/tiled.exr"));
    put(out / "data_image/regressions/jpeg", io::encode_jpeg(pattern(16, 8), 80));
    put(out / "data_image/regressions/exr_string_attribute_of_1_gib",
        slurp(out / "exr/regressions/string_attribute_of_1_gib.exr"));
    fs::remove_all(scratch);
    std::printf("fuzz_seeds: wrote %s\n", out.string().c_str());
    return 0;
}
