#include <hemi/io/gltf.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#include <tiny_gltf.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

namespace hemi::io
{
namespace
{

struct Reader
{
    std::string file;
    const tinygltf::Model& model;

    [[noreturn]] void fail(const std::string& what) const { throw FormatError(file + ": " + what); }

    // Reads `count` elements of `components` floats (or normalised/unsigned ints for indices) from accessor i.
    template <typename T>
    std::vector<T> read(int index, int components, const char* what) const
    {
        if (index < 0 || size_t(index) >= model.accessors.size())
            fail(std::string(what) + ": accessor " + std::to_string(index) + " does not exist");
        const tinygltf::Accessor& a = model.accessors[index];
        if (tinygltf::GetNumComponentsInType(uint32_t(a.type)) != components)
            fail(std::string(what) + ": accessor " + std::to_string(index) + " has the wrong type");
        if (a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size())
            fail(std::string(what) + ": accessor " + std::to_string(index) + " has no buffer view (sparse accessors are not supported)");
        const tinygltf::BufferView& view = model.bufferViews[a.bufferView];
        if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size())
            fail(std::string(what) + ": buffer view " + std::to_string(a.bufferView) + " has no buffer");
        const std::vector<unsigned char>& data = model.buffers[view.buffer].data;
        const int component_size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        if (component_size <= 0)
            fail(std::string(what) + ": accessor " + std::to_string(index) + " has an unknown component type");
        const size_t element = size_t(component_size) * components;
        const size_t stride = view.byteStride ? view.byteStride : element;
        const size_t begin = view.byteOffset + a.byteOffset;
        if (a.count == 0)
            return {};
        const size_t end = begin + stride * (a.count - 1) + element;
        if (end > view.byteOffset + view.byteLength || end > data.size() || stride < element)
            fail(std::string(what) + ": accessor " + std::to_string(index) + " reads past its buffer");
        std::vector<T> out(a.count * size_t(components));
        for (size_t i = 0; i < a.count; ++i)
            for (int c = 0; c < components; ++c)
            {
                const unsigned char* p = data.data() + begin + i * stride + size_t(c) * component_size;
                double v = 0;
                switch (a.componentType)
                {
                case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, p, 4); v = f; break; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = *p; break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t s; std::memcpy(&s, p, 2); v = s; break; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t u; std::memcpy(&u, p, 4); v = u; break; }
                default: fail(std::string(what) + ": unsupported component type");
                }
                if constexpr (std::is_floating_point_v<T>)
                    if (!std::isfinite(v))
                        fail(std::string(what) + ": non-finite value in accessor " + std::to_string(index));
                out[i * components + c] = T(v);
            }
        return out;
    }
};

glm::mat4 local_matrix(const tinygltf::Node& n)
{
    if (n.matrix.size() == 16)
    {
        glm::dmat4 m = glm::make_mat4(n.matrix.data());
        return glm::mat4(m);
    }
    glm::mat4 m(1.0f);
    if (n.translation.size() == 3)
        m = glm::translate(m, glm::vec3(float(n.translation[0]), float(n.translation[1]), float(n.translation[2])));
    if (n.rotation.size() == 4)
        m *= glm::mat4_cast(glm::quat(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]), float(n.rotation[2])));
    if (n.scale.size() == 3)
        m = glm::scale(m, glm::vec3(float(n.scale[0]), float(n.scale[1]), float(n.scale[2])));
    return m;
}

void generate_normals(Mesh& m, size_t first_vertex, size_t first_index)
{
    for (size_t v = first_vertex; v < m.positions.size(); ++v)
        m.normals[v] = glm::vec3(0.0f);
    for (size_t i = first_index; i + 2 < m.indices.size(); i += 3)
    {
        uint32_t a = m.indices[i], b = m.indices[i + 1], c = m.indices[i + 2];
        glm::vec3 n = glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]); // area-weighted
        m.normals[a] += n, m.normals[b] += n, m.normals[c] += n;
    }
    for (size_t v = first_vertex; v < m.positions.size(); ++v)
    {
        float len = glm::length(m.normals[v]);
        m.normals[v] = len > 0 ? m.normals[v] / len : glm::vec3(0, 0, 1);
    }
}

void generate_tangents(Mesh& m, size_t first_vertex, size_t first_index)
{
    // MikkTSpace's construction: each triangle's UV tangent and bitangent, projected into the plane of
    // each corner's vertex normal and normalised, are accumulated weighted by the corner's angle (so a
    // vertex's frame does not depend on how finely its neighbourhood is tessellated).
    const size_t n = m.positions.size();
    std::vector<glm::vec3> t(n, glm::vec3(0.0f)), b(n, glm::vec3(0.0f));
    auto unit_in_plane = [](const glm::vec3& v, const glm::vec3& normal) {
        const glm::vec3 p = v - normal * glm::dot(normal, v);
        const float len = glm::length(p);
        return len > 1e-20f ? p / len : glm::vec3(0.0f);
    };
    for (size_t i = first_index; i + 2 < m.indices.size(); i += 3)
    {
        const uint32_t idx[3] = {m.indices[i], m.indices[i + 1], m.indices[i + 2]};
        glm::vec3 e1 = m.positions[idx[1]] - m.positions[idx[0]], e2 = m.positions[idx[2]] - m.positions[idx[0]];
        glm::vec2 d1 = m.uvs[idx[1]] - m.uvs[idx[0]], d2 = m.uvs[idx[2]] - m.uvs[idx[0]];
        float det = d1.x * d2.y - d2.x * d1.y;
        if (std::abs(det) < 1e-20f)
            continue;
        // dP/du and dP/dv of the triangle; glTF's bitangent points toward -v (DESIGN.md, io/mesh.h).
        const glm::vec3 dpdu = (e1 * d2.y - e2 * d1.y) / det, dpdv = (e2 * d1.x - e1 * d2.x) / det;
        for (int c = 0; c < 3; ++c)
        {
            const uint32_t v = idx[c];
            const glm::vec3& normal = m.normals[v];
            const glm::vec3 a = unit_in_plane(m.positions[idx[(c + 1) % 3]] - m.positions[v], normal);
            const glm::vec3 e = unit_in_plane(m.positions[idx[(c + 2) % 3]] - m.positions[v], normal);
            // A corner whose edges vanish in the normal's plane says nothing about the frame: no weight.
            const float angle = glm::dot(a, a) > 0.0f && glm::dot(e, e) > 0.0f
                                    ? std::acos(std::clamp(glm::dot(a, e), -1.0f, 1.0f))
                                    : 0.0f;
            t[v] += angle * unit_in_plane(dpdu, normal);
            b[v] -= angle * unit_in_plane(dpdv, normal);
        }
    }
    for (size_t v = first_vertex; v < n; ++v)
    {
        glm::vec3 nn = m.normals[v];
        glm::vec3 tt = t[v] - nn * glm::dot(nn, t[v]);
        float len = glm::length(tt);
        if (len < 1e-12f) // no UV gradient: any tangent perpendicular to the normal
            tt = glm::normalize(std::abs(nn.x) < 0.9f ? glm::cross(nn, glm::vec3(1, 0, 0)) : glm::cross(nn, glm::vec3(0, 1, 0)));
        else
            tt /= len;
        float w = glm::dot(glm::cross(nn, tt), b[v]) < 0.0f ? -1.0f : 1.0f;
        m.tangents[v] = glm::vec4(tt, w);
    }
}

std::filesystem::path texture_path(const Reader& r, const std::filesystem::path& dir, int texture_index)
{
    if (texture_index < 0)
        return {};
    if (size_t(texture_index) >= r.model.textures.size())
        r.fail("texture " + std::to_string(texture_index) + " does not exist");
    int source = r.model.textures[texture_index].source;
    if (source < 0 || size_t(source) >= r.model.images.size())
        r.fail("texture " + std::to_string(texture_index) + " has no image");
    const tinygltf::Image& img = r.model.images[source];
    if (img.uri.empty())
        r.fail("image " + std::to_string(source) + " is embedded; hemi reads textures from files");
    std::filesystem::path p = dir / img.uri;
    if (!std::filesystem::exists(p))
        r.fail("texture file " + p.string() + " does not exist");
    return p;
}

} // namespace

GltfScene read_gltf(const std::filesystem::path& path)
{
    const std::string file = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw FormatError(file + ": no such file");
    tinygltf::TinyGLTF loader;
    // Images are only referenced here (decoded later by the texture reader): accept without decoding.
    loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*,
                             int, void*) { return true; },
                          nullptr);
    tinygltf::Model model;
    std::string err, warn;
    const bool binary = path.extension() == ".glb";
    bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, file)
                     : loader.LoadASCIIFromFile(&model, &err, &warn, file);
    if (!ok)
        throw FormatError(file + ": not a readable glTF file: " + (err.empty() ? std::string("unknown error") : err));

    Reader r{file, model};
    GltfScene scene;
    Mesh& m = scene.mesh;
    const std::filesystem::path dir = path.parent_path();
    int material = -1;

    auto add_mesh = [&](int mesh_index, const glm::mat4& world) {
        if (mesh_index < 0 || size_t(mesh_index) >= model.meshes.size())
            r.fail("node refers to mesh " + std::to_string(mesh_index) + ", which does not exist");
        const glm::mat3 linear(world);
        const glm::mat3 normal_matrix = glm::inverseTranspose(linear);
        const float handedness = glm::determinant(linear) < 0.0f ? -1.0f : 1.0f;
        for (const tinygltf::Primitive& prim : model.meshes[mesh_index].primitives)
        {
            if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1)
                r.fail("mesh " + std::to_string(mesh_index) + ": only triangle lists are supported");
            auto pos_it = prim.attributes.find("POSITION");
            if (pos_it == prim.attributes.end())
                r.fail("mesh " + std::to_string(mesh_index) + ": a primitive has no POSITION");
            std::vector<float> pos = r.read<float>(pos_it->second, 3, "POSITION");
            const size_t count = pos.size() / 3, first_vertex = m.positions.size(), first_index = m.indices.size();
            std::vector<float> nrm, tan, uv;
            if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end())
                nrm = r.read<float>(it->second, 3, "NORMAL");
            if (auto it = prim.attributes.find("TANGENT"); it != prim.attributes.end())
                tan = r.read<float>(it->second, 4, "TANGENT");
            if (auto it = prim.attributes.find("TEXCOORD_0"); it != prim.attributes.end())
                uv = r.read<float>(it->second, 2, "TEXCOORD_0");
            if ((!nrm.empty() && nrm.size() != count * 3) || (!tan.empty() && tan.size() != count * 4) ||
                (!uv.empty() && uv.size() != count * 2))
                r.fail("mesh " + std::to_string(mesh_index) + ": attribute counts differ from POSITION's");
            for (size_t v = 0; v < count; ++v)
            {
                m.positions.push_back(glm::vec3(world * glm::vec4(pos[v * 3], pos[v * 3 + 1], pos[v * 3 + 2], 1.0f)));
                m.normals.push_back(nrm.empty() ? glm::vec3(0.0f)
                                                : glm::normalize(normal_matrix * glm::vec3(nrm[v * 3], nrm[v * 3 + 1], nrm[v * 3 + 2])));
                m.tangents.push_back(tan.empty() ? glm::vec4(0.0f)
                                                 : glm::vec4(glm::normalize(linear * glm::vec3(tan[v * 4], tan[v * 4 + 1], tan[v * 4 + 2])),
                                                             tan[v * 4 + 3] * handedness));
                m.uvs.push_back(uv.empty() ? glm::vec2(0.0f) : glm::vec2(uv[v * 2], uv[v * 2 + 1]));
            }
            std::vector<uint32_t> idx;
            if (prim.indices >= 0)
                idx = r.read<uint32_t>(prim.indices, 1, "indices");
            else
                for (size_t v = 0; v < count; ++v)
                    idx.push_back(uint32_t(v));
            if (idx.size() % 3 != 0)
                r.fail("mesh " + std::to_string(mesh_index) + ": index count is not a multiple of 3");
            for (uint32_t i : idx)
                if (i >= count)
                    r.fail("mesh " + std::to_string(mesh_index) + ": index " + std::to_string(i) + " out of range (" +
                           std::to_string(count) + " vertices)");
            // A mirroring node (negative determinant) turns counter-clockwise triangles clockwise (glTF 2.0,
            // 3.7.4): swap two corners so that every triangle stays counter-clockwise seen from outside.
            for (size_t t = 0; t < idx.size(); t += 3)
            {
                m.indices.push_back(uint32_t(first_vertex + idx[t]));
                m.indices.push_back(uint32_t(first_vertex + idx[handedness < 0.0f ? t + 2 : t + 1]));
                m.indices.push_back(uint32_t(first_vertex + idx[handedness < 0.0f ? t + 1 : t + 2]));
            }
            if (nrm.empty())
                generate_normals(m, first_vertex, first_index);
            if (tan.empty())
            {
                generate_tangents(m, first_vertex, first_index);
                scene.tangents_generated = true;
            }
            if (material < 0)
                material = prim.material;
            else if (prim.material >= 0 && prim.material != material)
                ++scene.ignored_material_primitives;
        }
    };

    std::function<void(int, const glm::mat4&, int)> visit = [&](int node, const glm::mat4& parent, int depth) {
        if (node < 0 || size_t(node) >= model.nodes.size() || depth > 256)
            r.fail("node " + std::to_string(node) + " does not exist (or the hierarchy has a cycle)");
        const tinygltf::Node& n = model.nodes[node];
        glm::mat4 world = parent * local_matrix(n);
        if (n.mesh >= 0)
            add_mesh(n.mesh, world);
        for (int child : n.children)
            visit(child, world, depth + 1);
    };
    if (!model.scenes.empty())
    {
        int s = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size() ? model.defaultScene : 0;
        for (int node : model.scenes[s].nodes)
            visit(node, glm::mat4(1.0f), 0);
    }
    else
        for (size_t i = 0; i < model.meshes.size(); ++i)
            add_mesh(int(i), glm::mat4(1.0f));
    if (m.indices.empty())
        r.fail("the scene has no triangles");
    if (material >= 0 && size_t(material) < model.materials.size())
    {
        const tinygltf::Material& mat = model.materials[material];
        scene.base_color_texture = texture_path(r, dir, mat.pbrMetallicRoughness.baseColorTexture.index);
        scene.normal_texture = texture_path(r, dir, mat.normalTexture.index);
    }
    return scene;
}

void write_gltf(const std::filesystem::path& path, const Mesh& mesh, const std::string& base_color_uri,
                const std::string& normal_uri)
{
    const size_t n = mesh.vertex_count();
    if (n == 0 || mesh.indices.empty() || mesh.indices.size() % 3)
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": empty or non-triangle mesh");
    for (uint32_t i : mesh.indices)
        if (i >= n)
            throw std::invalid_argument("hemi: cannot write " + path.string() + ": index out of range");
    tinygltf::Model m;
    m.asset.version = "2.0";
    m.asset.generator = "hemi";
    m.buffers.emplace_back();
    std::vector<unsigned char>& data = m.buffers[0].data;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    auto add = [&](const void* bytes, size_t size, int component, int type, size_t count, int target) {
        while (data.size() % 4)
            data.push_back(0);
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = data.size();
        view.byteLength = size;
        view.target = target;
        const auto* b = static_cast<const unsigned char*>(bytes);
        data.insert(data.end(), b, b + size);
        m.bufferViews.push_back(view);
        tinygltf::Accessor a;
        a.bufferView = int(m.bufferViews.size() - 1);
        a.componentType = component;
        a.type = type;
        a.count = count;
        m.accessors.push_back(a);
        return int(m.accessors.size() - 1);
    };
    const int position = add(mesh.positions.data(), n * 12, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n,
                             TINYGLTF_TARGET_ARRAY_BUFFER);
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : mesh.positions)
    {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    m.accessors[position].minValues = {lo.x, lo.y, lo.z};
    m.accessors[position].maxValues = {hi.x, hi.y, hi.z};
    prim.attributes["POSITION"] = position;
    if (mesh.normals.size() == n)
        prim.attributes["NORMAL"] = add(mesh.normals.data(), n * 12, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                        TINYGLTF_TYPE_VEC3, n, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (mesh.tangents.size() == n)
        prim.attributes["TANGENT"] = add(mesh.tangents.data(), n * 16, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                         TINYGLTF_TYPE_VEC4, n, TINYGLTF_TARGET_ARRAY_BUFFER);
    if (mesh.uvs.size() == n)
        prim.attributes["TEXCOORD_0"] = add(mesh.uvs.data(), n * 8, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                            TINYGLTF_TYPE_VEC2, n, TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.indices = add(mesh.indices.data(), mesh.indices.size() * 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                       TINYGLTF_TYPE_SCALAR, mesh.indices.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    m.buffers[0].uri.clear();

    tinygltf::Material material;
    material.name = "hemi";
    auto texture = [&](const std::string& uri) {
        tinygltf::Image image;
        image.uri = uri;
        m.images.push_back(image);
        tinygltf::Texture t;
        t.source = int(m.images.size() - 1);
        m.textures.push_back(t);
        return int(m.textures.size() - 1);
    };
    if (!base_color_uri.empty())
        material.pbrMetallicRoughness.baseColorTexture.index = texture(base_color_uri);
    if (!normal_uri.empty())
        material.normalTexture.index = texture(normal_uri);
    m.materials.push_back(material);
    prim.material = 0;
    tinygltf::Mesh gmesh;
    gmesh.primitives.push_back(prim);
    m.meshes.push_back(gmesh);
    tinygltf::Node node;
    node.mesh = 0;
    m.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    m.scenes.push_back(scene);
    m.defaultScene = 0;

    const bool binary = path.extension() == ".glb";
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToFile(&m, tmp.string(), false, true, true, binary))
            throw FormatError(path.string() + ": writing glTF failed");
    });
}

} // namespace hemi::io
