#pragma once
// The engine sample's own Vulkan objects, made with its own code and its own memory (one allocation each: a
// real engine's allocator would serve them): buffers, images, pipelines and descriptor sets. hemi makes only
// what its models need; everything the engine draws with its own shaders, and the geometry every pass draws,
// is the engine's.
#include <volk.h>

#include <cstdint>
#include <span>
#include <vector>

namespace engine
{

// Throws std::runtime_error naming the call.
void check(VkResult r, const char* what);

// The device's memory types, and the one to use.
struct Memory
{
    VkPhysicalDeviceMemoryProperties properties{};
    // A type of `bits` with all of `required`, preferring one that also has `preferred`.
    uint32_t type(uint32_t bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const;
};

// Host-visible and coherent, device-local where the device has such memory; mapped for its lifetime.
struct Buffer
{
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
    VkDeviceSize size = 0;
};
Buffer create_buffer(VkDevice device, const Memory& memory, VkDeviceSize size, VkBufferUsageFlags usage,
                     bool host_cached = false);
void destroy(VkDevice device, Buffer& buffer);

// Device-local, optimal tiling, with a 2D view (depth aspect for depth formats).
struct Image
{
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
};
Image create_image(VkDevice device, const Memory& memory, VkExtent2D extent, VkFormat format,
                   VkImageUsageFlags usage);
void destroy(VkDevice device, Image& image);

VkDescriptorSetLayout create_set_layout(VkDevice device,
                                        std::span<const VkDescriptorSetLayoutBinding> bindings);
// Push constants of `push_size` bytes visible to every stage.
VkPipelineLayout create_pipeline_layout(VkDevice device, std::span<const VkDescriptorSetLayout> sets,
                                        uint32_t push_size);
void write_image(VkDevice device, VkDescriptorSet set, uint32_t binding, VkSampler sampler, VkImageView view,
                 VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
void write_texel_buffer(VkDevice device, VkDescriptorSet set, uint32_t binding, VkBufferView view);

// A graphics pipeline: triangle lists, dynamic viewport and scissor, counter-clockwise front faces,
// specialisation constant i = specialization[i] in both stages.
struct PipelineDesc
{
    std::span<const uint32_t> vertex_shader, fragment_shader; // no fragment shader: depth only
    std::vector<VkVertexInputBindingDescription> bindings;
    std::vector<VkVertexInputAttributeDescription> attributes;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    VkRenderPass render_pass = VK_NULL_HANDLE;
    uint32_t color_attachments = 1;
    bool depth_test = true, depth_write = true;
    VkCompareOp depth_compare = VK_COMPARE_OP_LESS;
    float depth_bias_constant = 0.0f, depth_bias_slope = 0.0f; // both 0: no bias
    VkCullModeFlags cull = VK_CULL_MODE_BACK_BIT;
    std::vector<uint32_t> specialization;
};
VkPipeline create_pipeline(VkDevice device, const PipelineDesc& desc);

} // namespace engine
