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

class GpuMesh
{
  public:
    // The mesh needs a normal, tangent and UV per vertex and a non-empty triangle list with indices in
    // range (TEXCOORD_1 is optional: zeros when absent); throws std::invalid_argument naming the problem.
    // The vertex and index data are written now or staged in `upload` (record it before the first draw).
    GpuMesh(const gpu::Device& device, const io::Mesh& mesh, gpu::UploadBatch& upload);

    // Its vertex layout: one interleaved fp32 stream (what MaterialKey::vertex defaults to).
    static VertexLayout layout() { return VertexLayout{}; }

    void bind(VkCommandBuffer cmd) const; // vertex and index buffers
    // Draws indices [first_index, first_index + index_count) (after bind()).
    void draw(VkCommandBuffer cmd, uint32_t first_index, uint32_t index_count, uint32_t instance_count = 1,
              uint32_t first_instance = 0) const;
    uint32_t vertex_count() const { return vertex_count_; }
    uint32_t index_count() const { return index_count_; }

  private:
    gpu::Buffer vertices_, indices_;
    uint32_t vertex_count_ = 0, index_count_ = 0;
};

} // namespace hemi::render
