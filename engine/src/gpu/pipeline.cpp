#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/vk_check.h>

#include <map>
#include <stdexcept>
#include <string>

namespace hemi::shaders::detail
{
struct EmbeddedShader
{
    std::string_view name;
    const uint32_t* code;
    size_t words;
};
extern const EmbeddedShader kEmbeddedShaders[];
extern const size_t kEmbeddedShadersCount;
} // namespace hemi::shaders::detail

namespace hemi::gpu
{

std::span<const uint32_t> embedded_spirv(std::string_view name)
{
    using namespace hemi::shaders::detail;
    for (size_t i = 0; i < kEmbeddedShadersCount; ++i)
        if (kEmbeddedShaders[i].name == name)
            return {kEmbeddedShaders[i].code, kEmbeddedShaders[i].words};
    throw std::invalid_argument("hemi: no embedded shader named '" + std::string(name) + "'");
}

ShaderModule create_shader_module(const Device& device, std::span<const uint32_t> spirv)
{
    if (spirv.empty())
        throw std::invalid_argument("hemi: empty SPIR-V");
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = spirv.size_bytes();
    info.pCode = spirv.data();
    VkShaderModule module;
    HEMI_VK_CHECK(vkCreateShaderModule(device.device(), &info, nullptr, &module));
    device.set_name(VK_OBJECT_TYPE_SHADER_MODULE, module, "hemi shader module");
    return ShaderModule(device.device(), module);
}

DescriptorSetLayout create_set_layout(const Device& device, const std::vector<Binding>& bindings)
{
    std::vector<VkDescriptorSetLayoutBinding> vk_bindings;
    for (const Binding& b : bindings)
        vk_bindings.push_back({b.binding, b.type, b.count, b.stages, nullptr});
    VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    set_info.bindingCount = uint32_t(vk_bindings.size());
    set_info.pBindings = vk_bindings.data();
    VkDescriptorSetLayout set_layout;
    HEMI_VK_CHECK(vkCreateDescriptorSetLayout(device.device(), &set_info, nullptr, &set_layout));
    device.set_name(VK_OBJECT_TYPE_DESCRIPTOR_SET_LAYOUT, set_layout,
                    "hemi descriptor set layout of " + std::to_string(bindings.size()) + " bindings");
    return DescriptorSetLayout(device.device(), set_layout);
}

namespace
{

void create_layouts(const Device& device, const std::vector<Binding>& bindings,
                    std::vector<VkDescriptorSetLayout> shared_layouts, uint32_t push_size, Program& p)
{
    VkDevice d = device.device();
    if (shared_layouts.empty())
    {
        p.set_layout = create_set_layout(device, bindings);
        shared_layouts.push_back(p.set_layout);
    }
    else if (!bindings.empty())
        throw std::invalid_argument("hemi: a program takes either bindings or shared set layouts, not both");

    VkPushConstantRange range{VK_SHADER_STAGE_ALL, 0, push_size};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = uint32_t(shared_layouts.size());
    layout_info.pSetLayouts = shared_layouts.data();
    layout_info.pushConstantRangeCount = push_size ? 1 : 0;
    layout_info.pPushConstantRanges = &range;
    VkPipelineLayout layout;
    HEMI_VK_CHECK(vkCreatePipelineLayout(d, &layout_info, nullptr, &layout));
    p.layout = PipelineLayout(d, layout);
    device.set_name(VK_OBJECT_TYPE_PIPELINE_LAYOUT, layout, "hemi pipeline layout");
    p.push_constant_size = push_size;
}

struct Specialization
{
    std::vector<VkSpecializationMapEntry> entries;
    VkSpecializationInfo info{};
    explicit Specialization(const std::vector<uint32_t>& values)
    {
        for (uint32_t i = 0; i < values.size(); ++i)
            entries.push_back({i, uint32_t(i * sizeof(uint32_t)), sizeof(uint32_t)});
        info.mapEntryCount = uint32_t(entries.size());
        info.pMapEntries = entries.data();
        info.dataSize = values.size() * sizeof(uint32_t);
        info.pData = values.data();
    }
};

} // namespace

Program create_compute_program(const Device& device, const ComputeProgramDesc& desc)
{
    Program p;
    p.bind_point = VK_PIPELINE_BIND_POINT_COMPUTE;
    create_layouts(device, desc.bindings, {}, desc.push_constant_size, p);
    ShaderModule module = create_shader_module(device, desc.shader);
    Specialization spec(desc.specialization);

    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.stage.pSpecializationInfo = desc.specialization.empty() ? nullptr : &spec.info;
    info.layout = p.layout;
    VkPipeline pipeline;
    HEMI_VK_CHECK(vkCreateComputePipelines(device.device(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline));
    p.pipeline = Pipeline(device.device(), pipeline);
    device.set_name(VK_OBJECT_TYPE_PIPELINE, pipeline, "hemi compute pipeline");
    return p;
}

Program create_graphics_program(const Device& device, const GraphicsProgramDesc& desc)
{
    const bool dynamic_rendering = desc.render_pass == VK_NULL_HANDLE;
    if (dynamic_rendering && !device.dynamic_rendering())
        throw std::invalid_argument(
            "hemi: a pipeline without a render pass needs dynamic rendering, which device " +
            std::string(device.name()) + " does not have enabled");
    if (dynamic_rendering && desc.color_formats.size() != desc.color_attachments)
        throw std::invalid_argument("hemi: dynamic rendering needs one colour format per colour attachment");
    Program p;
    p.bind_point = VK_PIPELINE_BIND_POINT_GRAPHICS;
    create_layouts(device, desc.bindings, desc.set_layouts, desc.push_constant_size, p);
    ShaderModule vs = create_shader_module(device, desc.vertex_shader);
    ShaderModule fs;
    if (!desc.fragment_shader.empty())
        fs = create_shader_module(device, desc.fragment_shader);
    Specialization spec(desc.specialization);

    VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                                 {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vs;
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = fs;
    stages[1].pName = "main";
    for (auto& s : stages)
        s.pSpecializationInfo = desc.specialization.empty() ? nullptr : &spec.info;

    VkPipelineVertexInputStateCreateInfo vertex_input{
        VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    vertex_input.vertexBindingDescriptionCount = uint32_t(desc.vertex_bindings.size());
    vertex_input.pVertexBindingDescriptions = desc.vertex_bindings.data();
    vertex_input.vertexAttributeDescriptionCount = uint32_t(desc.vertex_attributes.size());
    vertex_input.pVertexAttributeDescriptions = desc.vertex_attributes.data();

    VkPipelineInputAssemblyStateCreateInfo assembly{
        VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;

    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewport.viewportCount = 1;
    viewport.scissorCount = 1;

    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = desc.cull_mode;
    raster.frontFace = desc.front_face;
    raster.lineWidth = 1.0f;
    if (desc.depth_bias_constant != 0.0f || desc.depth_bias_slope != 0.0f)
    {
        raster.depthBiasEnable = VK_TRUE;
        raster.depthBiasConstantFactor = desc.depth_bias_constant;
        raster.depthBiasSlopeFactor = desc.depth_bias_slope;
    }

    VkPipelineMultisampleStateCreateInfo multisample{
        VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = desc.samples;

    VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    depth.depthTestEnable = desc.depth_test;
    depth.depthWriteEnable = desc.depth_test && desc.depth_write;
    depth.depthCompareOp = desc.depth_compare;

    std::vector<VkPipelineColorBlendAttachmentState> blend(desc.color_attachments);
    for (size_t i = 0; i < blend.size(); ++i)
    {
        VkPipelineColorBlendAttachmentState& b = blend[i];
        // Without independentBlend every attachment needs the same state: all written, all blended.
        const bool independent = device.independent_blend();
        if (desc.color_writes && (i < desc.written_color_attachments || !independent))
            b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                               VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        if (desc.blend && (i == 0 || !independent))
        {
            b.blendEnable = VK_TRUE;
            b.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
            b.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
            b.colorBlendOp = VK_BLEND_OP_ADD;
            b.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
            b.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
            b.alphaBlendOp = VK_BLEND_OP_ADD;
        }
    }
    VkPipelineColorBlendStateCreateInfo blend_state{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blend_state.attachmentCount = uint32_t(blend.size());
    blend_state.pAttachments = blend.data();

    VkDynamicState dynamic_states[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamic_states;

    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.stageCount = desc.fragment_shader.empty() ? 1 : 2;
    info.pStages = stages;
    info.pVertexInputState = &vertex_input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewport;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pDepthStencilState = &depth;
    info.pColorBlendState = &blend_state;
    info.pDynamicState = &dynamic;
    info.layout = p.layout;
    info.renderPass = desc.render_pass;
    info.subpass = desc.subpass;
    VkPipelineRenderingCreateInfoKHR rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO_KHR};
    if (dynamic_rendering)
    {
        rendering.colorAttachmentCount = uint32_t(desc.color_formats.size());
        rendering.pColorAttachmentFormats = desc.color_formats.data();
        rendering.depthAttachmentFormat = desc.depth_format;
        info.pNext = &rendering;
        info.subpass = 0;
    }
    VkPipeline pipeline;
    HEMI_VK_CHECK(vkCreateGraphicsPipelines(device.device(), desc.cache, 1, &info, nullptr, &pipeline));
    p.pipeline = Pipeline(device.device(), pipeline);
    device.set_name(VK_OBJECT_TYPE_PIPELINE, pipeline, "hemi graphics pipeline");
    return p;
}

DescriptorPool create_descriptor_pool(const Device& device, const std::vector<Binding>& bindings,
                                      uint32_t max_sets)
{
    std::map<VkDescriptorType, uint32_t> counts;
    for (const Binding& b : bindings)
        counts[b.type] += b.count * max_sets;
    std::vector<VkDescriptorPoolSize> sizes;
    for (auto [type, count] : counts)
        sizes.push_back({type, count});
    VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    info.maxSets = max_sets;
    info.poolSizeCount = uint32_t(sizes.size());
    info.pPoolSizes = sizes.data();
    VkDescriptorPool pool;
    HEMI_VK_CHECK(vkCreateDescriptorPool(device.device(), &info, nullptr, &pool));
    device.set_name(VK_OBJECT_TYPE_DESCRIPTOR_POOL, pool,
                    "hemi descriptor pool of " + std::to_string(max_sets) + " sets");
    return DescriptorPool(device.device(), pool);
}

VkDescriptorSet allocate_descriptor_set(const Device& device, VkDescriptorPool pool,
                                        VkDescriptorSetLayout layout)
{
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = pool;
    info.descriptorSetCount = 1;
    info.pSetLayouts = &layout;
    VkDescriptorSet set;
    HEMI_VK_CHECK(vkAllocateDescriptorSets(device.device(), &info, &set));
    device.set_name(VK_OBJECT_TYPE_DESCRIPTOR_SET, set, "hemi descriptor set");
    return set;
}

void write_descriptors(const Device& device, VkDescriptorSet set, std::span<const DescriptorWrite> writes)
{
    std::vector<VkWriteDescriptorSet> vk(writes.size());
    for (size_t i = 0; i < writes.size(); ++i)
    {
        const DescriptorWrite& w = writes[i];
        VkWriteDescriptorSet& v = vk[i];
        v = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        v.dstSet = set;
        v.dstBinding = w.binding;
        v.descriptorCount = 1;
        v.descriptorType = w.type;
        switch (w.type)
        {
        case VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER:
        case VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER:
            v.pTexelBufferView = &w.texel_view;
            break;
        case VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER:
        case VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE:
        case VK_DESCRIPTOR_TYPE_STORAGE_IMAGE:
        case VK_DESCRIPTOR_TYPE_SAMPLER:
            v.pImageInfo = &w.image;
            break;
        default:
            v.pBufferInfo = &w.buffer;
            break;
        }
    }
    vkUpdateDescriptorSets(device.device(), uint32_t(vk.size()), vk.data(), 0, nullptr);
}

} // namespace hemi::gpu
