#include "vulkan.h"

#include <stdexcept>
#include <string>

namespace engine
{

void check(VkResult r, const char* what)
{
    if (r != VK_SUCCESS)
        throw std::runtime_error(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
}

uint32_t Memory::type(uint32_t bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const
{
    uint32_t fallback = UINT32_MAX;
    for (uint32_t i = 0; i < properties.memoryTypeCount; ++i)
    {
        const VkMemoryPropertyFlags f = properties.memoryTypes[i].propertyFlags;
        if (!(bits & (1u << i)) || (f & required) != required)
            continue;
        if ((f & preferred) == preferred)
            return i;
        if (fallback == UINT32_MAX)
            fallback = i;
    }
    if (fallback == UINT32_MAX)
        throw std::runtime_error("engine: no memory type with the properties asked for");
    return fallback;
}

namespace
{
VkDeviceMemory allocate(VkDevice device, const Memory& memory, const VkMemoryRequirements& req,
                        VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred)
{
    VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    info.allocationSize = req.size;
    info.memoryTypeIndex = memory.type(req.memoryTypeBits, required, preferred);
    VkDeviceMemory m;
    check(vkAllocateMemory(device, &info, nullptr, &m), "vkAllocateMemory");
    return m;
}
} // namespace

Buffer create_buffer(VkDevice device, const Memory& memory, VkDeviceSize size, VkBufferUsageFlags usage,
                     bool host_cached)
{
    Buffer b;
    b.size = size;
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = size;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(vkCreateBuffer(device, &info, nullptr, &b.buffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, b.buffer, &req);
    b.memory = allocate(
        device, memory, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
        host_cached ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    check(vkBindBufferMemory(device, b.buffer, b.memory, 0), "vkBindBufferMemory");
    check(vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
    return b;
}

void destroy(VkDevice device, Buffer& b)
{
    if (b.buffer)
        vkDestroyBuffer(device, b.buffer, nullptr);
    if (b.memory)
        vkFreeMemory(device, b.memory, nullptr);
    b = {};
}

Image create_image(VkDevice device, const Memory& memory, VkExtent2D extent, VkFormat format,
                   VkImageUsageFlags usage)
{
    Image img;
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {extent.width, extent.height, 1};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    check(vkCreateImage(device, &info, nullptr, &img.image), "vkCreateImage");
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(device, img.image, &req);
    img.memory = allocate(device, memory, req, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    check(vkBindImageMemory(device, img.image, img.memory, 0), "vkBindImageMemory");
    const bool depth = format == VK_FORMAT_D32_SFLOAT || format == VK_FORMAT_D16_UNORM;
    VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view.image = img.image;
    view.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view.format = format;
    view.subresourceRange = {
        VkImageAspectFlags(depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT), 0, 1, 0, 1};
    check(vkCreateImageView(device, &view, nullptr, &img.view), "vkCreateImageView");
    return img;
}

void destroy(VkDevice device, Image& img)
{
    if (img.view)
        vkDestroyImageView(device, img.view, nullptr);
    if (img.image)
        vkDestroyImage(device, img.image, nullptr);
    if (img.memory)
        vkFreeMemory(device, img.memory, nullptr);
    img = {};
}

VkDescriptorSetLayout create_set_layout(VkDevice device,
                                        std::span<const VkDescriptorSetLayoutBinding> bindings)
{
    VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    info.bindingCount = uint32_t(bindings.size());
    info.pBindings = bindings.data();
    VkDescriptorSetLayout layout;
    check(vkCreateDescriptorSetLayout(device, &info, nullptr, &layout), "vkCreateDescriptorSetLayout");
    return layout;
}

VkPipelineLayout create_pipeline_layout(VkDevice device, std::span<const VkDescriptorSetLayout> sets,
                                        uint32_t push_size)
{
    const VkPushConstantRange push{VK_SHADER_STAGE_ALL, 0, push_size};
    VkPipelineLayoutCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    info.setLayoutCount = uint32_t(sets.size());
    info.pSetLayouts = sets.data();
    info.pushConstantRangeCount = push_size ? 1 : 0;
    info.pPushConstantRanges = &push;
    VkPipelineLayout layout;
    check(vkCreatePipelineLayout(device, &info, nullptr, &layout), "vkCreatePipelineLayout");
    return layout;
}

void write_image(VkDevice device, VkDescriptorSet set, uint32_t binding, VkSampler sampler, VkImageView view,
                 VkImageLayout layout)
{
    const VkDescriptorImageInfo image{sampler, view, layout};
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = binding;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = &image;
    vkUpdateDescriptorSets(device, 1, &w, 0, nullptr);
}

void write_texel_buffer(VkDevice device, VkDescriptorSet set, uint32_t binding, VkBufferView view)
{
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = binding;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    w.pTexelBufferView = &view;
    vkUpdateDescriptorSets(device, 1, &w, 0, nullptr);
}

VkPipeline create_pipeline(VkDevice device, const PipelineDesc& desc)
{
    auto module_of = [&](std::span<const uint32_t> code)
    {
        VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
        info.codeSize = code.size_bytes();
        info.pCode = code.data();
        VkShaderModule m;
        check(vkCreateShaderModule(device, &info, nullptr, &m), "vkCreateShaderModule");
        return m;
    };
    std::vector<VkSpecializationMapEntry> entries;
    for (uint32_t i = 0; i < desc.specialization.size(); ++i)
        entries.push_back({i, uint32_t(i * sizeof(uint32_t)), sizeof(uint32_t)});
    const VkSpecializationInfo spec{uint32_t(entries.size()), entries.data(),
                                    desc.specialization.size() * sizeof(uint32_t),
                                    desc.specialization.data()};
    VkPipelineShaderStageCreateInfo stages[2]{};
    const uint32_t stage_count = desc.fragment_shader.empty() ? 1 : 2;
    for (uint32_t i = 0; i < stage_count; ++i)
    {
        stages[i].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        stages[i].stage = i == 0 ? VK_SHADER_STAGE_VERTEX_BIT : VK_SHADER_STAGE_FRAGMENT_BIT;
        stages[i].module = module_of(i == 0 ? desc.vertex_shader : desc.fragment_shader);
        stages[i].pName = "main";
        stages[i].pSpecializationInfo = desc.specialization.empty() ? nullptr : &spec;
    }
    VkPipelineVertexInputStateCreateInfo vertex_input{
        VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    vertex_input.vertexBindingDescriptionCount = uint32_t(desc.bindings.size());
    vertex_input.pVertexBindingDescriptions = desc.bindings.data();
    vertex_input.vertexAttributeDescriptionCount = uint32_t(desc.attributes.size());
    vertex_input.pVertexAttributeDescriptions = desc.attributes.data();
    VkPipelineInputAssemblyStateCreateInfo assembly{
        VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewport.viewportCount = 1;
    viewport.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = desc.cull;
    raster.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    raster.lineWidth = 1.0f;
    if (desc.depth_bias_constant != 0.0f || desc.depth_bias_slope != 0.0f)
    {
        raster.depthBiasEnable = VK_TRUE;
        raster.depthBiasConstantFactor = desc.depth_bias_constant;
        raster.depthBiasSlopeFactor = desc.depth_bias_slope;
    }
    VkPipelineMultisampleStateCreateInfo multisample{
        VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    depth.depthTestEnable = desc.depth_test;
    depth.depthWriteEnable = desc.depth_write;
    depth.depthCompareOp = desc.depth_compare;
    std::vector<VkPipelineColorBlendAttachmentState> blend(desc.color_attachments);
    for (VkPipelineColorBlendAttachmentState& b : blend)
        b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                           VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo blend_state{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blend_state.attachmentCount = uint32_t(blend.size());
    blend_state.pAttachments = blend.data();
    const VkDynamicState dynamic_states[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamic_states;
    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.stageCount = stage_count;
    info.pStages = stages;
    info.pVertexInputState = &vertex_input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewport;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pDepthStencilState = &depth;
    info.pColorBlendState = &blend_state;
    info.pDynamicState = &dynamic;
    info.layout = desc.layout;
    info.renderPass = desc.render_pass;
    VkPipeline pipeline;
    const VkResult r = vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline);
    for (uint32_t i = 0; i < stage_count; ++i)
        vkDestroyShaderModule(device, stages[i].module, nullptr);
    check(r, "vkCreateGraphicsPipelines");
    return pipeline;
}

} // namespace engine
