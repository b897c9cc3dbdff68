// Sorted draw packets (draw_queue.h).
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
                  float depth)
{
    if (layer > 0xffu)
        throw std::invalid_argument("hemi: draw key layer " + std::to_string(layer) + " exceeds 255");
    const float d = std::isfinite(depth) ? std::clamp(depth, 0.0f, 1.0f) : 1.0f;
    const uint64_t depth16 = uint64_t(std::lround(d * 65535.0f));
    return uint64_t(layer) << 56 | uint64_t(type.id & 0xffffu) << 40 | hash12(material) << 28 |
           hash12(source) << 16 | depth16;
}

DrawStats record_packets(VkCommandBuffer cmd, std::span<const DrawPacket> packets)
{
    DrawStats stats;
    const MaterialType* type = nullptr;
    VkDescriptorSet bound[3] = {VK_NULL_HANDLE, VK_NULL_HANDLE, VK_NULL_HANDLE};
    const MeshBinding* mesh = nullptr;
    for (const DrawPacket& p : packets)
    {
        if (!p.type || !p.frame || !p.material || !p.source || !p.mesh)
            throw std::invalid_argument("hemi: a draw packet needs a material type, its three descriptor "
                                        "sets and a mesh");
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

void make_instanced(DrawPacket& packet, uint32_t first, uint32_t count)
{
    if (count == 0)
        throw std::invalid_argument("hemi: an instanced draw of 0 instances");
    packet.push.instanced = 1;
    packet.instance_count = count;
    packet.first_instance = first;
}

void DrawQueue::sort()
{
    std::stable_sort(packets_.begin(), packets_.end(),
                     [](const DrawPacket& a, const DrawPacket& b) { return a.key < b.key; });
}

} // namespace hemi::render
