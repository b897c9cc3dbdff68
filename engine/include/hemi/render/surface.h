#pragma once
// What every material draws: a mesh on the GPU (positions, normals, glTF tangents, UVs; 32-bit indices)
// and its normal map. Shared by all raster materials so that there is one vertex layout and one upload.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/io/mesh.h>
#include <hemi/render/offscreen.h>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace hemi::render
{

class GpuMesh
{
public:
    // The mesh needs a normal, tangent and UV per vertex and a non-empty triangle list with indices in
    // range; throws std::invalid_argument naming the problem otherwise.
    GpuMesh(const gpu::Device& device, const io::Mesh& mesh);

    // Vertex input of every material's vertex shader: locations 0 position, 1 normal, 2 tangent, 3 uv.
    static std::vector<VkVertexInputBindingDescription> vertex_bindings();
    static std::vector<VkVertexInputAttributeDescription> vertex_attributes();

    void draw(VkCommandBuffer cmd) const; // binds the buffers and draws every triangle
    uint32_t vertex_count() const { return vertex_count_; }

private:
    gpu::Buffer vertices_, indices_;
    uint32_t vertex_count_ = 0, index_count_ = 0;
};

// Where a material draws: a render pass and subpass, hemi's OffscreenTarget or an engine's own. Materials
// write linear colour to colour attachment 0 and, when the subpass has a second colour attachment, (u, v, 0,
// 1) where the mesh covers the pixel to attachment 1 (hemi's tests and tools read it; with one attachment a
// colour-only shader variant is used, so nothing is written without a target); further colour
// attachments are not written (Vulkan leaves them undefined where the mesh is drawn), none is blended. A
// depth attachment, if any, is tested and written (LESS).
// Viewport and scissor are dynamic state: the caller sets them (OffscreenTarget::begin does).
struct SurfacePass
{
    VkRenderPass render_pass = VK_NULL_HANDLE;
    uint32_t subpass = 0;
    uint32_t color_attachments = 1;
};

// A material's per-frame uniform update, outside the render pass: the previous frame's vertex and fragment
// reads finish before the update, which finishes before this frame's draws read it.
void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& uniforms, const void* data, size_t size);

// Inside the render pass: binds the material's pipeline and descriptor set, and draws the mesh.
void draw_surface(VkCommandBuffer cmd, const gpu::Program& program, VkDescriptorSet set, const GpuMesh& mesh);

// hemi's offscreen target as a surface pass (subpass 0, colour + aux attachments).
SurfacePass surface_pass(const OffscreenTarget& target);

// The graphics program of a material drawing a GpuMesh into `pass`: embedded shaders by name, set-0
// bindings, specialization constants shared by both stages, back-face culling of counter-clockwise (from
// outside) meshes.
gpu::Program create_surface_program(const gpu::Device& device, const SurfacePass& pass,
                                    std::string_view vertex_shader, std::string_view fragment_shader,
                                    const std::vector<gpu::Binding>& bindings,
                                    const std::vector<uint32_t>& specialization = {});

// An RGBA8 texture as a sampled image in SHADER_READ_ONLY_OPTIMAL: R8G8B8A8_SRGB when `srgb` (colour),
// R8G8B8A8_UNORM otherwise (data). Throws std::invalid_argument on a size mismatch.
gpu::Image upload_texture(const gpu::Device& device, std::span<const uint8_t> rgba8, uint32_t width,
                          uint32_t height, bool srgb);

// An RGBA8 tangent-space normal map (glTF convention) as a sampled image in SHADER_READ_ONLY_OPTIMAL.
gpu::Image upload_normal_map(const gpu::Device& device, std::span<const uint8_t> rgba8, uint32_t width,
                             uint32_t height);

} // namespace hemi::render
