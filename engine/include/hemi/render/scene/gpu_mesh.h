#pragma once
// A mesh on the GPU in the one vertex layout every material reads (position, normal, glTF tangent, both UV
// sets; 32-bit indices), uploaded through the caller's UploadBatch. Shared by every instance drawn from it.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/mesh.h>

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

    // Vertex input of the surface shader: locations 0 position, 1 normal, 2 tangent, 3 uv0, 4 uv1.
    static std::vector<VkVertexInputBindingDescription> vertex_bindings();
    static std::vector<VkVertexInputAttributeDescription> vertex_attributes();

    void bind(VkCommandBuffer cmd) const; // vertex and index buffers
    // Draws indices [first_index, first_index + index_count) (after bind()).
    void draw(VkCommandBuffer cmd, uint32_t first_index, uint32_t index_count) const;
    uint32_t vertex_count() const { return vertex_count_; }
    uint32_t index_count() const { return index_count_; }

  private:
    gpu::Buffer vertices_, indices_;
    uint32_t vertex_count_ = 0, index_count_ = 0;
};

} // namespace hemi::render
