#pragma once
// hemi's glTF writer's model, for the writers that add to a scene before it is written (io/lightmap_gltf.h):
// internal to the engine library, not installed.
#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>

#include <tiny_gltf.h>

#include <glm/common.hpp>

#include <cmath>
#include <filesystem>
#include <type_traits>
#include <vector>

namespace hemi::io::detail
{

// Builds a tinygltf model whose one buffer holds every accessor and embedded image.
struct GltfBuilder
{
    tinygltf::Model m;

    GltfBuilder()
    {
        m.asset.version = "2.0";
        m.asset.generator = "hemi";
        m.buffers.emplace_back();
    }

    int view(const void* bytes, size_t size, int target)
    {
        std::vector<unsigned char>& data = m.buffers[0].data;
        while (data.size() % 4)
            data.push_back(0);
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = data.size();
        v.byteLength = size;
        v.target = target;
        const auto* b = static_cast<const unsigned char*>(bytes);
        data.insert(data.end(), b, b + size);
        m.bufferViews.push_back(v);
        return int(m.bufferViews.size() - 1);
    }

    int accessor(const void* bytes, size_t size, int component, int type, size_t count, int target)
    {
        tinygltf::Accessor a;
        a.bufferView = view(bytes, size, target);
        a.componentType = component;
        a.type = type;
        a.count = count;
        m.accessors.push_back(a);
        return int(m.accessors.size() - 1);
    }

    // POSITION, NORMAL, TANGENT, TEXCOORD_0/1 of `mesh`'s vertices `vertices` (all when empty), as exporters
    // do.
    void attributes(tinygltf::Primitive& prim, const Mesh& mesh, const std::vector<uint32_t>& vertices,
                    bool uvs1)
    {
        auto gather = [&](const auto& all)
        {
            using T = typename std::decay_t<decltype(all)>::value_type;
            std::vector<T> out;
            out.reserve(vertices.size());
            for (uint32_t v : vertices)
                out.push_back(all[v]);
            return out;
        };
        const size_t n = vertices.size();
        const std::vector<glm::vec3> pos = gather(mesh.positions);
        const int position = accessor(pos.data(), n * 12, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                                      n, TINYGLTF_TARGET_ARRAY_BUFFER);
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (const glm::vec3& p : pos)
        {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        m.accessors[size_t(position)].minValues = {lo.x, lo.y, lo.z};
        m.accessors[size_t(position)].maxValues = {hi.x, hi.y, hi.z};
        prim.attributes["POSITION"] = position;
        const size_t all = mesh.vertex_count();
        if (mesh.normals.size() == all)
            prim.attributes["NORMAL"] =
                accessor(gather(mesh.normals).data(), n * 12, TINYGLTF_COMPONENT_TYPE_FLOAT,
                         TINYGLTF_TYPE_VEC3, n, TINYGLTF_TARGET_ARRAY_BUFFER);
        if (mesh.tangents.size() == all)
            prim.attributes["TANGENT"] =
                accessor(gather(mesh.tangents).data(), n * 16, TINYGLTF_COMPONENT_TYPE_FLOAT,
                         TINYGLTF_TYPE_VEC4, n, TINYGLTF_TARGET_ARRAY_BUFFER);
        if (mesh.uvs.size() == all)
            prim.attributes["TEXCOORD_0"] =
                accessor(gather(mesh.uvs).data(), n * 8, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, n,
                         TINYGLTF_TARGET_ARRAY_BUFFER);
        if (uvs1)
            prim.attributes["TEXCOORD_1"] =
                accessor(gather(mesh.uvs1).data(), n * 8, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2,
                         n, TINYGLTF_TARGET_ARRAY_BUFFER);
    }

    void write(const std::filesystem::path& path)
    {
        m.buffers[0].uri.clear();
        const bool binary = path.extension() == ".glb";
        write_atomically(path,
                         [&](const std::filesystem::path& tmp)
                         {
                             tinygltf::TinyGLTF writer;
                             // Images are written by the caller (or are embedded already): tinygltf's default
                             // image writer would re-encode decoded pixels, which hemi does not keep.
                             writer.SetImageWriter([](const std::string*, const std::string*,
                                                      const tinygltf::Image*, bool, std::string*, void*)
                                                   { return false; },
                                                   nullptr);
                             if (!writer.WriteGltfSceneToFile(&m, tmp.string(), false, true, true, binary))
                                 throw FormatError(path.string() + ": writing glTF failed");
                         });
    }

    void single_node(const tinygltf::Mesh& mesh)
    {
        m.meshes.push_back(mesh);
        tinygltf::Node node;
        node.mesh = 0;
        m.nodes.push_back(node);
        tinygltf::Scene s;
        s.nodes = {0};
        m.scenes.push_back(s);
        m.defaultScene = 0;
    }
};

// What write_gltf(path, scene, storage) writes, before it is written (external images are already written
// beside `path`). Throws as write_gltf does for an inconsistent scene.
GltfBuilder scene_builder(const std::filesystem::path& path, const GltfScene& scene,
                          const std::vector<ImageStorage>& storage);

} // namespace hemi::io::detail
