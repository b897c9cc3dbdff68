// Sorted draw packets (draw_queue.h).
#include "../refuse.h"

#include <hemi/render/scene/draw_queue.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::render
{
namespace
{
// 12 bits of a handle, mixed (splitmix64's finaliser), so that nearby handles spread.
uint64_t hash12(VkDescriptorSet set)
{
    uint64_t x = uint64_t(reinterpret_cast<uintptr_t>(set));
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    x ^= x >> 31;
    return x & 0xfffu;
}
} // namespace

uint64_t draw_key(uint32_t layer, const MaterialType& type, VkDescriptorSet material, VkDescriptorSet source,
                  float depth) noexcept
{
    const float d = std::isfinite(depth) ? std::clamp(depth, 0.0f, 1.0f) : 1.0f;
    const uint64_t depth16 = uint64_t(std::lround(d * 65535.0f));
    return uint64_t(layer & 0xffu) << 56 | uint64_t(type.id & 0xffffu) << 40 | hash12(material) << 28 |
           hash12(source) << 16 | depth16;
}

DrawStats record_packets(VkCommandBuffer cmd, std::span<const DrawPacket> packets) noexcept
{
    DrawStats stats;
    // Every packet is checked before the first is recorded: a refused list records nothing.
    const gpu::Device* device = nullptr;
    size_t first_bad = packets.size();
    for (size_t i = 0; i < packets.size(); ++i)
    {
        const DrawPacket& p = packets[i];
        if (p.type && !device)
            device = p.type->device;
        if (!p.type || !p.frame || !p.material || !p.source || !p.mesh)
        {
            first_bad = std::min(first_bad, i);
            ++stats.refused;
        }
    }
    if (stats.refused)
    {
        if (device)
        {
            const DrawPacket& p = packets[first_bad];
            detail::refuse(*device, "record_packets",
                           "%llu of %zu packets lack a material type, a descriptor set or a mesh (released, "
                           "or never set); the first is packet %zu (type %s, frame %s, material %s, source "
                           "%s, mesh %s): nothing recorded",
                           (unsigned long long)stats.refused, packets.size(), first_bad,
                           p.type ? "set" : "null", p.frame ? "set" : "null", p.material ? "set" : "null",
                           p.source ? "set" : "null", p.mesh ? "set" : "null");
        }
        return stats;
    }
    const MaterialType* type = nullptr;
    VkDescriptorSet bound[3] = {VK_NULL_HANDLE, VK_NULL_HANDLE, VK_NULL_HANDLE};
    const MeshBinding* mesh = nullptr;
    for (const DrawPacket& p : packets)
    {
        const gpu::Program& program = p.type->program;
        const VkDescriptorSet sets[3] = {p.frame, p.material, p.source};
        uint32_t first = 0;
        if (p.type != type)
        {
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
            ++stats.pipeline_binds;
            // A different type may have a different pipeline layout: bind every set again.
            type = p.type;
        }
        else
            while (first < 3 && sets[first] == bound[first])
                ++first;
        if (first < 3)
        {
            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, first, 3 - first,
                                    sets + first, 0, nullptr);
            ++stats.descriptor_set_binds;
            std::copy(sets, sets + 3, bound);
        }
        vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof p.push, &p.push);
        if (p.mesh != mesh)
        {
            p.mesh->bind(cmd);
            ++stats.mesh_binds;
            mesh = p.mesh;
        }
        vkCmdDrawIndexed(cmd, p.index_count, p.instance_count, p.first_index, p.vertex_offset,
                         p.first_instance);
        ++stats.draws;
        stats.instances += p.instance_count;
    }
    return stats;
}

void make_instanced(DrawPacket& packet, uint32_t first, uint32_t count) noexcept
{
    packet.push.instanced = 1;
    packet.instance_count = count;
    packet.first_instance = first;
}

void DrawQueue::sort()
{
    // By (key, position): a total order, so std::sort (which allocates nothing, unlike std::stable_sort's
    // temporary buffer) keeps equal keys in the order they were added. The scratch arrays keep their
    // capacity from frame to frame.
    const size_t n = packets_.size();
    order_.resize(n);
    for (size_t i = 0; i < n; ++i)
        order_[i] = {packets_[i].key, uint32_t(i)};
    std::sort(order_.begin(), order_.end());
    scratch_.resize(n);
    for (size_t i = 0; i < n; ++i)
        scratch_[i] = packets_[order_[i].second];
    packets_.swap(scratch_);
}

} // namespace hemi::render
