// Writes the fuzz targets' seed corpora and the regression inputs of the reliability issue, made in code:
//   <out>/<target>/corpus/       small valid inputs of each reader
//   <out>/<target>/regressions/  the hostile inputs that once got through (each must stay a clean refusal)
// Usage: fuzz_seeds OUT_DIR
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>

#include "../hostile_inputs.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
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

void exr(const fs::path& p, int display, int data)
{
    fs::create_directories(p.parent_path());
    Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(display - 1, display - 1)),
                       Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(data - 1, data - 1)));
    header.channels().insert("R", Imf::Channel(Imf::HALF));
    header.channels().insert("G", Imf::Channel(Imf::FLOAT));
    std::vector<uint16_t> r(size_t(data) * data, 0x3c00); // half 1.0
    std::vector<float> g(size_t(data) * data, 0.5f);
    Imf::OutputFile file(p.c_str(), header);
    Imf::FrameBuffer fb;
    fb.insert("R", Imf::Slice(Imf::HALF, reinterpret_cast<char*>(r.data()), 2, 2 * size_t(data)));
    fb.insert("G", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(g.data()), 4, 4 * size_t(data)));
    file.setFrameBuffer(fb);
    file.writePixels(data);
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

    // exr
    exr(out / "exr/corpus/small.exr", 4, 4);
    exr(out / "exr/corpus/cropped.exr", 16, 2);
    exr(out / "exr/regressions/huge_display_window.exr", 16384, 1);

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
        // A lightmap asset of the same scene: a 2 x 2 atlas, one output of each kind's size.
        io::LightmapAsset l;
        l.mesh = s.mesh;
        l.mesh.uvs1 = l.mesh.uvs;
        l.materials = s.materials;
        l.images = s.images;
        l.primitives = s.primitives;
        l.width = l.height = 2;
        l.outputs.push_back({"plain", 1, std::vector<float>(2 * 2 * 3, 0.5f)});
        l.outputs.push_back({"h4", 4, std::vector<float>(4 * 2 * 2 * 3, 0.25f)});
        io::write_lightmap_asset(scratch / "tiny_lightmap.hemi", l);
        put(out / "asset/corpus/tiny_lightmap.hemi", slurp(scratch / "tiny_lightmap.hemi"));
    }
    fs::remove_all(scratch);
    std::printf("fuzz_seeds: wrote %s\n", out.string().c_str());
    return 0;
}
