#include <hemi/gpu/commands.h>
#include <hemi/math/separable_basis.h>
#include <hemi/render/material/frame_set.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::render
{

void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& buffer, const void* data, size_t size,
                           VkDeviceSize offset, VkAccessFlags read_access)
{
    const VkPipelineStageFlags shaders =
        VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT;
    gpu::memory_barrier(cmd, shaders, read_access, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_ACCESS_TRANSFER_WRITE_BIT);
    vkCmdUpdateBuffer(cmd, buffer, offset, size, data);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, shaders,
                        read_access);
}

FrameSet::FrameSet(const MaterialSystem& system, uint32_t frames_in_flight, uint32_t max_instances)
    : max_instances_(max_instances)
{
    const gpu::Device& device = system.device();
    if (frames_in_flight == 0)
        throw std::invalid_argument("hemi: a frame set needs at least one frame in flight");
    const VkDeviceSize align = std::max<VkDeviceSize>(1, device.limits().minUniformBufferOffsetAlignment);
    stride_ = (sizeof(shared::FrameUniforms) + align - 1) / align * align;
    uniforms_ = gpu::create_buffer(
        device, {stride_ * frames_in_flight, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, gpu::MemoryUsage::Dynamic});
    device.set_name(VK_OBJECT_TYPE_BUFFER, uniforms_.handle(), "hemi frame uniforms");
    // Instance records (one at least: the binding is always there, read only by instanced draws).
    const VkDeviceSize storage_align =
        std::max<VkDeviceSize>(1, device.limits().minStorageBufferOffsetAlignment);
    const VkDeviceSize records = std::max<uint32_t>(1, max_instances) * sizeof(shared::DrawPush);
    instance_stride_ = (records + storage_align - 1) / storage_align * storage_align;
    instances_ = gpu::create_buffer(device, {instance_stride_ * frames_in_flight,
                                             VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, gpu::MemoryUsage::Dynamic});
    device.set_name(VK_OBJECT_TYPE_BUFFER, instances_.handle(), "hemi frame instances");
    std::vector<gpu::BufferRange> uniform_ranges, instance_ranges;
    for (uint32_t slot = 0; slot < frames_in_flight; ++slot)
    {
        uniform_ranges.push_back({uniforms_.handle(), slot * stride_, sizeof(shared::FrameUniforms)});
        instance_ranges.push_back({instances_.handle(), slot * instance_stride_, records});
    }
    make_sets(system, uniform_ranges, instance_ranges);
}

FrameSet::FrameSet(const MaterialSystem& system, std::span<const gpu::BufferRange> uniforms,
                   std::span<const gpu::BufferRange> instances, uint32_t max_instances)
    : engine_data_(true), max_instances_(max_instances)
{
    const gpu::Device& device = system.device();
    if (uniforms.empty())
        throw std::invalid_argument(
            "hemi: a frame set over the engine's data needs one uniform range per slot");
    if (!instances.empty() && instances.size() != uniforms.size())
        throw std::invalid_argument("hemi: " + std::to_string(instances.size()) + " instance ranges for " +
                                    std::to_string(uniforms.size()) + " frame slots");
    const VkDeviceSize align = std::max<VkDeviceSize>(1, device.limits().minUniformBufferOffsetAlignment);
    const VkDeviceSize storage_align =
        std::max<VkDeviceSize>(1, device.limits().minStorageBufferOffsetAlignment);
    const VkDeviceSize records = std::max<uint32_t>(1, max_instances) * sizeof(shared::DrawPush);
    for (size_t slot = 0; slot < uniforms.size(); ++slot)
    {
        const gpu::BufferRange& u = uniforms[slot];
        if (u.buffer == VK_NULL_HANDLE || u.size < sizeof(shared::FrameUniforms) || u.offset % align != 0)
            throw std::invalid_argument("hemi: frame slot " + std::to_string(slot) + "'s uniform range (" +
                                        std::to_string(u.size) + " bytes at " + std::to_string(u.offset) +
                                        ") must hold a FrameUniforms of " +
                                        std::to_string(sizeof(shared::FrameUniforms)) +
                                        " bytes at a multiple of " + std::to_string(align));
        if (!instances.empty() &&
            (instances[slot].buffer == VK_NULL_HANDLE || instances[slot].size < records ||
             instances[slot].offset % storage_align != 0))
            throw std::invalid_argument("hemi: frame slot " + std::to_string(slot) +
                                        "'s instance range must hold " + std::to_string(records) +
                                        " bytes at a multiple of " + std::to_string(storage_align));
    }
    std::vector<gpu::BufferRange> instance_ranges(instances.begin(), instances.end());
    if (instance_ranges.empty())
    {
        instances_ = gpu::create_buffer(device, {records, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        device.set_name(VK_OBJECT_TYPE_BUFFER, instances_.handle(), "hemi frame instances (unused)");
        instance_ranges.assign(uniforms.size(), gpu::BufferRange{instances_.handle(), 0, records});
    }
    make_sets(system, uniforms, instance_ranges);
}

void FrameSet::make_sets(const MaterialSystem& system, std::span<const gpu::BufferRange> uniforms,
                         std::span<const gpu::BufferRange> instances)
{
    const auto bindings = MaterialSystem::frame_bindings();
    for (size_t slot = 0; slot < uniforms.size(); ++slot)
    {
        sets_.push_back(system.descriptors().allocate(system.frame_layout(), bindings));
        gpu::DescriptorWrite writes[2];
        writes[0].binding = HEMI_FRAME_BINDING_UNIFORMS;
        writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        writes[0].buffer = {uniforms[slot].buffer, uniforms[slot].offset, sizeof(shared::FrameUniforms)};
        writes[1].binding = HEMI_FRAME_BINDING_INSTANCES;
        writes[1].type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[1].buffer = {instances[slot].buffer, instances[slot].offset, instances[slot].size};
        gpu::write_descriptors(system.device(), sets_.back(), writes);
    }
}

VkDeviceSize FrameSet::slot_offset(uint32_t slot) const
{
    if (slot >= sets_.size())
        throw std::invalid_argument("hemi: frame slot " + std::to_string(slot) + " of a frame set made for " +
                                    std::to_string(sets_.size()) + " frame(s) in flight");
    return slot * stride_;
}

void FrameSet::write_instances(uint32_t slot, std::span<const shared::DrawPush> records, uint32_t first)
{
    if (engine_data_)
        throw std::logic_error("hemi: this frame set reads the engine's instance records: write them there");
    (void)slot_offset(slot);
    if (uint64_t(first) + records.size() > max_instances_)
        throw std::invalid_argument("hemi: instance records [" + std::to_string(first) + ", +" +
                                    std::to_string(records.size()) + ") past a frame set made for " +
                                    std::to_string(max_instances_) + " instances");
    if (records.empty())
        return;
    std::memcpy(static_cast<std::byte*>(instances_.mapped()) + slot * instance_stride_ +
                    first * sizeof(shared::DrawPush),
                records.data(), records.size_bytes());
}

VkDescriptorSet FrameSet::set(uint32_t slot) const
{
    (void)slot_offset(slot);
    return sets_[slot].get();
}

shared::FrameUniforms frame_uniforms(const FrameData& frame)
{
    shared::FrameUniforms u{};
    u.view_projection = frame.view_projection;
    if (frame.lights.size() > HEMI_MAX_LIGHTS)
        throw std::invalid_argument("hemi: at most " + std::to_string(HEMI_MAX_LIGHTS) +
                                    " dynamic lights, got " + std::to_string(frame.lights.size()));
    if (!(frame.specular_exponent > 0.0f) || !std::isfinite(frame.specular_exponent) ||
        !std::isfinite(frame.specular_strength))
        throw std::invalid_argument(
            "hemi: the specular exponent and strength must be finite, the exponent > 0");
    u.options = glm::vec4(frame.lighting_only ? 1.0f : 0.0f, float(frame.lights.size()),
                          frame.specular_exponent, frame.specular_strength);
    u.eye = glm::vec4(frame.eye, 1.0f);
    for (size_t i = 0; i < frame.lights.size(); ++i)
    {
        const DynamicLight& l = frame.lights[i];
        const bool finite = std::isfinite(l.position.x + l.position.y + l.position.z) &&
                            std::isfinite(l.irradiance.x + l.irradiance.y + l.irradiance.z);
        if (!finite || (!l.point && !(glm::length(l.position) > 0.0f)))
            throw std::invalid_argument("hemi: dynamic light " + std::to_string(i) +
                                        " is not finite or has no direction");
        u.light_position[i] =
            glm::vec4(l.point ? l.position : glm::normalize(l.position), l.point ? 1.0f : 0.0f);
        u.light_irradiance[i] = glm::vec4(l.irradiance, 0.0f);
    }
    const auto& w = math::sep4_weights();
    for (int j = 0; j < 9; ++j)
        u.sep4_weights[j] = glm::vec4(w[j * 4], w[j * 4 + 1], w[j * 4 + 2], w[j * 4 + 3]);
    return u;
}

void FrameSet::write(uint32_t slot, const FrameData& frame)
{
    if (engine_data_)
        throw std::logic_error("hemi: this frame set reads the engine's view data: write it there");
    const shared::FrameUniforms u = frame_uniforms(frame);
    std::memcpy(static_cast<std::byte*>(uniforms_.mapped()) + slot_offset(slot), &u, sizeof u);
}

void FrameSet::record_update(VkCommandBuffer cmd, const FrameData& frame, uint32_t slot) const
{
    if (engine_data_)
        throw std::logic_error("hemi: this frame set reads the engine's view data: write it there");
    const shared::FrameUniforms u = frame_uniforms(frame);
    record_uniform_update(cmd, uniforms_, &u, sizeof u, slot_offset(slot));
}

} // namespace hemi::render
