#include <hemi/render/sh_normalmap.h>

#include "hemi/shared/sh_normalmap.h"

#include <glm/gtc/matrix_transform.hpp>

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

ShNormalMapRenderer::ShNormalMapRenderer(const gpu::Device& device, const OffscreenTarget& target,
                                         const io::Mesh& mesh, std::span<const uint8_t> normal_map,
                                         uint32_t map_width, uint32_t map_height)
{
    const size_t n = mesh.positions.size();
    if (n == 0 || mesh.indices.empty() || mesh.indices.size() % 3 != 0)
        throw std::invalid_argument("hemi: ShNormalMapRenderer needs a non-empty triangle list");
    if (mesh.normals.size() != n || mesh.tangents.size() != n || mesh.uvs.size() != n)
        throw std::invalid_argument("hemi: ShNormalMapRenderer needs a normal, tangent and UV per vertex");
    for (uint32_t i : mesh.indices)
        if (i >= n)
            throw std::invalid_argument("hemi: mesh index " + std::to_string(i) + " out of range (" +
                                        std::to_string(n) + " vertices)");
    if (normal_map.size() != size_t(map_width) * map_height * 4 || map_width == 0 || map_height == 0)
        throw std::invalid_argument("hemi: normal map is " + std::to_string(normal_map.size()) + " bytes for " +
                                    std::to_string(map_width) + "x" + std::to_string(map_height) + " RGBA8");

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
    index_count_ = uint32_t(mesh.indices.size());
    uniforms_ = gpu::create_buffer(device, {sizeof(shared::ShNormalMapUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});

    normal_map_ = gpu::create_image(device, {map_width, map_height, VK_FORMAT_R8G8B8A8_UNORM});
    gpu::upload_image(device, normal_map_, normal_map.data(), normal_map.size(),
                      VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    sampler_ = gpu::create_sampler(device, {});

    const VkShaderStageFlags graphics = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    std::vector<gpu::Binding> bindings = {
        {HEMI_SH_NORMALMAP_BINDING_UNIFORMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, graphics},
        {HEMI_SH_NORMALMAP_BINDING_NORMAL_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_FRAGMENT_BIT},
    };
    gpu::GraphicsProgramDesc desc;
    desc.vertex_shader = gpu::embedded_spirv("sh_normalmap.vert");
    desc.fragment_shader = gpu::embedded_spirv("sh_normalmap.frag");
    desc.bindings = bindings;
    desc.vertex_bindings = {{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX}};
    desc.vertex_attributes = {
        {0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)},
        {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, normal)},
        {2, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(Vertex, tangent)},
        {3, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(Vertex, uv)},
    };
    desc.render_pass = target.render_pass();
    desc.color_attachments = OffscreenTarget::kColorAttachments;
    desc.cull_mode = VK_CULL_MODE_BACK_BIT;
    // Meshes are counter-clockwise seen from outside; look_at_projection flips y for Vulkan's clip space,
    // and Vulkan's facing rule (its area formula is negated for y-down framebuffers) keeps them CCW.
    desc.front_face = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    program_ = gpu::create_graphics_program(device, desc);

    pool_ = gpu::create_descriptor_pool(device, bindings, 1);
    set_ = gpu::allocate_descriptor_set(device, pool_, program_.set_layout);
    gpu::DescriptorWrite writes[2];
    writes[0].binding = HEMI_SH_NORMALMAP_BINDING_UNIFORMS;
    writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    writes[0].buffer = {uniforms_, 0, VK_WHOLE_SIZE};
    writes[1].binding = HEMI_SH_NORMALMAP_BINDING_NORMAL_MAP;
    writes[1].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[1].image = {sampler_, normal_map_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    gpu::write_descriptors(device, set_, writes);
}

void ShNormalMapRenderer::update(VkCommandBuffer cmd, const ShNormalMapFrame& frame) const
{
    shared::ShNormalMapUniforms u{};
    u.view_projection = frame.view_projection;
    u.model = frame.model;
    u.albedo = glm::vec4(frame.albedo, 0.0f);
    for (int i = 0; i < 9; ++i)
        u.irradiance[i] = glm::vec4(frame.irradiance[i], 0.0f);
    vkCmdUpdateBuffer(cmd, uniforms_, 0, sizeof u, &u);
}

void ShNormalMapRenderer::draw(VkCommandBuffer cmd) const
{
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program_.pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program_.layout, 0, 1, &set_, 0, nullptr);
    VkBuffer vb = vertices_;
    VkDeviceSize offset = 0;
    vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
    vkCmdBindIndexBuffer(cmd, indices_, 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cmd, index_count_, 1, 0, 0, 0);
}

glm::mat4 look_at_projection(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees, float aspect)
{
    glm::mat4 view = glm::lookAt(eye, target, glm::vec3(0.0f, 0.0f, 1.0f));
    glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(fov_y_degrees), aspect, 0.05f, 100.0f);
    proj[1][1] *= -1.0f; // Vulkan clip space: y down
    return proj * view;
}

} // namespace hemi::render
