// glTF reading: models made in code (tinygltf's writer, hand-written JSON, and hemi's own scene writer making
// Blender-like files), node transforms, generated tangents against the UV layout, materials and images as
// exporters store them, every unsupported feature named, and malformed input with the file named in the
// error.
#include "../temp_dir.h"

#include <hemi/io/gltf.h>
#include <hemi/io/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using nlohmann::json;

namespace
{
fs::path dir()
{
    return hemi::test::temp_dir("gltf_test");
}

template <typename T> void append(std::vector<unsigned char>& buf, const std::vector<T>& v)
{
    size_t at = buf.size();
    buf.resize(at + v.size() * sizeof(T));
    std::memcpy(buf.data() + at, v.data(), v.size() * sizeof(T));
}

std::string slurp(const fs::path& p)
{
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

// A small RGBA8 image with every pixel different (a PNG must come back exactly).
hemi::io::ImageRgba8 pattern(uint32_t w, uint32_t h, uint32_t seed)
{
    hemi::io::ImageRgba8 img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (size_t i = 0; i < img.pixels.size(); ++i)
        img.pixels[i] = uint8_t((i * 37 + seed * 91 + (i / 4) * 11) % 256);
    return img;
}

// A smooth image (what JPEG keeps within a few levels).
hemi::io::ImageRgba8 gradient(uint32_t w, uint32_t h)
{
    hemi::io::ImageRgba8 img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            uint8_t* p = &img.pixels[(size_t(y) * w + x) * 4];
            p[0] = uint8_t(40 + x * 160 / w);
            p[1] = uint8_t(60 + y * 120 / h);
            p[2] = 200;
            p[3] = 255;
        }
    return img;
}

// A unit quad in the xy plane facing +z, UV origin at the top-left (glTF), translated by (0, 0, 2).
tinygltf::Model quad_model(bool with_normal_texture, std::vector<uint16_t> indices = {0, 1, 2, 0, 2, 3})
{
    tinygltf::Model m;
    std::vector<float> pos = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    std::vector<float> uv = {0, 1, 1, 1, 1, 0, 0, 0};
    tinygltf::Buffer buffer;
    append(buffer.data, pos);
    append(buffer.data, uv);
    append(buffer.data, indices);
    m.buffers.push_back(buffer);
    auto view = [&](size_t offset, size_t length)
    {
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = offset;
        v.byteLength = length;
        m.bufferViews.push_back(v);
        return int(m.bufferViews.size() - 1);
    };
    auto accessor = [&](int v, int component, int type, size_t count)
    {
        tinygltf::Accessor a;
        a.bufferView = v;
        a.componentType = component;
        a.type = type;
        a.count = count;
        m.accessors.push_back(a);
        return int(m.accessors.size() - 1);
    };
    int p = accessor(view(0, 48), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 4);
    m.accessors[p].minValues = {0, 0, 0};
    m.accessors[p].maxValues = {1, 1, 0};
    int t = accessor(view(48, 32), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, 4);
    int i = accessor(view(80, indices.size() * 2), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                     TINYGLTF_TYPE_SCALAR, indices.size());
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = p;
    prim.attributes["TEXCOORD_0"] = t;
    prim.indices = i;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    if (with_normal_texture)
    {
        tinygltf::Image img;
        img.uri = "quad_normal.png";
        m.images.push_back(img);
        tinygltf::Texture tex;
        tex.source = 0;
        m.textures.push_back(tex);
        tinygltf::Material mat;
        mat.normalTexture.index = 0;
        m.materials.push_back(mat);
        prim.material = 0;
    }
    tinygltf::Mesh mesh;
    mesh.primitives.push_back(prim);
    m.meshes.push_back(mesh);
    tinygltf::Node node;
    node.mesh = 0;
    node.translation = {0, 0, 2};
    m.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    m.scenes.push_back(scene);
    m.defaultScene = 0;
    m.asset.version = "2.0";
    return m;
}

fs::path write_model(const tinygltf::Model& m, const std::string& name, bool binary = false)
{
    fs::path p = dir() / name;
    tinygltf::TinyGLTF writer;
    EXPECT_TRUE(writer.WriteGltfSceneToFile(&m, p.string(), false, true, true, binary));
    return p;
}

// A hand-written glTF (JSON plus a .bin buffer) to edit the way other exporters write files: a unit quad
// (accessor 0 POSITION, 1 TEXCOORD_0, 2 u16 indices) in one node of one scene, no material.
struct Handmade
{
    json j;
    std::vector<unsigned char> bin;

    int view(const void* data, size_t size)
    {
        while (bin.size() % 4)
            bin.push_back(0);
        const size_t at = bin.size();
        bin.resize(at + size);
        std::memcpy(bin.data() + at, data, size);
        j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", size}});
        return int(j["bufferViews"].size() - 1);
    }
    template <typename T>
    int accessor(const std::vector<T>& values, int component, const char* type, size_t count)
    {
        j["accessors"].push_back({{"bufferView", view(values.data(), values.size() * sizeof(T))},
                                  {"componentType", component},
                                  {"count", count},
                                  {"type", type}});
        return int(j["accessors"].size() - 1);
    }
    json& primitive(size_t p = 0) { return j["meshes"][0]["primitives"][p]; }
    fs::path save(const std::string& name) const
    {
        json out = j;
        out["buffers"] = json::array({{{"uri", name + ".bin"}, {"byteLength", bin.size()}}});
        std::ofstream(dir() / (name + ".bin"), std::ios::binary)
            .write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
        std::ofstream(dir() / (name + ".gltf")) << out.dump(1);
        return dir() / (name + ".gltf");
    }
};

Handmade handmade_quad()
{
    Handmade h;
    h.j = json::parse(R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
                          "nodes": [{"mesh": 0}],
                          "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                                      "indices": 2}]}]})");
    h.accessor(std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, 5126, "VEC3", 4);
    h.j["accessors"][0]["min"] = {0, 0, 0};
    h.j["accessors"][0]["max"] = {1, 1, 0};
    h.accessor(std::vector<float>{0, 1, 1, 1, 1, 0, 0, 0}, 5126, "VEC2", 4);
    h.accessor(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, 5123, "SCALAR", 6);
    return h;
}

// Gives the quad a material with a base colour texture from an external PNG (written beside it).
void add_textured_material(Handmade& h, const std::string& uri = "base.png",
                           const std::string& file = "base.png")
{
    hemi::io::write_png(dir() / file, pattern(2, 2, 1));
    h.j["images"] = json::array({{{"uri", uri}}});
    h.j["textures"] = json::array({{{"source", 0}}});
    h.j["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
    h.primitive()["material"] = 0;
}

std::string error_of(const fs::path& p)
{
    try
    {
        hemi::io::read_gltf(p);
    }
    catch (const hemi::io::FormatError& e)
    {
        return e.what();
    }
    catch (const std::exception& e)
    {
        return std::string("not a FormatError: ") + e.what();
    }
    return "accepted";
}

void expect_error_naming(const fs::path& p, const std::string& part)
{
    const std::string what = error_of(p);
    EXPECT_NE(what.find(p.filename().string()), std::string::npos) << what;
    EXPECT_NE(what.find(part), std::string::npos) << what;
}

// The warning that names `feature`, or an empty string.
std::string warning_naming(const hemi::io::GltfScene& s, const std::string& feature)
{
    for (const std::string& w : s.warnings)
        if (w.find(feature) != std::string::npos)
            return w;
    return {};
}

std::string all_warnings(const hemi::io::GltfScene& s)
{
    std::string out;
    for (const std::string& w : s.warnings)
        out += "\n  " + w;
    return out.empty() ? " (none)" : out;
}

} // namespace

TEST(GltfReader, ReadsTransformedGeometryAndGeneratesTangentsFromUvs)
{
    hemi::io::write_png(dir() / "quad_normal.png", pattern(4, 4, 0));
    for (bool binary : {false, true})
    {
        fs::path p = write_model(quad_model(true), binary ? "quad.glb" : "quad.gltf", binary);
        hemi::io::GltfScene s = hemi::io::read_gltf(p);
        ASSERT_EQ(s.mesh.vertex_count(), 4u);
        ASSERT_EQ(s.mesh.indices.size(), 6u);
        EXPECT_FLOAT_EQ(s.mesh.positions[2].z, 2.0f); // node translation applied
        EXPECT_TRUE(s.tangents_generated);
        for (size_t v = 0; v < 4; ++v)
        {
            EXPECT_NEAR(glm::length(s.mesh.normals[v] - glm::vec3(0, 0, 1)), 0.0f, 1e-6f) << "normal " << v;
            // u grows along +x, so T = +x; v grows along -y, so the bitangent (toward -v) is +y: w = +1.
            EXPECT_NEAR(glm::length(glm::vec3(s.mesh.tangents[v]) - glm::vec3(1, 0, 0)), 0.0f, 1e-6f)
                << "tangent " << v;
            EXPECT_EQ(s.mesh.tangents[v].w, 1.0f);
        }
        EXPECT_TRUE(s.mesh.uvs1.empty());
        ASSERT_EQ(s.primitives.size(), 1u);
        EXPECT_EQ(s.primitives[0], (hemi::io::Primitive{0, 6, 0}));
        ASSERT_EQ(s.materials.size(), 1u);
        EXPECT_FALSE(s.materials[0].base_color.present());
        ASSERT_TRUE(s.materials[0].normal.present());
        ASSERT_EQ(s.images.size(), 1u);
        EXPECT_EQ(s.images[0].name, "quad_normal.png");
        EXPECT_EQ(s.images[0].mime_type, "image/png");
        EXPECT_EQ(hemi::io::decode_image(s.images[0]).pixels, pattern(4, 4, 0).pixels);
        EXPECT_TRUE(s.warnings.empty()) << all_warnings(s);
    }
}

TEST(GltfReader, MirroredUvsFlipTheHandedness)
{
    tinygltf::Model m = quad_model(false);
    // Mirror u: u = 1 - x. The tangent then points to -x and the frame is left-handed.
    std::vector<float> uv = {1, 1, 0, 1, 0, 0, 1, 0};
    std::memcpy(m.buffers[0].data.data() + 48, uv.data(), 32);
    hemi::io::GltfScene s = hemi::io::read_gltf(write_model(m, "mirrored.gltf"));
    EXPECT_NEAR(glm::length(glm::vec3(s.mesh.tangents[0]) - glm::vec3(-1, 0, 0)), 0.0f, 1e-6f);
    EXPECT_EQ(s.mesh.tangents[0].w, -1.0f);
}

// Generated tangents weight each triangle by its corner angle (MikkTSpace), not by its area or UV scale: a
// vertex shared by a 90-degree corner whose UVs run along +x and a ten times larger 45-degree corner whose
// UVs (three times denser) run along +y gets the tangent normalize(2x + y); summing raw dP/du (x + y/3),
// area weighting or angle times raw dP/du (2x + y/3) would give other mixes.
TEST(GltfReader, GeneratedTangentsWeightTrianglesByCornerAngle)
{
    hemi::io::Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-10, 0, 0}, {-10, -10, 0}};
    m.normals.assign(5, glm::vec3(0, 0, 1));
    // Triangle A (0, 1, 2): u = x, v = -y. Triangle B (0, 3, 4): u = y, v = x (the same frame turned 90 deg).
    // Vertex 0 has one UV for both; the others belong to one triangle each.
    m.uvs = {
        {0, 0}, {1, 0}, {0, -1}, {0, -30}, {-30, -30}}; // B's UVs 3x denser: raw dP/du would weigh it 1/3
    m.indices = {0, 1, 2, 0, 3, 4};
    const fs::path p = dir() / "corner.gltf";
    hemi::io::write_gltf(p, m);
    const hemi::io::GltfScene s = hemi::io::read_gltf(p);
    ASSERT_TRUE(s.tangents_generated);
    const glm::vec3 want = glm::normalize(glm::vec3(2, 1, 0));
    EXPECT_NEAR(glm::length(glm::vec3(s.mesh.tangents[0]) - want), 0.0f, 1e-5f)
        << s.mesh.tangents[0].x << " " << s.mesh.tangents[0].y << " " << s.mesh.tangents[0].z;
    EXPECT_EQ(s.mesh.tangents[0].w, 1.0f);
    EXPECT_NEAR(glm::length(glm::vec3(s.mesh.tangents[1]) - glm::vec3(1, 0, 0)), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::length(glm::vec3(s.mesh.tangents[3]) - glm::vec3(0, 1, 0)), 0.0f, 1e-5f);
}

// A node that mirrors its mesh (scale -1 on x) keeps the triangles counter-clockwise seen from the side the
// normals face (glTF flips the winding of mirrored nodes): the quad still faces +z, generated normals
// included, and the tangent frame turns left-handed.
TEST(GltfReader, MirroringNodeKeepsTrianglesFacingOut)
{
    tinygltf::Model m = quad_model(false);
    m.nodes[0].scale = {-1.0, 1.0, 1.0};
    const hemi::io::GltfScene s = hemi::io::read_gltf(write_model(m, "mirrored_node.gltf"));
    for (size_t t = 0; t < s.mesh.indices.size(); t += 3)
    {
        const glm::vec3 a = s.mesh.positions[s.mesh.indices[t]], b = s.mesh.positions[s.mesh.indices[t + 1]],
                        c = s.mesh.positions[s.mesh.indices[t + 2]];
        EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f)
            << "triangle " << t / 3 << " winds clockwise seen from +z";
    }
    for (const glm::vec3& n : s.mesh.normals)
        EXPECT_NEAR(glm::length(n - glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
}

// Each primitive keeps its own material: a second primitive with another material is its own range, and a
// primitive without one gets the default material, appended once after the file's.
TEST(GltfReader, EachPrimitiveKeepsItsMaterial)
{
    hemi::io::write_png(dir() / "quad_normal.png", pattern(4, 4, 0));
    tinygltf::Model m = quad_model(true);
    tinygltf::Material red;
    red.name = "red";
    red.pbrMetallicRoughness.baseColorFactor = {1.0, 0.0, 0.0, 1.0};
    m.materials.push_back(red);
    tinygltf::Primitive second = m.meshes[0].primitives[0];
    second.material = 1;
    m.meshes[0].primitives.push_back(second);
    tinygltf::Primitive none = second;
    none.material = -1;
    m.meshes[0].primitives.push_back(none);
    m.meshes[0].primitives.push_back(none);
    const hemi::io::GltfScene s = hemi::io::read_gltf(write_model(m, "two_materials.gltf"));
    EXPECT_EQ(s.mesh.vertex_count(), 16u);
    ASSERT_EQ(s.primitives.size(), 4u);
    EXPECT_EQ(s.primitives[0], (hemi::io::Primitive{0, 6, 0}));
    EXPECT_EQ(s.primitives[1], (hemi::io::Primitive{6, 6, 1}));
    EXPECT_EQ(s.primitives[2], (hemi::io::Primitive{12, 6, 2}));
    EXPECT_EQ(s.primitives[3], (hemi::io::Primitive{18, 6, 2}));
    ASSERT_EQ(s.materials.size(), 3u);
    EXPECT_TRUE(s.materials[0].normal.present());
    EXPECT_EQ(s.materials[1].name, "red");
    EXPECT_EQ(s.materials[1].base_color_factor, glm::vec4(1, 0, 0, 1));
    EXPECT_FALSE(s.materials[1].normal.present());
    EXPECT_EQ(s.materials[2], (hemi::io::Material{"default"}));
    EXPECT_EQ(s.images.size(), 1u);
}

namespace
{
// A Blender-like scene: four primitives, each with its own vertices, three materials (one used twice), three
// images as exporters store them: a PNG beside the file (with a space in its name), a JPEG inside the buffer
// and a PNG as a data URI. A doubleSided open quad with TEXCOORD_1 and a KHR_texture_transform on its
// texture.
hemi::io::GltfScene blender_like_scene()
{
    using namespace hemi::io;
    GltfScene s;
    Mesh& m = s.mesh;
    auto quad = [&](glm::vec3 corner, glm::vec3 u, glm::vec3 v, uint32_t material, bool second_uvs)
    {
        const uint32_t first = uint32_t(m.positions.size());
        const glm::vec3 n = glm::normalize(glm::cross(u, v));
        const glm::vec2 uv[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
        const glm::vec3 p[4] = {corner, corner + u, corner + u + v, corner + v};
        for (int k = 0; k < 4; ++k)
        {
            m.positions.push_back(p[k]);
            m.normals.push_back(n);
            m.tangents.push_back(glm::vec4(glm::normalize(u), 1.0f));
            m.uvs.push_back(uv[k]);
            m.uvs1.push_back(second_uvs ? glm::vec2(0.125f * float(k + 1), 0.5f + 0.25f * float(k % 2))
                                        : glm::vec2(0.0f));
        }
        s.primitives.push_back({uint32_t(m.indices.size()), 6, material});
        m.indices.insert(m.indices.end(), {first, first + 1, first + 2, first, first + 2, first + 3});
    };
    quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0, false); // brick floor
    quad({2, 0, 0}, {0, 1, 0}, {0, 0, 1}, 1, true);  // the open, double-sided panel
    quad({0, 0, 2}, {0, 1, 0}, {1, 0, 0}, 2, false); // plain ceiling (facing -z)
    quad({0, 3, 0}, {1, 0, 0}, {0, 0, 1}, 0, false); // brick again

    s.images.push_back({"brick base.png", "image/png", encode_png(pattern(8, 4, 1))});
    s.images.push_back({"brick_normal.jpg", "image/jpeg", encode_jpeg(gradient(16, 16), 95)});
    s.images.push_back({"panel.png", "image/png", encode_png(pattern(5, 3, 2))});

    Material brick;
    brick.name = "brick";
    brick.base_color_factor = {0.8f, 0.7f, 0.6f, 1.0f};
    brick.base_color.image = 0;
    brick.base_color.sampler = {Filter::Nearest, Filter::Nearest, true, Wrap::ClampToEdge,
                                Wrap::MirroredRepeat};
    brick.normal.image = 1;
    brick.normal_scale = 0.5f;
    brick.occlusion.image = 0; // occlusionTexture (red channel) and its strength
    brick.occlusion.sampler.wrap_s = Wrap::ClampToEdge;
    brick.occlusion_strength = 0.7f;
    brick.technique = "ssbump"; // a custom property: Blender exports it as the material's extras
    Material panel;
    panel.name = "panel";
    panel.base_color.image = 2;
    panel.base_color.texcoord = 1;
    panel.base_color.offset = {0.25f, 0.5f};
    panel.base_color.scale = {2.0f, 3.0f};
    panel.base_color.rotation = 0.3f;
    panel.base_color.sampler.mipmaps = false;
    panel.emissive_factor = {0.1f, 0.2f, 0.3f};
    panel.emissive.image = 0; // the brick image again, with the default sampler
    panel.double_sided = true;
    panel.alpha_mode = AlphaMode::Mask;
    panel.alpha_cutoff = 0.3f;
    Material plain;
    plain.name = "plain";
    plain.base_color_factor = {0.2f, 0.4f, 0.6f, 1.0f};
    s.materials = {brick, panel, plain};
    return s;
}

// The JSON chunk of a .glb, or the .gltf's JSON.
json gltf_json(const fs::path& p)
{
    const std::string bytes = slurp(p);
    if (bytes.rfind("glTF", 0) != 0)
        return json::parse(bytes);
    uint32_t length;
    std::memcpy(&length, bytes.data() + 12, 4);
    return json::parse(bytes.substr(20, length));
}
} // namespace

TEST(GltfReader, BlenderLikeSceneReadsBackAsWritten)
{
    using hemi::io::ImageStorage;
    const hemi::io::GltfScene in = blender_like_scene();
    const std::vector<ImageStorage> storage = {ImageStorage::External, ImageStorage::BufferView,
                                               ImageStorage::DataUri};
    for (const char* name : {"blender.glb", "blender.gltf"})
    {
        SCOPED_TRACE(name);
        const fs::path p = dir() / name;
        fs::remove(dir() / "brick base.png");
        hemi::io::write_gltf(p, in, storage);

        // Stored as asked: the external file beside the glTF under a percent-encoded URI, the JPEG in a
        // buffer view, the panel as a data URI; the texture transform as the extension.
        const json j = gltf_json(p);
        ASSERT_EQ(j["images"].size(), 3u);
        EXPECT_EQ(j["images"][0]["uri"], "brick%20base.png");
        EXPECT_TRUE(fs::exists(dir() / "brick base.png"));
        EXPECT_TRUE(j["images"][1].contains("bufferView"));
        EXPECT_EQ(j["images"][1]["mimeType"], "image/jpeg");
        EXPECT_EQ(j["images"][2]["uri"].get<std::string>().rfind("data:image/png;base64,", 0), 0u);
        EXPECT_TRUE(j["materials"][1]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"].contains(
            "KHR_texture_transform"));
        EXPECT_EQ(j["meshes"][0]["primitives"].size(), 4u);

        const hemi::io::GltfScene out = hemi::io::read_gltf(p);
        EXPECT_FALSE(out.tangents_generated);
        // Every primitive's range and material, every material field, exactly.
        EXPECT_EQ(out.primitives, in.primitives);
        ASSERT_EQ(out.materials.size(), 3u);
        for (size_t i = 0; i < 3; ++i)
            EXPECT_EQ(out.materials[i], in.materials[i]) << "material " << i;
        EXPECT_TRUE(out.materials[1].double_sided);
        EXPECT_FALSE(out.materials[0].double_sided);
        // The geometry, vertex for vertex (each primitive's vertices are its own, in order).
        EXPECT_EQ(out.mesh.positions, in.mesh.positions);
        EXPECT_EQ(out.mesh.normals, in.mesh.normals);
        EXPECT_EQ(out.mesh.tangents, in.mesh.tangents);
        EXPECT_EQ(out.mesh.uvs, in.mesh.uvs);
        EXPECT_EQ(out.mesh.uvs1, in.mesh.uvs1);
        EXPECT_EQ(out.mesh.indices, in.mesh.indices);
        // TEXCOORD_1 on the panel only: the others read zeros, and the reader says so.
        EXPECT_NE(warning_naming(out, "TEXCOORD_1"), "") << all_warnings(out);
        // The panel's MASK: drawn with alpha, baked opaque, and the reader says so.
        EXPECT_NE(warning_naming(out, "alphaMode MASK"), "") << all_warnings(out);
        EXPECT_EQ(out.warnings.size(), 2u) << all_warnings(out);
        // The images, encoded as they were, and decoding to the pixels written.
        ASSERT_EQ(out.images.size(), 3u);
        EXPECT_EQ(out.images[0].name, "brick base.png");
        EXPECT_NE(out.images[1].name.find(name), std::string::npos) << out.images[1].name;
        EXPECT_NE(out.images[2].name.find("data URI"), std::string::npos) << out.images[2].name;
        for (size_t i = 0; i < 3; ++i)
        {
            EXPECT_EQ(out.images[i].mime_type, in.images[i].mime_type);
            EXPECT_EQ(out.images[i].bytes, in.images[i].bytes) << "image " << i;
        }
        EXPECT_EQ(hemi::io::decode_image(out.images[0]).pixels, pattern(8, 4, 1).pixels);
        EXPECT_EQ(hemi::io::decode_image(out.images[2]).pixels, pattern(5, 3, 2).pixels);
        const hemi::io::ImageRgba8 jpeg = hemi::io::decode_image(out.images[1]), want = gradient(16, 16);
        ASSERT_EQ(jpeg.width, 16u);
        ASSERT_EQ(jpeg.height, 16u);
        int worst = 0;
        for (size_t k = 0; k < want.pixels.size(); ++k)
            worst = std::max(worst, std::abs(int(jpeg.pixels[k]) - int(want.pixels[k])));
        EXPECT_LE(worst, 6) << "JPEG at quality 95 of a smooth gradient";
    }
}

// Two textures with different samplers on one image, used by two materials: one image in the scene. An image
// no material uses is not read at all (its file may be missing).
TEST(GltfReader, ImagesAreReadOncePerImageAndOnlyWhenUsed)
{
    Handmade h = handmade_quad();
    hemi::io::write_png(dir() / "shared.png", pattern(3, 3, 4));
    h.j["images"] = json::parse(R"([{"uri": "missing.png"}, {"uri": "shared.png"}])");
    h.j["samplers"] = json::parse(R"([{"magFilter": 9728, "minFilter": 9986, "wrapS": 33071, "wrapT": 33648},
                                      {"minFilter": 9729}])");
    h.j["textures"] = json::parse(R"([{"source": 1, "sampler": 0}, {"source": 1, "sampler": 1}])");
    h.j["materials"] = json::parse(R"([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
                                       {"emissiveTexture": {"index": 1}, "normalTexture": {"index": 0, "scale": 2}}])");
    h.primitive()["material"] = 1;
    const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("shared"));
    ASSERT_EQ(s.images.size(), 1u);
    EXPECT_EQ(s.images[0].name, "shared.png");
    ASSERT_EQ(s.materials.size(), 2u);
    const hemi::io::TextureRef& a = s.materials[0].base_color;
    EXPECT_EQ(a.image, 0);
    EXPECT_EQ(a.sampler,
              (hemi::io::TextureSampler{hemi::io::Filter::Nearest, hemi::io::Filter::Nearest, true,
                                        hemi::io::Wrap::ClampToEdge, hemi::io::Wrap::MirroredRepeat}));
    EXPECT_EQ(s.materials[1].emissive.image, 0);
    EXPECT_EQ(s.materials[1].emissive.sampler,
              (hemi::io::TextureSampler{hemi::io::Filter::Linear, hemi::io::Filter::Linear, false}));
    EXPECT_EQ(s.materials[1].normal.image, 0);
    EXPECT_EQ(s.materials[1].normal_scale, 2.0f);
    EXPECT_EQ(s.primitives[0].material, 1u);
}

// KHR_texture_transform as the extension's example and sample model define it, texCoord override included.
TEST(GltfReader, TextureTransformFollowsTheExtension)
{
    // "This example utilizes only the lower left quadrant of the source image, rotated clockwise 90 degrees."
    hemi::io::TextureRef t;
    t.offset = {0.0f, 1.0f};
    t.rotation = float(M_PI / 2);
    t.scale = {0.5f, 0.5f};
    const glm::mat3 m = t.uv_transform();
    auto at = [&](float u, float v) { return glm::vec2(m * glm::vec3(u, v, 1.0f)); };
    EXPECT_NEAR(glm::length(at(0, 0) - glm::vec2(0.0f, 1.0f)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(at(1, 0) - glm::vec2(0.0f, 0.5f)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(at(0, 1) - glm::vec2(0.5f, 1.0f)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(at(1, 1) - glm::vec2(0.5f, 0.5f)), 0.0f, 1e-6f);

    Handmade h = handmade_quad();
    add_textured_material(h);
    h.accessor(std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}, 5126, "VEC2", 4);
    h.primitive()["attributes"]["TEXCOORD_1"] = 3;
    h.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = json::parse(
        R"({"KHR_texture_transform": {"offset": [0.5, -0.25], "rotation": 0.75, "scale": [2, 4], "texCoord": 1}})");
    h.j["extensionsUsed"] = {"KHR_texture_transform"};
    h.j["extensionsRequired"] = {"KHR_texture_transform"};
    const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("transform"));
    const hemi::io::TextureRef& r = s.materials[0].base_color;
    EXPECT_EQ(r.offset, glm::vec2(0.5f, -0.25f));
    EXPECT_EQ(r.rotation, 0.75f);
    EXPECT_EQ(r.scale, glm::vec2(2.0f, 4.0f));
    EXPECT_EQ(r.texcoord, 1u) << "the extension's texCoord overrides the textureInfo's";
    ASSERT_EQ(s.mesh.uvs1.size(), 4u);
    EXPECT_EQ(s.mesh.uvs1[2], glm::vec2(1, 1));
    EXPECT_TRUE(s.warnings.empty()) << all_warnings(s);

    // Without any TEXCOORD_1 in the scene the texture reads TEXCOORD_0, and the reader says so.
    h.primitive()["attributes"].erase("TEXCOORD_1");
    const hemi::io::GltfScene t0 = hemi::io::read_gltf(h.save("transform_no_uv1"));
    EXPECT_EQ(t0.materials[0].base_color.texcoord, 0u);
    EXPECT_TRUE(t0.mesh.uvs1.empty());
    EXPECT_NE(warning_naming(t0, "TEXCOORD_1"), "") << all_warnings(t0);
}

// The ways exporters store images: percent-encoded URIs, data URIs, buffer views whose declared type is
// wrong.
TEST(GltfReader, ReadsImagesAsExportersStoreThem)
{
    {
        Handmade h = handmade_quad();
        add_textured_material(h, "my%20texture%2Bv2.png", "my texture+v2.png");
        const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("percent"));
        EXPECT_EQ(s.images[0].name, "my texture+v2.png");
        EXPECT_EQ(hemi::io::decode_image(s.images[0]).pixels, pattern(2, 2, 1).pixels);
    }
    {
        // A JPEG in a buffer view that declares itself a PNG: read by its signature, with a warning.
        Handmade h = handmade_quad();
        const std::vector<uint8_t> jpeg = hemi::io::encode_jpeg(gradient(8, 8), 90);
        const int view = h.view(jpeg.data(), jpeg.size());
        h.j["images"] = json::array({{{"bufferView", view}, {"mimeType", "image/png"}}});
        h.j["textures"] = json::array({{{"source", 0}}});
        h.j["materials"] = json::parse(R"([{"emissiveTexture": {"index": 0}}])");
        h.primitive()["material"] = 0;
        const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("mislabelled"));
        ASSERT_EQ(s.images.size(), 1u);
        EXPECT_EQ(s.images[0].mime_type, "image/jpeg");
        EXPECT_EQ(s.images[0].bytes, jpeg);
        EXPECT_NE(warning_naming(s, "declares image/png"), "") << all_warnings(s);
    }
    // Broken references, each named: a malformed escape, a missing file, a remote URI, a GIF, an unsupported
    // data URI.
    auto broken = [&](const json& image, const std::string& name, const std::string& part)
    {
        Handmade h = handmade_quad();
        add_textured_material(h);
        h.j["images"][0] = image;
        expect_error_naming(h.save(name), part);
    };
    broken({{"uri", "bad%zzescape.png"}}, "bad_escape", "percent-encoding");
    broken({{"uri", "nowhere.png"}}, "nowhere", "nowhere.png does not exist");
    broken({{"uri", "https://example.com/a.png"}}, "remote", "not a relative file path");
    broken({{"uri", "data:image/gif;base64,R0lGODlhAQABAAAAACw="}}, "gif", "neither PNG nor JPEG");
    broken({{"uri", "data:image/webp;base64,UklGRg=="}}, "webp", "data URI");
    std::ofstream(dir() / "text.png") << "not an image at all";
    broken({{"uri", "text.png"}}, "text", "neither a PNG nor a JPEG");
}

TEST(GltfReader, ConvertsStripsAndFansSparseAndNormalizedAttributes)
{
    {
        Handmade h = handmade_quad();
        h.j["accessors"][2]["count"] = 4; // indices 0, 1, 2, 0 -> as a strip 0 1 3 2 below
        const std::vector<uint16_t> strip = {0, 1, 3, 2};
        h.j["accessors"][2]["bufferView"] = h.view(strip.data(), 8);
        h.primitive()["mode"] = 5;
        const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("strip"));
        EXPECT_EQ(s.mesh.indices, (std::vector<uint32_t>{0, 1, 3, 1, 2, 3}));
        EXPECT_EQ(s.primitives[0], (hemi::io::Primitive{0, 6, 0}));
        h.primitive()["mode"] = 6;
        const std::vector<uint16_t> fan = {0, 1, 2, 3};
        h.j["accessors"][2]["bufferView"] = h.view(fan.data(), 8);
        EXPECT_EQ(hemi::io::read_gltf(h.save("fan")).mesh.indices, (std::vector<uint32_t>{1, 2, 0, 2, 3, 0}));
    }
    {
        // A sparse POSITION (vertex 2 moved) and TEXCOORD_0 as normalised unsigned shorts.
        Handmade h = handmade_quad();
        const std::vector<uint8_t> index = {2};
        const std::vector<float> value = {5, 6, 7};
        const int iv = h.view(index.data(), 1), vv = h.view(value.data(), 12);
        h.j["accessors"][0]["sparse"] = {{"count", 1},
                                         {"indices", {{"bufferView", iv}, {"componentType", 5121}}},
                                         {"values", {{"bufferView", vv}}}};
        const std::vector<uint16_t> uv = {0, 65535, 65535, 65535, 65535, 0, 0, 0};
        const int t = h.accessor(uv, 5123, "VEC2", 4);
        h.j["accessors"][size_t(t)]["normalized"] = true;
        h.primitive()["attributes"]["TEXCOORD_0"] = t;
        const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("sparse"));
        EXPECT_EQ(s.mesh.positions[2], glm::vec3(5, 6, 7));
        EXPECT_EQ(s.mesh.positions[1], glm::vec3(1, 0, 0));
        EXPECT_EQ(s.mesh.uvs[1], glm::vec2(1, 1));
        EXPECT_EQ(s.mesh.uvs[2], glm::vec2(1, 0));
    }
}

// Every feature hemi reads as something simpler or ignores is named in a warning; the scene still reads.
TEST(GltfReader, UnsupportedFeaturesAreNamedInWarnings)
{
    struct Case
    {
        const char* name;
        std::function<void(Handmade&)> edit;
        std::string feature;
    };
    const std::vector<Case> cases = {
        {"skin",
         [](Handmade& h)
         {
             h.j["skins"] = json::parse(R"([{"joints": [0]}])");
             h.j["nodes"][0]["skin"] = 0;
             h.j["nodes"][0]["translation"] = {5, 0, 0};
         },
         "skins are not supported: node 0 is drawn in its bind pose"},
        {"morph", [](Handmade& h) { h.primitive()["targets"] = json::parse(R"([{"POSITION": 0}])"); },
         "morph targets ignored"},
        {"blend",
         [](Handmade& h)
         {
             h.j["materials"] = json::parse(R"([{"alphaMode": "BLEND", "name": "glass"}])");
             h.primitive()["material"] = 0;
         },
         "alphaMode BLEND baked opaque (drawn with alpha): material 0 (glass)"},
        {"mask",
         [](Handmade& h)
         {
             h.j["materials"] = json::parse(R"([{"alphaMode": "MASK"}])");
             h.primitive()["material"] = 0;
         },
         "alphaMode MASK baked opaque"},
        {"clearcoat",
         [](Handmade& h)
         {
             h.j["materials"] =
                 json::parse(R"([{"extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1}}}])");
             h.j["extensionsUsed"] = {"KHR_materials_clearcoat"};
             h.primitive()["material"] = 0;
         },
         "KHR_materials_clearcoat ignored"},
        {"specgloss",
         [](Handmade& h)
         {
             h.j["materials"] =
                 json::parse(R"([{"extensions": {"KHR_materials_pbrSpecularGlossiness": {}}}])");
             h.j["extensionsUsed"] = {"KHR_materials_pbrSpecularGlossiness"};
             h.j["extensionsRequired"] = {"KHR_materials_pbrSpecularGlossiness"};
             h.primitive()["material"] = 0;
         },
         "KHR_materials_pbrSpecularGlossiness ignored"},
        {"lights",
         [](Handmade& h)
         {
             h.j["extensionsUsed"] = {"KHR_lights_punctual"};
             h.j["extensions"] = json::parse(R"({"KHR_lights_punctual": {"lights": [{"type": "point"}]}})");
         },
         "light(s) that no node places: ignored"},
        {"lines",
         [](Handmade& h)
         {
             json lines = h.primitive();
             lines["mode"] = 1;
             h.j["meshes"][0]["primitives"].push_back(lines);
         },
         "LINES primitives are not drawn: mesh 0 primitive 1 skipped"},
        {"points",
         [](Handmade& h)
         {
             json points = h.primitive();
             points["mode"] = 0;
             points.erase("indices");
             h.j["meshes"][0]["primitives"].push_back(points);
         },
         "POINTS primitives are not drawn"},
        {"colour",
         [](Handmade& h)
         {
             h.accessor(std::vector<float>(16, 0.5f), 5126, "VEC4", 4);
             h.primitive()["attributes"]["COLOR_0"] = 3;
         },
         "vertex colours (COLOR_0) ignored"},
        {"texcoord2",
         [](Handmade& h)
         {
             h.primitive()["attributes"]["TEXCOORD_2"] = 1;
             add_textured_material(h);
             h.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 2;
         },
         "reads TEXCOORD_2, which hemi does not support"},
        {"webp",
         [](Handmade& h)
         {
             add_textured_material(h);
             h.j["textures"][0] = json::parse(R"({"extensions": {"EXT_texture_webp": {"source": 0}}})");
             h.j["extensionsUsed"] = {"EXT_texture_webp"};
         },
         "EXT_texture_webp ignored: texture 0 has no PNG/JPEG image"},
        {"instancing",
         [](Handmade& h)
         {
             h.j["nodes"][0]["extensions"] =
                 json::parse(R"({"EXT_mesh_gpu_instancing": {"attributes": {}}})");
             h.j["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
         },
         "EXT_mesh_gpu_instancing ignored: node 0 is drawn once"},
        {"draco_fallback",
         [](Handmade& h)
         {
             h.primitive()["extensions"] = json::parse(
                 R"({"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}})");
             h.j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
         },
         "KHR_draco_mesh_compression ignored"},
        {"animation",
         [](Handmade& h)
         {
             const int input = h.accessor(std::vector<float>{0, 1}, 5126, "SCALAR", 2);
             const int output = h.accessor(std::vector<float>{0, 0, 0, 1, 0, 0}, 5126, "VEC3", 2);
             h.j["animations"] =
                 json::parse(R"([{"channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                                                   "samplers": [{"input": )" +
                             std::to_string(input) + R"(, "output": )" + std::to_string(output) + "}]}]");
         },
         "animations ignored"},
    };
    for (const Case& c : cases)
    {
        SCOPED_TRACE(c.name);
        Handmade h = handmade_quad();
        c.edit(h);
        const fs::path p = h.save(std::string("feature_") + c.name);
        hemi::io::GltfScene s;
        try
        {
            s = hemi::io::read_gltf(p);
        }
        catch (const std::exception& e)
        {
            ADD_FAILURE() << e.what();
            continue;
        }
        EXPECT_NE(warning_naming(s, c.feature), "")
            << "expected a warning with '" << c.feature << "'; got" << all_warnings(s);
        EXPECT_EQ(s.mesh.indices.size(), 6u);
        if (std::string(c.name) == "skin") // drawn as stored: the skinned node's own transform is not applied
        {
            EXPECT_EQ(s.mesh.positions[1], glm::vec3(1, 0, 0));
        }
    }
}

// What makes the geometry unreadable is an error naming the file and the feature.
// KHR_lights_punctual: each light a node places, in scene space with glTF's units, and bad lights refused.
TEST(GltfReader, ReadsPunctualLightsWhereTheirNodesPlaceThem)
{
    Handmade h = handmade_quad();
    h.j["extensionsUsed"] = {"KHR_lights_punctual"};
    h.j["extensions"] = json::parse(R"({"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 0.5, 0.25], "intensity": 40, "range": 12, "name": "bulb",
         "extras": {"hemi_bake_mode": "mixed"}},
        {"type": "spot", "intensity": 7, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"type": "directional", "intensity": 3}]}})");
    // A point light 2 up, a spot turned +90 degrees about x under a parent moved by (1, 0, 0) (its -Z points
    // along +y), and a directional light with no transform (pointing along -z).
    h.j["nodes"].push_back(
        {{"translation", {0, 2, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    h.j["nodes"].push_back({{"translation", {1, 0, 0}}, {"children", {3}}});
    h.j["nodes"].push_back({{"rotation", {0.7071068, 0, 0, 0.7071068}},
                            {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    h.j["nodes"].push_back({{"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}},
                            {"extras", {{"hemi_bake_mode", "realtime"}}}}); // the node's extras
    h.j["scenes"][0]["nodes"] = {0, 1, 2, 4};
    const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("lights"));
    ASSERT_EQ(s.lights.size(), 3u);
    using T = hemi::io::PunctualLight::Type;
    EXPECT_EQ(s.lights[0].type, T::Point);
    EXPECT_EQ(s.lights[0].name, "bulb");
    EXPECT_EQ(s.lights[0].color, glm::vec3(1, 0.5f, 0.25f));
    EXPECT_FLOAT_EQ(s.lights[0].intensity, 40.0f);
    EXPECT_FLOAT_EQ(s.lights[0].range, 12.0f);
    EXPECT_EQ(s.lights[0].position, glm::vec3(0, 2, 0));
    EXPECT_EQ(s.lights[1].type, T::Spot);
    EXPECT_NEAR(glm::length(s.lights[1].position - glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(s.lights[1].direction - glm::vec3(0, 1, 0)), 0.0f, 1e-5f);
    EXPECT_FLOAT_EQ(s.lights[1].inner_cone, 0.2f);
    EXPECT_FLOAT_EQ(s.lights[1].outer_cone, 0.6f);
    EXPECT_EQ(s.lights[2].type, T::Directional);
    EXPECT_EQ(s.lights[2].direction, glm::vec3(0, 0, -1));
    // Bake modes (issue 43): the light's extras, else its node's, else baked.
    EXPECT_EQ(s.lights[0].mode, hemi::io::LightMode::Mixed);
    EXPECT_EQ(s.lights[1].mode, hemi::io::LightMode::Baked);
    EXPECT_EQ(s.lights[2].mode, hemi::io::LightMode::Realtime);
    for (const std::string& w : s.warnings)
        EXPECT_EQ(w.find("light"), std::string::npos) << w;

    Handmade bad = h;
    bad.j["nodes"][4]["extensions"]["KHR_lights_punctual"]["light"] = 5;
    expect_error_naming(bad.save("light_missing"), "light 5 does not exist");
    bad = h;
    bad.j["extensions"]["KHR_lights_punctual"]["lights"][1]["spot"]["innerConeAngle"] = 0.9;
    expect_error_naming(bad.save("light_cone"), "cone angles");
    bad = h;
    bad.j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = -1;
    expect_error_naming(bad.save("light_negative"), "intensity");
    bad = h;
    bad.j["extensions"]["KHR_lights_punctual"]["lights"][0]["extras"]["hemi_bake_mode"] = "stationary";
    expect_error_naming(bad.save("light_mode"),
                        "light 0 (bulb): extras.hemi_bake_mode must be \"baked\", \"mixed\" or \"realtime\", "
                        "not \"stationary\"");
}

// Light probes placed by hand (issue 44): every node of the scene named hemi_probe* (Blender's empties and
// their copies, "hemi_probe.001"), at its world position; other names and nodes outside the scene are not.
TEST(GltfReader, ReadsLightProbesFromNodesNamedHemiProbe)
{
    Handmade h = handmade_quad();
    h.j["nodes"].push_back({{"name", "hemi_probe"}, {"translation", {1, 2, 3}}});
    h.j["nodes"].push_back(
        {{"name", "room"}, {"translation", {10, 0, 0}}, {"scale", {2, 2, 2}}, {"children", {3, 4, 5}}});
    h.j["nodes"].push_back({{"name", "hemi_probe.001"}, {"translation", {0, 1, 0}}});
    h.j["nodes"].push_back(
        {{"name", "Hemi_Probe"}, {"translation", {0, 5, 0}}}); // not the prefix: case counts
    h.j["nodes"].push_back({{"name", "hemi_probe_stairs"}, {"translation", {0.5, 0, -1}}});
    h.j["nodes"].push_back({{"name", "hemi_probe.002"}, {"translation", {7, 7, 7}}}); // in no scene
    h.j["scenes"][0]["nodes"] = {0, 1, 2};
    const hemi::io::GltfScene s = hemi::io::read_gltf(h.save("probes"));
    ASSERT_EQ(s.light_probes.size(), 3u);
    EXPECT_EQ(s.light_probes[0], glm::vec3(1, 2, 3));
    EXPECT_EQ(s.light_probes[1], glm::vec3(10, 2, 0));
    EXPECT_EQ(s.light_probes[2], glm::vec3(11, 0, -2));
    EXPECT_TRUE(hemi::io::read_gltf(handmade_quad().save("no_probes")).light_probes.empty());
    // write_gltf writes them back as such nodes.
    const fs::path again = fs::temp_directory_path() / "hemi_gltf_probes_again.glb";
    hemi::io::write_gltf(again, s);
    EXPECT_EQ(hemi::io::read_gltf(again).light_probes, s.light_probes);
    fs::remove(again);

    Handmade bad = h;
    bad.j["nodes"][2]["scale"] = {1e30, 1e30, 1e30};
    bad.j["nodes"][3]["translation"] = {0, 1e30, 0};
    expect_error_naming(bad.save("probe_far"),
                        "node 3 (\"hemi_probe.001\"), a light probe, is placed at a point "
                        "that is not finite");
}

TEST(GltfReader, UnreadableFeaturesAreErrorsNamingThem)
{
    auto required = [](const std::string& ext)
    {
        Handmade h = handmade_quad();
        h.j["extensionsUsed"] = {ext};
        h.j["extensionsRequired"] = {ext};
        return h.save("required_" + ext);
    };
    expect_error_naming(required("KHR_draco_mesh_compression"), "KHR_draco_mesh_compression");
    expect_error_naming(required("EXT_meshopt_compression"), "EXT_meshopt_compression");
    expect_error_naming(required("EXT_mesh_gpu_instancing"), "requires extension EXT_mesh_gpu_instancing");
    {
        // Draco geometry without a fallback (no extensionsRequired, as some exporters write it).
        Handmade h = handmade_quad();
        h.j["accessors"][0].erase("bufferView");
        h.primitive()["extensions"] = json::parse(
            R"({"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}})");
        expect_error_naming(h.save("draco_only"), "KHR_draco_mesh_compression");
    }
    {
        Handmade h = handmade_quad();
        h.j["asset"]["version"] = "1.0";
        expect_error_naming(h.save("version1"), "glTF 1.0 is not supported; re-export as glTF 2.0");
        // A real glTF 1.0 layout: collections keyed by id, no asset block.
        std::ofstream(dir() / "gltf1.gltf") << R"({"meshes": {"mesh0": {"primitives": []}}, "nodes": {}})";
        expect_error_naming(dir() / "gltf1.gltf", "glTF 1.0 is not supported; re-export as glTF 2.0");
        // A binary glTF 1.0 (KHR_binary_glTF) header.
        const char header[20] = {'g', 'l', 'T', 'F', 1, 0, 0, 0, 20, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
        std::ofstream(dir() / "gltf1.glb", std::ios::binary).write(header, 20);
        expect_error_naming(dir() / "gltf1.glb", "glTF 1.0 is not supported; re-export as glTF 2.0");
    }
    {
        Handmade h = handmade_quad();
        h.primitive()["mode"] = 1;
        expect_error_naming(h.save("only_lines"), "no triangles (1 point or line primitive(s) skipped)");
        h.primitive()["mode"] = 9;
        expect_error_naming(h.save("mode9"), "unknown primitive mode 9");
    }
}

// The node hierarchy must be a forest. A graph in which each node lists the next one twice would be walked
// 2^N times by a naive traversal; it is refused at its first repeated node, as are cycles and shared
// children. A deep chain (far deeper than any recursion limit) is read.
TEST(GltfReader, NodeGraphsThatAreNotForestsAreRefusedQuickly)
{
    auto chain = [](size_t n, bool twice)
    {
        Handmade h = handmade_quad();
        h.j["nodes"] = json::array();
        for (size_t i = 0; i < n; ++i)
        {
            json node = json::object();
            if (i + 1 < n)
                node["children"] = twice ? json{i + 1, i + 1} : json{i + 1};
            else
                node["mesh"] = 0;
            h.j["nodes"].push_back(node);
        }
        return h;
    };
    // No clock: the bound on the work is in the refusal. The walk is depth-first in file order, so it refuses
    // at the first repeat, node 63 again from node 62, after 64 visits. A walk that visits every path (2^63
    // of them here) before or instead of refusing never gets to an answer; one that flattens the graph into
    // instances first gives no refusal (the small graph), or never finishes (the large one).
    expect_error_naming(chain(64, true).save("doubled"), "node 63 is reached twice (again from node 62)");
    expect_error_naming(chain(12, true).save("doubled12"), "node 11 is reached twice (again from node 10)");
    {
        Handmade h = handmade_quad();
        h.j["nodes"] = json::parse(R"([{"children": [1]}, {"children": [0], "mesh": 0}])");
        expect_error_naming(h.save("cycle"), "node 0 is reached twice");
        h.j["nodes"] = json::parse(R"([{"children": [2]}, {"children": [2]}, {"mesh": 0}])");
        h.j["scenes"][0]["nodes"] = {0, 1};
        expect_error_naming(h.save("shared_child"), "node 2 is reached twice");
        h.j["nodes"] = json::parse(R"([{"mesh": 0}])");
        h.j["scenes"][0]["nodes"] = {0, 0};
        expect_error_naming(h.save("root_twice"), "node 0 is reached twice");
        h.j["scenes"][0]["nodes"] = {0, 7};
        expect_error_naming(h.save("no_node"), "refers to node 7, which does not exist");
    }
    const hemi::io::GltfScene deep = hemi::io::read_gltf(chain(5000, false).save("deep"));
    EXPECT_EQ(deep.mesh.indices.size(), 6u);
}

// Accessor arithmetic does not overflow: counts, offsets and lengths near 2^64 are refused as reading past
// the buffer (not a std::length_error from allocating first, not a wrapped-around bounds check).
TEST(GltfReader, HugeAccessorsReadPastTheirBufferNotIntoAnOverflow)
{
    const uint64_t huge = uint64_t(1) << 62;
    auto expect =
        [&](const std::function<void(Handmade&)>& edit, const std::string& name, const std::string& part)
    {
        // The refusal's own message is the check: reading or allocating first would end in a crash, a
        // std::length_error or std::bad_alloc (2^62 elements), not in "reads past its buffer".
        Handmade h = handmade_quad();
        edit(h);
        expect_error_naming(h.save(name), part);
    };
    expect([&](Handmade& h) { h.j["accessors"][0]["count"] = huge; }, "count62", "reads past its buffer");
    expect([&](Handmade& h) { h.j["accessors"][2]["count"] = huge; }, "indices62", "reads past its buffer");
    expect([&](Handmade& h) { h.j["accessors"][0]["count"] = (huge << 1) + 1; }, "count63",
           "reads past its buffer");
    expect([&](Handmade& h) { h.j["accessors"][0]["byteOffset"] = huge * 3; }, "offset",
           "reads past its buffer");
    expect([&](Handmade& h) { h.j["bufferViews"][0]["byteLength"] = huge; }, "length",
           "reads past its buffer");
    expect([&](Handmade& h) { h.j["bufferViews"][0]["byteOffset"] = huge; }, "view_offset",
           "reads past its buffer");
    expect(
        [&](Handmade& h)
        {
            h.j["bufferViews"][0]["byteStride"] = 252;
            h.j["accessors"][0]["count"] = huge;
        },
        "stride", "reads past its buffer");
    // Without a buffer view an accessor is zeros: a count no index can address is refused before allocating.
    expect(
        [&](Handmade& h)
        {
            h.j["accessors"][0].erase("bufferView");
            h.j["accessors"][0]["count"] = huge;
        },
        "zeros", "no buffer view and 4611686018427387904 elements");
}

TEST(GltfReader, RejectsMissingMalformedAndInconsistentFiles)
{
    expect_error_naming(dir() / "nope.gltf", "no such file");
    std::ofstream(dir() / "garbage.gltf") << "{ this is not json";
    expect_error_naming(dir() / "garbage.gltf", "not a readable glTF");
    expect_error_naming(write_model(quad_model(false, {0, 1, 7}), "badindex.gltf"), "index 7 out of range");
    fs::remove(dir() / "quad_normal.png");
    expect_error_naming(write_model(quad_model(true), "notexture.gltf"), "quad_normal.png");
    tinygltf::Model nopos = quad_model(false);
    nopos.meshes[0].primitives[0].attributes.erase("POSITION");
    expect_error_naming(write_model(nopos, "nopos.gltf"), "no POSITION");
    tinygltf::Model nan = quad_model(false);
    float bad = std::nanf("");
    std::memcpy(nan.buffers[0].data.data() + 4, &bad, 4);
    expect_error_naming(write_model(nan, "nan.gltf"), "non-finite");
    Handmade h = handmade_quad();
    h.primitive()["material"] = 3;
    expect_error_naming(h.save("nomaterial"), "refers to material 3, which does not exist");
    h = handmade_quad();
    add_textured_material(h);
    h.j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = 4;
    expect_error_naming(h.save("notexture_index"), "refers to texture 4, which does not exist");
}

TEST(GltfReader, RejectsEveryTruncatedGlb)
{
    fs::path good = write_model(quad_model(false), "whole.glb", true);
    std::ifstream f(good, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 100u);
    fs::path cut = dir() / "cut.glb";
    for (size_t n = 0; n < bytes.size(); ++n)
    {
        std::ofstream(cut, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(n));
        EXPECT_THROW(hemi::io::read_gltf(cut), hemi::io::FormatError) << "truncated to " << n << " bytes";
    }
}

TEST(GltfWriter, RefusesInconsistentScenes)
{
    hemi::io::GltfScene s = blender_like_scene();
    s.primitives[1].material = 7;
    EXPECT_THROW(hemi::io::write_gltf(dir() / "never.glb", s), std::invalid_argument);
    s = blender_like_scene();
    s.primitives.pop_back();
    EXPECT_THROW(hemi::io::write_gltf(dir() / "never.glb", s), std::invalid_argument);
    s = blender_like_scene();
    EXPECT_THROW(hemi::io::write_gltf(dir() / "never.glb", s, std::vector<hemi::io::ImageStorage>(2)),
                 std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir() / "never.glb"));
}
