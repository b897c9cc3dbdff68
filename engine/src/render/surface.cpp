#include <hemi/gpu/commands.h>
#include <hemi/render/surface.h>

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
    float uv[2];
};
} // namespace

GpuMesh::GpuMesh(const gpu::Device& device, const io::Mesh& mesh)
{
    const size_t n = mesh.positions.size();
    if (std::string problem = io::mesh_problem(mesh, io::MeshNeeds::Frames); !problem.empty())
        throw std::invalid_argument("hemi: " + problem);
    std::vector<Vertex> vertices(n);
    for (size_t i = 0; i < n; ++i)
        vertices[i] = {{mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z},
                       {mesh.normals[i].x, mesh.normals[i].y, mesh.normals[i].z},
                       {mesh.tangents[i].x, mesh.tangents[i].y, mesh.tangents[i].z, mesh.tangents[i].w},
                       {mesh.uvs[i].x, mesh.uvs[i].y}};
    vertices_ = gpu::create_buffer(device, {vertices.size() * sizeof(Vertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    gpu::write_buffer(device, vertices_, vertices.data(), vertices.size() * sizeof(Vertex));
    indices_ = gpu::create_buffer(device, {mesh.indices.size() * 4, VK_BUFFER_USAGE_INDEX_BUFFER_BIT});
    gpu::write_buffer(device, indices_, mesh.indices.data(), mesh.indices.size() * 4);
    vertex_count_ = uint32_t(n);
    index_count_ = uint32_t(mesh.indices.size());
}

std::vector<VkVertexInputBindingDescription> GpuMesh::vertex_bindings()
{
    return {{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX}};
}

std::vector<VkVertexInputAttributeDescription> GpuMesh::vertex_attributes()
{
    return {
        {0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)},
        {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, normal)},
        {2, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(Vertex, tangent)},
        {3, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(Vertex, uv)},
    };
}

void GpuMesh::draw(VkCommandBuffer cmd) const
{
    VkBuffer vb = vertices_;
    VkDeviceSize offset = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
    vkCmdBindIndexBuffer(cmd, indices_, 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, index_count_, 1, 0, 0, 0);
}

void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& uniforms, const void* data, size_t size)
{
    const VkPipelineStageFlags shaders = VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT;
    gpu::memory_barrier(cmd, shaders, VK_ACCESS_UNIFORM_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_TRANSFER_WRITE_BIT);
    vkCmdUpdateBuffer(cmd, uniforms, 0, size, data);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, shaders,
                        VK_ACCESS_UNIFORM_READ_BIT);
}

void draw_surface(VkCommandBuffer cmd, const gpu::Program& program, VkDescriptorSet set, const GpuMesh& mesh)
{
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0, 1, &set, 0, nullptr);
    mesh.draw(cmd);
}

SurfacePass surface_pass(const OffscreenTarget& target)
{
    return {target.render_pass(), 0, OffscreenTarget::kColorAttachments};
}

gpu::Program create_surface_program(const gpu::Device& device, const SurfacePass& pass,
                                    std::string_view vertex_shader, std::string_view fragment_shader,
                                    const std::vector<gpu::Binding>& bindings,
                                    const std::vector<uint32_t>& specialization)
{
    gpu::GraphicsProgramDesc desc;
    desc.vertex_shader = gpu::embedded_spirv(vertex_shader);
    desc.fragment_shader = gpu::embedded_spirv(fragment_shader);
    desc.bindings = bindings;
    desc.specialization = specialization;
    desc.vertex_bindings = GpuMesh::vertex_bindings();
    desc.vertex_attributes = GpuMesh::vertex_attributes();
    if (pass.render_pass == VK_NULL_HANDLE || pass.color_attachments == 0)
        throw std::invalid_argument("hemi: a surface pass needs a render pass with at least one colour attachment");
    desc.render_pass = pass.render_pass;
    desc.subpass = pass.subpass;
    desc.color_attachments = pass.color_attachments;
    desc.cull_mode = VK_CULL_MODE_BACK_BIT;
    // Meshes are counter-clockwise seen from outside; look_at_projection flips y for Vulkan's clip space,
    // and Vulkan's facing rule (its area formula is negated for y-down framebuffers) keeps them CCW.
    desc.front_face = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    return gpu::create_graphics_program(device, desc);
}

gpu::Image upload_normal_map(const gpu::Device& device, std::span<const uint8_t> rgba8, uint32_t width,
                             uint32_t height)
{
    return upload_texture(device, rgba8, width, height, false);
}

gpu::Image upload_texture(const gpu::Device& device, std::span<const uint8_t> rgba8, uint32_t width,
                          uint32_t height, bool srgb)
{
    if (width == 0 || height == 0 || rgba8.size() != size_t(width) * height * 4)
        throw std::invalid_argument("hemi: texture is " + std::to_string(rgba8.size()) + " bytes for " +
                                    std::to_string(width) + "x" + std::to_string(height) + " RGBA8");
    gpu::Image image = gpu::create_image(
        device, {width, height, srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM});
    gpu::upload_image(device, image, rgba8.data(), rgba8.size(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    return image;
}

} // namespace hemi::render
