// glTF reading: a model made in code (tinygltf's writer), node transforms, generated tangents against the
// UV layout, and malformed input with the file named in the error.
#include "../temp_dir.h"

#include <hemi/io/gltf.h>
#include <hemi/io/image.h>

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <glm/geometric.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace
{
fs::path dir()
{
    return hemi::test::temp_dir("gltf_test");
}

template <typename T>
void append(std::vector<unsigned char>& buf, const std::vector<T>& v)
{
    size_t at = buf.size();
    buf.resize(at + v.size() * sizeof(T));
    std::memcpy(buf.data() + at, v.data(), v.size() * sizeof(T));
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
    auto view = [&](size_t offset, size_t length) {
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = offset;
        v.byteLength = length;
        m.bufferViews.push_back(v);
        return int(m.bufferViews.size() - 1);
    };
    auto accessor = [&](int v, int component, int type, size_t count) {
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
    int i = accessor(view(80, indices.size() * 2), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR,
                     indices.size());
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

void expect_error_naming(const fs::path& p, const std::string& part)
{
    try
    {
        hemi::io::read_gltf(p);
        ADD_FAILURE() << "read_gltf accepted " << p;
    }
    catch (const hemi::io::FormatError& e)
    {
        std::string what = e.what();
        EXPECT_NE(what.find(p.filename().string()), std::string::npos) << what;
        EXPECT_NE(what.find(part), std::string::npos) << what;
    }
}
} // namespace

TEST(GltfReader, ReadsTransformedGeometryAndGeneratesTangentsFromUvs)
{
    std::ofstream(dir() / "quad_normal.png") << "png";
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
            EXPECT_NEAR(glm::length(glm::vec3(s.mesh.tangents[v]) - glm::vec3(1, 0, 0)), 0.0f, 1e-6f) << "tangent " << v;
            EXPECT_EQ(s.mesh.tangents[v].w, 1.0f);
        }
        EXPECT_EQ(s.normal_texture.filename(), "quad_normal.png");
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
    m.uvs = {{0, 0}, {1, 0}, {0, -1}, {0, -30}, {-30, -30}}; // B's UVs 3x denser: raw dP/du would weigh it 1/3
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
        EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f) << "triangle " << t / 3 << " winds clockwise seen from +z";
    }
    for (const glm::vec3& n : s.mesh.normals)
        EXPECT_NEAR(glm::length(n - glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
}

// A scene with a second material: its primitive's geometry is read, and the reader counts it so that the
// baker can warn that the asset references the first material's textures only.
TEST(GltfReader, CountsPrimitivesOfOtherMaterials)
{
    std::ofstream(dir() / "quad_normal.png") << "png";
    tinygltf::Model m = quad_model(true);
    m.materials.push_back(tinygltf::Material{});
    tinygltf::Primitive second = m.meshes[0].primitives[0];
    second.material = 1;
    m.meshes[0].primitives.push_back(second);
    const hemi::io::GltfScene s = hemi::io::read_gltf(write_model(m, "two_materials.gltf"));
    EXPECT_EQ(s.mesh.vertex_count(), 8u);
    EXPECT_EQ(s.ignored_material_primitives, 1u);
    EXPECT_EQ(s.normal_texture.filename(), "quad_normal.png");
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
