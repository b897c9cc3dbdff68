#include <hemi/math/separable_basis.h>
#include <hemi/render/prt_material.h>

#include "hemi/shared/prt_material.h"

#include <stdexcept>
#include <string>

namespace hemi::render
{

PrtMaterialRenderer::PrtMaterialRenderer(const gpu::Device& device, const SurfacePass& pass,
                                         const io::Mesh& mesh, const io::ImageRgba8& normal_map,
                                         const io::ImageRgba8* base_color, const math::BasisDesc& basis,
                                         const CoefficientSource& coefficients)
    : mesh_(device, mesh), normal_map_(upload_normal_map(device, normal_map.pixels, normal_map.width,
                                                         normal_map.height))
{
    const io::ImageRgba8 white{1, 1, {255, 255, 255, 255}};
    const io::ImageRgba8& albedo = base_color ? *base_color : white;
    base_color_ = upload_texture(device, albedo.pixels, albedo.width, albedo.height, true);
    if (coefficients.vertex_count() != mesh_.vertex_count())
        throw std::invalid_argument("hemi: transfer pass has " + std::to_string(coefficients.vertex_count()) +
                                    " vertices, the mesh " + std::to_string(mesh_.vertex_count()));
    if (int(coefficients.k()) != basis.size)
        throw std::invalid_argument("hemi: transfer pass has K = " + std::to_string(coefficients.k()) +
                                    ", basis " + std::string(basis.name) + " needs " + std::to_string(basis.size));
    sampler_ = gpu::create_sampler(device, {});
    const VkDeviceSize texels = VkDeviceSize(coefficients.vertex_count()) * coefficients.k();
    if (texels > device.limits().maxTexelBufferElements)
        throw std::invalid_argument("hemi: " + std::to_string(texels) + " coefficient texels exceed the device's "
                                    "maxTexelBufferElements");
    coefficient_view_ = gpu::create_buffer_view(device, coefficients.coefficients(), VK_FORMAT_R32G32B32A32_SFLOAT, 0,
                                                texels * 16);
    uniforms_ = gpu::create_buffer(device, {sizeof(shared::PrtMaterialUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});

    const VkShaderStageFlags graphics = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    std::vector<gpu::Binding> bindings = {
        {HEMI_PRT_MATERIAL_BINDING_UNIFORMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, graphics},
        {HEMI_PRT_MATERIAL_BINDING_NORMAL_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_FRAGMENT_BIT},
        {HEMI_PRT_MATERIAL_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, VK_SHADER_STAGE_VERTEX_BIT},
        {HEMI_PRT_MATERIAL_BINDING_BASE_COLOR, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_FRAGMENT_BIT},
    };
    program_ = create_surface_program(device, pass, "prt_material.vert",
                                      pass.color_attachments >= 2 ? "prt_material.frag" : "prt_material_color.frag", bindings,
                                      {uint32_t(basis.id), uint32_t(basis.size)});
    pool_ = gpu::create_descriptor_pool(device, bindings, 1);
    set_ = gpu::allocate_descriptor_set(device, pool_, program_.set_layout);
    gpu::DescriptorWrite writes[4];
    writes[0].binding = HEMI_PRT_MATERIAL_BINDING_UNIFORMS;
    writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    writes[0].buffer = {uniforms_, 0, VK_WHOLE_SIZE};
    writes[1].binding = HEMI_PRT_MATERIAL_BINDING_NORMAL_MAP;
    writes[1].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[1].image = {sampler_, normal_map_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    writes[2].binding = HEMI_PRT_MATERIAL_BINDING_COEFFICIENTS;
    writes[2].type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    writes[2].texel_view = coefficient_view_;
    writes[3].binding = HEMI_PRT_MATERIAL_BINDING_BASE_COLOR;
    writes[3].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[3].image = {sampler_, base_color_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    gpu::write_descriptors(device, set_, writes);
}

void PrtMaterialRenderer::update(VkCommandBuffer cmd, const PrtMaterialFrame& frame) const
{
    shared::PrtMaterialUniforms u{};
    u.view_projection = frame.view_projection;
    u.model = frame.model;
    u.albedo = glm::vec4(frame.albedo, frame.use_base_color ? 1.0f : 0.0f);
    const auto& w = math::sep4_weights();
    for (int j = 0; j < 9; ++j)
        u.sep4_weights[j] = glm::vec4(w[j * 4], w[j * 4 + 1], w[j * 4 + 2], w[j * 4 + 3]);
    record_uniform_update(cmd, uniforms_, &u, sizeof u);
}

void PrtMaterialRenderer::draw(VkCommandBuffer cmd) const
{
    draw_surface(cmd, program_, set_, mesh_);
}

} // namespace hemi::render
