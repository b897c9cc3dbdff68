#pragma once
// Descriptor set 0 of the material system: what every draw of one view shares (camera, options, the
// separable basis's weights), updated once per frame.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/render/material/material_system.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <span>
#include <vector>

namespace hemi::render
{

// A dynamic light, added to the precomputed lighting by the techniques that take dynamic lights (irradiance,
// rnm, rnm_ao, ssbump: Green 2007 projects them onto Valve's three directions; lambert, banks, factored).
// World space, z up.
struct DynamicLight
{
    bool point = false; // false: directional
    glm::vec3 position{0.0f, 0.0f,
                       1.0f}; // a point light's position, or the direction towards a directional one
    glm::vec3 irradiance{
        1.0f}; // on a surface facing it (a point light's at distance 1, falling off as 1 / d^2)
    // glTF's falloffs (KHR_lights_punctual, as hemi-bake bakes them): a point or spot light's range window
    // clamp(1 - (d / range)^4, 0, 1) when range > 0; a spot light (spot) its smooth cone
    // saturate((cos a - cos outer) / (cos inner - cos outer))^2, a the angle off spot_direction (where it
    // points; radians, 0 <= inner < outer <= pi/2).
    float range = 0.0f;
    bool spot = false;
    glm::vec3 spot_direction{0.0f, 0.0f, -1.0f};
    float inner_cone = 0.0f, outer_cone = 0.785398163f;
    // A lightmap's mixed light (io::LightmapLight::channel, 0-3): on a lightmapped surface its light is
    // times that channel of the lightmap's shadowmask (the level's static shadows; surfaces of other sources
    // take it unshadowed). -1: a light the lightmap knows nothing of.
    int shadowmask_channel = -1;
};

struct FrameData
{
    glm::mat4 view_projection{1.0f};  // Vulkan clip space (material_system.h)
    bool lighting_only = false;       // albedo 1 and no emissive: the "white" view of the lighting alone
    glm::vec3 eye{0.0f};              // the camera's position (world): the view direction of specular terms
    std::vector<DynamicLight> lights; // at most HEMI_MAX_LIGHTS (more are refused)
    // The dynamic lights' specular term (normalised Blinn-Phong, (m + 8) / (8 pi) (n.h)^m (n.l) E, at the
    // technique's normal): exponent m and strength (0: none). A stand-in for per-material gloss.
    float specular_exponent = 32.0f; // > 0
    float specular_strength = 0.0f;
    // The glossy layer (hemi/lib/specular.glsl, docs/specular.md): a GGX coat over every surface, of glTF's
    // roughness (clamped to [0.03, 1]; 0: no coat, the Blinn-Phong term above instead) and reflectance f0 at
    // normal incidence (in [0, 1]). It replaces the dynamic lights' Blinn-Phong with exact GGX, and the
    // irradiance technique adds the specular its coefficients hold (hemi_basis_specular; a world-space SH9
    // probe's, hemi_sh9_specular). Added to the diffuse light, not weighted against it.
    float glossy_roughness = 0.0f;
    float glossy_f0 = 0.04f;
};

// Per-frame data for `frames_in_flight` frames, each slot its own range of one buffer and its own set, and
// room for `max_instances` instance records per frame (instanced draws, shared::DrawPush).
//   write_instances(): the records of a slot's instanced draws, through the same mapped memory.
//   write():         through persistently mapped memory (host-visible, device-local where the device has such
//                    memory): no command, no barrier. Write slot `slot` only once the GPU has finished the
//                    frame that last read it (the engine's per-frame fence); the queue submission that
//                    follows makes the host writes visible.
//   record_update(): outside a render pass, in the command buffer: the previous frame's reads finish before
//                    the update, which finishes before this frame's draws read it (a frame recorded and
//                    submitted at once: tools, tests).
// The uniform block hemi's pipelines read for a view (shared::FrameUniforms, std140, hemi/shared/surface.h),
// packed from `frame` into `out`: what an engine writes into its own buffer for FrameSet's engine-data
// constructor. On the frame path: too many lights or values that are not finite are reported through the
// system's device's log callback, and `out` is left as it was (false).
bool frame_uniforms(const MaterialSystem& system, const FrameData& frame,
                    shared::FrameUniforms& out) noexcept;

class FrameSet
{
  public:
    explicit FrameSet(const MaterialSystem& system, uint32_t frames_in_flight = 1,
                      uint32_t max_instances = 0);
    // Over the engine's own view data: uniforms[slot] is a range of the engine's buffer (UNIFORM_BUFFER
    // usage, its offset a multiple of minUniformBufferOffsetAlignment) holding a shared::FrameUniforms the
    // engine writes itself (frame_uniforms()), one per frame slot; instances[slot], when given, a range
    // (STORAGE_BUFFER usage) of shared::DrawPush records for instanced draws, max_instances of them. hemi
    // makes only the descriptor sets (and, without instance ranges, a one-record buffer for the binding);
    // write() and write_instances() are refused (logged, false): the engine writes its buffers.
    FrameSet(const MaterialSystem& system, std::span<const gpu::BufferRange> uniforms,
             std::span<const gpu::BufferRange> instances = {}, uint32_t max_instances = 0);
    //
    // The calls below are on the frame path: none throws or allocates. A bad argument (a slot out of range,
    // too many lights, values that are not finite, records past max_instances, a write to a frame set over
    // the engine's data) is reported through the device's log callback, and the call writes and records
    // nothing and returns false (set(): VK_NULL_HANDLE, which the draws given it refuse in turn).
    bool write(uint32_t slot, const FrameData& frame) noexcept;
    // Records [first, first + records.size()) of slot `slot`'s instance buffer, which instanced draws read
    // (draw_queue.h: make_instanced; PrtModel::instance_record, LightmapModel::instance_record), at most
    // max_instances. Write a slot only once the GPU is done with it, as write().
    bool write_instances(uint32_t slot, std::span<const shared::DrawPush> records,
                         uint32_t first = 0) noexcept;
    uint32_t max_instances() const { return max_instances_; }
    bool record_update(VkCommandBuffer cmd, const FrameData& frame, uint32_t slot = 0) const noexcept;
    VkDescriptorSet set(uint32_t slot = 0) const noexcept;
    uint32_t frames_in_flight() const { return uint32_t(sets_.size()); }

  private:
    bool check_write(const char* call, uint32_t slot) const noexcept;
    const gpu::Device* device_;
    void make_sets(const MaterialSystem& system, std::span<const gpu::BufferRange> uniforms,
                   std::span<const gpu::BufferRange> instances);
    bool engine_data_ = false;
    gpu::Buffer uniforms_, instances_;
    VkDeviceSize stride_ = 0, instance_stride_ = 0;
    uint32_t max_instances_ = 0;
    std::vector<gpu::DescriptorSet> sets_;
};

// The update-with-barriers of a small block of `buffer` at `offset` read by vertex and fragment shaders
// with `read_access` (uniform or storage reads; vkCmdUpdateBuffer).
void record_uniform_update(VkCommandBuffer cmd, const gpu::Buffer& buffer, const void* data, size_t size,
                           VkDeviceSize offset = 0, VkAccessFlags read_access = VK_ACCESS_UNIFORM_READ_BIT);

} // namespace hemi::render
