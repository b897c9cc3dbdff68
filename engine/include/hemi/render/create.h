#pragma once
// Loading without exceptions (docs/engine.md, "Errors"). hemi's constructors and readers throw when a level
// loads (a bad file, a bad argument, a Vulkan failure); an engine built with -fno-exceptions makes its hemi
// objects through these functions instead. Each one is noexcept: it catches inside hemi whatever the
// constructor or reader throws (std::bad_alloc included) and returns the object or the reason it could not be
// made, the same message the exception carried (naming the call, the file or the argument). Where a device
// is at hand the message also goes to its log callback at LogLevel::Error.
#include <hemi/gpu/device.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/io/prt_asset.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/probe_object.h>
#include <hemi/render/scene/prt_model.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hemi
{

// An object hemi made, or why it could not: `if (auto level = render::create_lightmap_model(...))
// use(*level); else log(level.error());`. Holds the object by unique_ptr (hemi's objects do not move).
template <typename T> class Created
{
  public:
    Created(std::unique_ptr<T> value) noexcept : value_(std::move(value)) {}
    Created(std::string error) noexcept : error_(std::move(error)) {}

    explicit operator bool() const noexcept { return value_ != nullptr; }
    T& operator*() const noexcept { return *value_; }
    T* operator->() const noexcept { return value_.get(); }
    T* get() const noexcept { return value_.get(); }
    // The object, which the caller now owns (null when it could not be made).
    std::unique_ptr<T> take() noexcept { return std::move(value_); }
    // Why the object could not be made; empty when it was.
    const std::string& error() const noexcept { return error_; }

  private:
    std::unique_ptr<T> value_;
    std::string error_;
};

} // namespace hemi

namespace hemi::render
{

Created<gpu::Device> create_device(const gpu::ExternalDevice& external) noexcept;
// Without a target: no default pass (MaterialSystem(device)); with one: its default colour pass.
Created<MaterialSystem> create_material_system(const gpu::Device& device,
                                               VkPipelineCache cache = VK_NULL_HANDLE) noexcept;
Created<MaterialSystem> create_material_system(const gpu::Device& device, const RenderTargetDesc& target,
                                               VkPipelineCache cache = VK_NULL_HANDLE) noexcept;

Created<io::LightmapAsset> read_lightmap_asset(const std::filesystem::path& path) noexcept;
Created<io::PrtAsset> read_prt_asset(const std::filesystem::path& path) noexcept;
Created<io::EnvmapAsset> read_envmap_asset(const std::filesystem::path& path) noexcept;

Created<LightmapModel> create_lightmap_model(
    MaterialSystem& system, const io::LightmapAsset& asset, const std::vector<std::string>& techniques,
    gpu::UploadBatch& upload, const std::map<std::string, std::string>& material_techniques = {},
    const EngineGeometry* geometry = nullptr, LightmapFilter filter = LightmapFilter::Linear) noexcept;
Created<PrtModel> create_prt_model(MaterialSystem& system, const io::PrtAsset& asset,
                                   const PrtModelDesc& desc, gpu::UploadBatch& upload) noexcept;
Created<ProbeObject> create_probe_object(MaterialSystem& system, const io::Mesh& mesh,
                                         const std::vector<io::EncodedImage>& images,
                                         const std::vector<io::Material>& materials,
                                         const std::vector<io::Primitive>& primitives, uint32_t instances,
                                         gpu::UploadBatch& upload, uint32_t frames_in_flight = 1,
                                         const EngineGeometry* geometry = nullptr) noexcept;
Created<FrameSet> create_frame_set(const MaterialSystem& system, uint32_t frames_in_flight = 1,
                                   uint32_t max_instances = 0) noexcept;
Created<FrameSet> create_frame_set(const MaterialSystem& system, std::span<const gpu::BufferRange> uniforms,
                                   std::span<const gpu::BufferRange> instances = {},
                                   uint32_t max_instances = 0) noexcept;

// add_pass of each model: true and the pass's index in `index`, or false (logged) when its pipelines could
// not be made.
bool add_pass(LightmapModel& model, const PassDesc& pass, size_t& index) noexcept;
bool add_pass(PrtModel& model, const PassDesc& pass, size_t& index) noexcept;
bool add_pass(ProbeObject& object, const PassDesc& pass, size_t& index) noexcept;
// LightmapModel::draw_list into `out`: false (logged, `out` empty) for a technique the model did not load.
bool draw_list(const LightmapModel& model, const std::string& technique, size_t pass,
               std::vector<LightmapDraw>& out) noexcept;
// UploadBatch::record: false (logged) when a staging buffer could not be made.
bool record_uploads(gpu::UploadBatch& upload, VkCommandBuffer cmd) noexcept;

} // namespace hemi::render
