#pragma once
// A mesh on the GPU in hemi's own vertex layout (position, normal, glTF tangent, both UV sets, fp32,
// interleaved; 32-bit indices; an engine's meshes in their own layouts draw through MaterialKey::vertex),
// uploaded through the caller's UploadBatch. Shared by every instance drawn from it.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/mesh.h>
#include <hemi/render/material/material_system.h>

#include <cstdint>
#include <vector>

namespace hemi::render
{

// The vertex and index buffers a draw binds: a GpuMesh's, or the engine's own (EngineGeometry). Streams
// [0, streams) are bound at binding 0 on, each at its offset.
struct MeshBinding
{
    uint32_t streams = 1;
    VkBuffer vertex_buffers[VertexLayout::kMaxVertexStreams] = {};
    VkDeviceSize vertex_offsets[VertexLayout::kMaxVertexStreams] = {};
    VkBuffer index_buffer = VK_NULL_HANDLE;
    VkDeviceSize index_offset = 0;
    VkIndexType index_type = VK_INDEX_TYPE_UINT32; // or VK_INDEX_TYPE_UINT16

    void bind(VkCommandBuffer cmd) const;
};

// A model drawn from the engine's own vertex and index buffers, in its own layout: hemi then uploads and
// holds no vertex or index data of the model (the asset's CPU mesh still gives each primitive's bounds).
struct EngineGeometry
{
    VertexLayout layout; // the engine's streams, offsets and formats (MaterialKey::vertex)
    MeshBinding buffers; // bound as given (the engine keeps them alive while the model draws)
    // The engine's draw of each of the asset's primitives, in the asset's order: its index range and the
    // vertexOffset added to its indices. Empty: the asset's own index ranges, vertex offset 0 (the engine
    // kept the asset's vertex and index order). A PRT model reads vertex v's coefficients at the asset's
    // vertex index, so the engine keeps the asset's vertex order for it (its vertex v of the model at
    // vertex_offset + v; hemi takes the offset out of the coefficient index).
    struct Range
    {
        uint32_t first_index = 0, index_count = 0;
        int32_t vertex_offset = 0;
    };
    std::vector<Range> primitives;
};

class GpuMesh
{
  public:
    // The mesh needs a normal, tangent and UV per vertex and a non-empty triangle list with indices in
    // range (TEXCOORD_1 is optional: zeros when absent); throws std::invalid_argument naming the problem.
    // The vertex and index data are written now or staged in `upload` (record it before the first draw).
    GpuMesh(const gpu::Device& device, const io::Mesh& mesh, gpu::UploadBatch& upload);

    // Its vertex layout: one interleaved fp32 stream (what MaterialKey::vertex defaults to).
    static VertexLayout layout() { return VertexLayout{}; }

    void bind(VkCommandBuffer cmd) const { binding_.bind(cmd); } // vertex and index buffers
    const MeshBinding& binding() const { return binding_; }
    // Draws indices [first_index, first_index + index_count) (after bind()).
    void draw(VkCommandBuffer cmd, uint32_t first_index, uint32_t index_count, uint32_t instance_count = 1,
              uint32_t first_instance = 0) const;
    uint32_t vertex_count() const { return vertex_count_; }
    uint32_t index_count() const { return index_count_; }

  private:
    gpu::Buffer vertices_, indices_;
    MeshBinding binding_;
    uint32_t vertex_count_ = 0, index_count_ = 0;
};

} // namespace hemi::render
