#pragma once
// Compute and graphics programs from SPIR-V (embedded in the library, looked up by file name), with
// their descriptor-set layout and push-constant range, plus descriptor pools and writes.

#include <hemi/gpu/device.h>
#include <hemi/gpu/handle.h>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace hemi::gpu
{

// The SPIR-V of a shader in shaders/ by file name, e.g. "prt_transfer.comp". Throws when unknown.
std::span<const uint32_t> embedded_spirv(std::string_view name);
ShaderModule create_shader_module(const Device& device, std::span<const uint32_t> spirv);

struct Binding
{
    uint32_t binding = 0;
    VkDescriptorType type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    VkShaderStageFlags stages = VK_SHADER_STAGE_ALL;
    uint32_t count = 1;
};

// A descriptor-set layout of its own, for programs whose sets are shared (the material system's frame,
// material and coefficient-source sets).
DescriptorSetLayout create_set_layout(const Device& device, const std::vector<Binding>& bindings);

// A pipeline, its layout and one push-constant block visible to every stage. Programs made from `bindings`
// own their single set layout (set 0); programs made from shared `set_layouts` own none.
struct Program
{
    DescriptorSetLayout set_layout;
    PipelineLayout layout;
    Pipeline pipeline;
    VkPipelineBindPoint bind_point = VK_PIPELINE_BIND_POINT_COMPUTE;
    uint32_t push_constant_size = 0;
};

struct ComputeProgramDesc
{
    std::span<const uint32_t> shader;
    std::vector<Binding> bindings;
    uint32_t push_constant_size = 0;
    // Specialization constants: value i goes to constant_id i.
    std::vector<uint32_t> specialization;
};
Program create_compute_program(const Device& device, const ComputeProgramDesc& desc);

struct GraphicsProgramDesc
{
    std::span<const uint32_t> vertex_shader;
    std::span<const uint32_t> fragment_shader;      // empty: no fragment stage (a depth-only pass)
    std::vector<Binding> bindings;                  // set 0, owned by the program; or:
    std::vector<VkDescriptorSetLayout> set_layouts; // sets 0.. in order, owned by the caller (bindings empty)
    uint32_t push_constant_size = 0;
    std::vector<uint32_t> specialization; // shared by both stages
    std::vector<VkVertexInputBindingDescription> vertex_bindings;
    std::vector<VkVertexInputAttributeDescription> vertex_attributes;
    // Where the pipeline draws: a render pass and subpass, or, with render_pass null, dynamic rendering
    // (VK_KHR_dynamic_rendering; Device::dynamic_rendering()) into attachments of these formats.
    VkRenderPass render_pass = VK_NULL_HANDLE;
    uint32_t subpass = 0;
    uint32_t color_attachments = 1;
    std::vector<VkFormat> color_formats;         // dynamic rendering only; color_attachments is their count
    VkFormat depth_format = VK_FORMAT_UNDEFINED; // dynamic rendering only
    VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
    bool depth_test = true;
    bool depth_write = true;
    VkCompareOp depth_compare = VK_COMPARE_OP_LESS;
    VkCullModeFlags cull_mode = VK_CULL_MODE_BACK_BIT;
    VkFrontFace front_face = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    // Colour attachment 0 blends src alpha over (src a + dst (1 - a); alpha: a + dst alpha (1 - a)); the
    // others keep their values. Without blending every attachment is written, or none with colour_writes off.
    bool blend = false;
    bool color_writes = true;
    // Attachments from this index on keep their values (with the independentBlend feature; without it,
    // every attachment is written and blended alike, as Vulkan then requires).
    uint32_t written_color_attachments = ~0u;
    float depth_bias_constant = 0.0f, depth_bias_slope = 0.0f; // both 0: no depth bias
    VkPipelineCache cache = VK_NULL_HANDLE;                    // the host's pipeline cache, if any
};
// Viewport and scissor are dynamic state.
Program create_graphics_program(const Device& device, const GraphicsProgramDesc& desc);

// A descriptor pool sized for `max_sets` sets of the given bindings' types.
DescriptorPool create_descriptor_pool(const Device& device, const std::vector<Binding>& bindings,
                                      uint32_t max_sets);
VkDescriptorSet allocate_descriptor_set(const Device& device, VkDescriptorPool pool,
                                        VkDescriptorSetLayout layout);

// One descriptor write; fill exactly one of buffer / image / texel_view to match `type`.
struct DescriptorWrite
{
    uint32_t binding = 0;
    VkDescriptorType type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    VkDescriptorBufferInfo buffer{};
    VkDescriptorImageInfo image{};
    VkBufferView texel_view = VK_NULL_HANDLE;
};
void write_descriptors(const Device& device, VkDescriptorSet set, std::span<const DescriptorWrite> writes);

} // namespace hemi::gpu
