#pragma once
// Uploads recorded into a command buffer the caller submits: an engine loads many textures and meshes
// with one submission of its own instead of a submit-and-wait per resource. The staging memory lives in
// the batch, which the caller destroys (or clear()s) once that submission has completed.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>

#include <cstddef>
#include <functional>
#include <span>
#include <vector>

namespace hemi::gpu
{

class UploadBatch
{
  public:
    explicit UploadBatch(const Device& device) : device_(&device) {}
    const Device& device() const { return *device_; }

    // `size` bytes into `dst` at `offset`: written directly when the buffer is host-mapped (lavapipe, most
    // integrated GPUs), else staged and copied by record(). The data are copied now.
    void buffer(const Buffer& dst, const void* data, VkDeviceSize size, VkDeviceSize offset = 0);
    // Tightly packed texels of mip 0 (of every layer, one after another); when the image has more mips,
    // record() fills them by successive linear blits (box-filtered halving). Every mip ends in
    // SHADER_READ_ONLY_OPTIMAL.
    void image(const Image& dst, const void* texels, size_t bytes);
    // Every mip level given, not generated (mips a blit cannot make, e.g. solid-angle-weighted ones):
    // levels[i] holds mip i's tightly packed texels of every layer; dst.mip_levels() levels. Every mip ends
    // in SHADER_READ_ONLY_OPTIMAL.
    void image_levels(const Image& dst, std::span<const std::vector<std::byte>> levels);

    // Records every pending copy and blit, with the barriers that make them visible to shader reads
    // (vertex input, index, uniform, sampled) of later commands. Clears the pending list.
    void record(VkCommandBuffer cmd);
    // record() into a one-shot command buffer, submitted and waited for: for tools and tests.
    void submit_and_wait();
    // Frees the staging memory: call once the submission holding record()'s commands has completed.
    void clear();
    bool empty() const { return pending_.empty(); }

  private:
    const Device* device_;
    std::vector<Buffer> staging_;
    std::vector<std::function<void(VkCommandBuffer)>> pending_;
};

// Mips of a full chain for a width x height image: 1 + floor(log2(max(width, height))).
uint32_t full_mip_count(uint32_t width, uint32_t height);

} // namespace hemi::gpu
