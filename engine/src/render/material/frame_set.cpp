#include "../refuse.h"

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
    : device_(&system.device()), max_instances_(max_instances)
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
    : device_(&system.device()), engine_data_(true), max_instances_(max_instances)
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

namespace
{
// FrameData's checks, reported as `call` through `device`.
bool pack_frame(const gpu::Device& device, const char* call, const FrameData& frame,
                shared::FrameUniforms& u) noexcept
{
    if (frame.lights.size() > HEMI_MAX_LIGHTS)
        return detail::refuse(device, call, "at most %d dynamic lights, got %zu", HEMI_MAX_LIGHTS,
                              frame.lights.size());
    if (!(frame.specular_exponent > 0.0f) || !std::isfinite(frame.specular_exponent) ||
        !std::isfinite(frame.specular_strength))
        return detail::refuse(device, call,
                              "the specular exponent and strength must be finite, the exponent > 0");
    if (!(frame.glossy_roughness >= 0.0f && frame.glossy_roughness <= 1.0f) ||
        !(frame.glossy_f0 >= 0.0f && frame.glossy_f0 <= 1.0f))
        return detail::refuse(device, call, "the glossy roughness and f0 must be in [0, 1], got %g and %g",
                              double(frame.glossy_roughness), double(frame.glossy_f0));
    for (int c = 0; c < 4; ++c)
        if (!std::isfinite(frame.view_projection[c].x + frame.view_projection[c].y +
                           frame.view_projection[c].z + frame.view_projection[c].w))
            return detail::refuse(device, call, "the view-projection matrix is not finite");
    if (!std::isfinite(frame.eye.x + frame.eye.y + frame.eye.z))
        return detail::refuse(device, call, "the eye position is not finite");
    for (size_t i = 0; i < frame.lights.size(); ++i)
    {
        const DynamicLight& l = frame.lights[i];
        const bool finite = std::isfinite(l.position.x + l.position.y + l.position.z) &&
                            std::isfinite(l.irradiance.x + l.irradiance.y + l.irradiance.z);
        if (!finite || (!l.point && !(glm::length(l.position) > 0.0f)))
            return detail::refuse(device, call, "dynamic light %zu is not finite or has no direction", i);
        if (!(l.range >= 0.0f) || !std::isfinite(l.range) ||
            (l.spot && (!l.point || !(glm::length(l.spot_direction) > 0.0f) ||
                        !std::isfinite(l.spot_direction.x + l.spot_direction.y + l.spot_direction.z) ||
                        !(l.inner_cone >= 0.0f && l.inner_cone < l.outer_cone &&
                          l.outer_cone <= float(M_PI / 2) + 1e-6f))))
            return detail::refuse(
                device, call,
                "dynamic light %zu: a range must be >= 0, a spot light a point light with a "
                "direction and 0 <= inner < outer <= pi/2",
                i);
        if (l.shadowmask_channel < -1 || l.shadowmask_channel > 3)
            return detail::refuse(device, call, "dynamic light %zu has shadowmask channel %d (0 to 3, or -1)",
                                  i, l.shadowmask_channel);
    }
    u = {};
    u.view_projection = frame.view_projection;
    u.options = glm::vec4(frame.lighting_only ? 1.0f : 0.0f, float(frame.lights.size()),
                          frame.specular_exponent, frame.specular_strength);
    u.eye = glm::vec4(frame.eye, 1.0f);
    u.glossy = glm::vec4(frame.glossy_roughness, frame.glossy_f0, 0.0f, 0.0f);
    for (size_t i = 0; i < frame.lights.size(); ++i)
    {
        const DynamicLight& l = frame.lights[i];
        u.light_position[i] =
            glm::vec4(l.point ? l.position : glm::normalize(l.position), l.point ? 1.0f : 0.0f);
        u.light_irradiance[i] = glm::vec4(l.irradiance, float(l.shadowmask_channel + 1));
        u.light_spot[i] =
            glm::vec4(l.spot ? glm::normalize(l.spot_direction) : glm::vec3(0.0f), l.point ? l.range : 0.0f);
        const float cos_outer = std::cos(l.outer_cone);
        u.light_cone[i] =
            glm::vec4(cos_outer, 1.0f / std::max(0.001f, std::cos(l.inner_cone) - cos_outer), 0.0f, 0.0f);
    }
    const auto& w = math::sep4_weights();
    for (int j = 0; j < 9; ++j)
        u.sep4_weights[j] = glm::vec4(w[j * 4], w[j * 4 + 1], w[j * 4 + 2], w[j * 4 + 3]);
    return true;
}
} // namespace

bool frame_uniforms(const MaterialSystem& system, const FrameData& frame, shared::FrameUniforms& out) noexcept
{
    shared::FrameUniforms u;
    if (!pack_frame(system.device(), "frame_uniforms", frame, u))
        return false;
    out = u;
    return true;
}

bool FrameSet::check_write(const char* call, uint32_t slot) const noexcept
{
    if (engine_data_)
        return detail::refuse(*device_, call,
                              "this frame set reads the engine's own buffers: write them there");
    if (slot >= sets_.size())
        return detail::refuse(*device_, call, "frame slot %u of a frame set made for %zu frame(s) in flight",
                              slot, sets_.size());
    return true;
}

bool FrameSet::write_instances(uint32_t slot, std::span<const shared::DrawPush> records,
                               uint32_t first) noexcept
{
    if (!check_write("FrameSet::write_instances", slot))
        return false;
    if (uint64_t(first) + records.size() > max_instances_)
        return detail::refuse(*device_, "FrameSet::write_instances",
                              "instance records [%u, %llu) past a frame set made for %u instances", first,
                              (unsigned long long)(first + records.size()), max_instances_);
    if (!records.empty())
        std::memcpy(static_cast<std::byte*>(instances_.mapped()) + slot * instance_stride_ +
                        first * sizeof(shared::DrawPush),
                    records.data(), records.size_bytes());
    return true;
}

VkDescriptorSet FrameSet::set(uint32_t slot) const noexcept
{
    if (slot >= sets_.size())
    {
        detail::refuse(*device_, "FrameSet::set",
                       "frame slot %u of a frame set made for %zu frame(s) in flight", slot, sets_.size());
        return VK_NULL_HANDLE;
    }
    return sets_[slot].get();
}

bool FrameSet::write(uint32_t slot, const FrameData& frame) noexcept
{
    shared::FrameUniforms u;
    if (!check_write("FrameSet::write", slot) || !pack_frame(*device_, "FrameSet::write", frame, u))
        return false;
    std::memcpy(static_cast<std::byte*>(uniforms_.mapped()) + slot * stride_, &u, sizeof u);
    return true;
}

bool FrameSet::record_update(VkCommandBuffer cmd, const FrameData& frame, uint32_t slot) const noexcept
{
    shared::FrameUniforms u;
    if (!check_write("FrameSet::record_update", slot) ||
        !pack_frame(*device_, "FrameSet::record_update", frame, u))
        return false;
    record_uniform_update(cmd, uniforms_, &u, sizeof u, slot * stride_);
    return true;
}

} // namespace hemi::render
