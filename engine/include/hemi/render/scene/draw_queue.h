#pragma once
// Draws that scale: each draw is a packet (its material type, three descriptor sets, mesh range and push
// constants) with a 64-bit sort key; a frame's packets are sorted by key and recorded with only the state
// that changes between neighbours bound. 10,000 draws of 2 material types record 2 pipeline binds.
//
// The key, from the most significant bit down: the caller's pass or layer (8 bits), the material type's id
// (MaterialType::id, 16 bits), the material's descriptor set and the coefficient source's set (hashed, 12
// bits each), then a 16-bit depth (front to back for opaque surfaces; an engine sorting blended surfaces
// back to front passes 1 - depth). Engines with their own render queue can take the packets (packets()) and
// sort and record them their way, with record_packets().

#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/gpu_mesh.h>

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace hemi::render
{

struct DrawPacket
{
    uint64_t key = 0; // draw_key()
    const MaterialType* type = nullptr;
    VkDescriptorSet frame = VK_NULL_HANDLE, material = VK_NULL_HANDLE, source = VK_NULL_HANDLE;
    const MeshBinding* mesh = nullptr; // GpuMesh::binding() or an EngineGeometry's buffers
    uint32_t first_index = 0, index_count = 0;
    int32_t vertex_offset = 0;
    shared::DrawPush push{};
    // Instanced: `instance_count` instances whose values are records [first_instance, first_instance +
    // instance_count) of the frame set's instance buffer (push.instanced = 1; make_instanced()).
    uint32_t instance_count = 1, first_instance = 0;
};

// Instances [first, first + count) of the frame set's instance records; count 0: not instanced.
struct InstanceRange
{
    uint32_t first = 0, count = 0;
};

// Makes `packet` draw `count` instances with the values of the frame's instance records from `first` on
// (FrameSet::write_instances): one draw for many instances of one asset (count 0 draws nothing).
void make_instanced(DrawPacket& packet, uint32_t first, uint32_t count) noexcept;

// `layer` < 256 (its low 8 bits are used); `depth` in [0, 1] (clamped; not finite: 1), e.g. the view depth
// of the draw's bounds' centre over the far plane.
uint64_t draw_key(uint32_t layer, const MaterialType& type, VkDescriptorSet material, VkDescriptorSet source,
                  float depth) noexcept;

// What record_packets() bound, for an engine's statistics (and hemi-bench's counters).
struct DrawStats
{
    uint64_t draws = 0, pipeline_binds = 0, descriptor_set_binds = 0, mesh_binds = 0;
    uint64_t instances = 0; // drawn by those draws (each instanced draw's count)
    uint64_t refused = 0;   // packets without a type, a set or a mesh: then nothing was recorded
};

// Inside the caller's render pass: the packets in the order given, binding a pipeline, descriptor sets or a
// mesh only where it differs from the previous packet's. A packet without a type, a descriptor set or a mesh
// (a released object's) refuses the whole list: nothing is recorded, the stats count the refused packets,
// and the device of the packets' material types logs it (docs/engine.md, "Errors"). Allocates nothing.
DrawStats record_packets(VkCommandBuffer cmd, std::span<const DrawPacket> packets) noexcept;

class DrawQueue
{
  public:
    // The queue keeps its capacity through clear(): a steady frame allocates nothing.
    void add(const DrawPacket& packet) { packets_.push_back(packet); }
    // By key; packets of equal keys keep the order they were added in.
    void sort();
    DrawStats record(VkCommandBuffer cmd) const noexcept { return record_packets(cmd, packets_); }
    void clear() { packets_.clear(); }
    size_t size() const { return packets_.size(); }
    std::span<const DrawPacket> packets() const { return packets_; }

  private:
    std::vector<DrawPacket> packets_, scratch_;
    std::vector<std::pair<uint64_t, uint32_t>> order_; // sort(): (key, position)
};

} // namespace hemi::render
