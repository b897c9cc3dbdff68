#include <hemi/render/scene/gpu_mesh.h>

#include <cstddef>
#include <stdexcept>
#include <string>

namespace hemi::render
{
namespace
{
struct Vertex
{
    float position[3];
    float normal[3];
    float tangent[4];
    float uv0[2];
    float uv1[2];
};
// VertexLayout's default describes this struct.
static_assert(sizeof(Vertex) == 56 && offsetof(Vertex, normal) == 12 && offsetof(Vertex, tangent) == 24 &&
              offsetof(Vertex, uv0) == 40 && offsetof(Vertex, uv1) == 48);
} // namespace

GpuMesh::GpuMesh(const gpu::Device& device, const io::Mesh& mesh, gpu::UploadBatch& upload)
{
    const size_t n = mesh.positions.size();
    if (std::string problem = io::mesh_problem(mesh, io::MeshNeeds::Frames); !problem.empty())
        throw std::invalid_argument("hemi: " + problem);
    if (!mesh.uvs1.empty() && mesh.uvs1.size() != n)
        throw std::invalid_argument("hemi: the mesh has " + std::to_string(mesh.uvs1.size()) +
                                    " TEXCOORD_1 values for " + std::to_string(n) + " vertices");
    std::vector<Vertex> vertices(n);
    for (size_t i = 0; i < n; ++i)
    {
        const glm::vec2 uv1 = mesh.uvs1.empty() ? glm::vec2(0.0f) : mesh.uvs1[i];
        vertices[i] = {{mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z},
                       {mesh.normals[i].x, mesh.normals[i].y, mesh.normals[i].z},
                       {mesh.tangents[i].x, mesh.tangents[i].y, mesh.tangents[i].z, mesh.tangents[i].w},
                       {mesh.uvs[i].x, mesh.uvs[i].y},
                       {uv1.x, uv1.y}};
    }
    vertices_ =
        gpu::create_buffer(device, {vertices.size() * sizeof(Vertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    upload.buffer(vertices_, vertices.data(), vertices.size() * sizeof(Vertex));
    indices_ = gpu::create_buffer(device, {mesh.indices.size() * 4, VK_BUFFER_USAGE_INDEX_BUFFER_BIT});
    upload.buffer(indices_, mesh.indices.data(), mesh.indices.size() * 4);
    device.set_name(VK_OBJECT_TYPE_BUFFER, vertices_.handle(), "hemi mesh vertices");
    device.set_name(VK_OBJECT_TYPE_BUFFER, indices_.handle(), "hemi mesh indices");
    vertex_count_ = uint32_t(n);
    index_count_ = uint32_t(mesh.indices.size());
    binding_.vertex_buffers[0] = vertices_.handle();
    binding_.index_buffer = indices_.handle();
}

void MeshBinding::bind(VkCommandBuffer cmd) const
{
    vkCmdBindVertexBuffers(cmd, 0, streams, vertex_buffers, vertex_offsets);
    vkCmdBindIndexBuffer(cmd, index_buffer, index_offset, index_type);
}

void GpuMesh::draw(VkCommandBuffer cmd, uint32_t first_index, uint32_t index_count, uint32_t instance_count,
                   uint32_t first_instance) const
{
    if (uint64_t(first_index) + index_count > index_count_)
        throw std::invalid_argument("hemi: draw of indices [" + std::to_string(first_index) + ", +" +
                                    std::to_string(index_count) + ") past the mesh's " +
                                    std::to_string(index_count_));
    vkCmdDrawIndexed(cmd, index_count, instance_count, first_index, 0, first_instance);
}

} // namespace hemi::render
