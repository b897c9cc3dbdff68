#include <hemi/render/sh_normalmap.h>

#include "hemi/shared/sh_normalmap.h"

#include <glm/gtc/matrix_transform.hpp>

namespace hemi::render
{

ShNormalMapRenderer::ShNormalMapRenderer(const gpu::Device& device, const OffscreenTarget& target,
                                         const io::Mesh& mesh, std::span<const uint8_t> normal_map,
                                         uint32_t map_width, uint32_t map_height)
    : mesh_(device, mesh), normal_map_(upload_normal_map(device, normal_map, map_width, map_height))
{
    uniforms_ = gpu::create_buffer(device, {sizeof(shared::ShNormalMapUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});

    sampler_ = gpu::create_sampler(device, {});

    const VkShaderStageFlags graphics = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    std::vector<gpu::Binding> bindings = {
        {HEMI_SH_NORMALMAP_BINDING_UNIFORMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, graphics},
        {HEMI_SH_NORMALMAP_BINDING_NORMAL_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_FRAGMENT_BIT},
    };
    program_ = create_surface_program(device, surface_pass(target), "sh_normalmap.vert", "sh_normalmap.frag", bindings);

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
    record_uniform_update(cmd, uniforms_, &u, sizeof u);
}

void ShNormalMapRenderer::draw(VkCommandBuffer cmd) const
{
    draw_surface(cmd, program_, set_, mesh_);
}

glm::mat4 look_at_projection(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees, float aspect)
{
    glm::mat4 view = glm::lookAt(eye, target, glm::vec3(0.0f, 0.0f, 1.0f));
    glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(fov_y_degrees), aspect, 0.05f, 100.0f);
    proj[1][1] *= -1.0f; // Vulkan clip space: y down
    return proj * view;
}

} // namespace hemi::render
