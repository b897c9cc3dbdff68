// Loading without exceptions: every function runs hemi's throwing constructor or reader and turns what it
// throws into a message (render/create.h).
#include <hemi/render/create.h>

#include <exception>
#include <new>

namespace hemi::render
{
namespace
{

// What an exception says, or a fixed text for one that says nothing hemi can read. The fixed texts fit the
// standard library's short-string buffer (15 characters): they are made without allocating, out of memory
// too.
std::string message_of(std::exception_ptr e) noexcept
{
    try
    {
        std::rethrow_exception(e);
    }
    catch (const std::bad_alloc&)
    {
        return "hemi: no memory";
    }
    catch (const std::exception& x)
    {
        try
        {
            return x.what();
        }
        catch (...)
        {
            return "hemi: no memory"; // the copy of what() could not be made
        }
    }
    catch (...)
    {
        return "hemi: unknown";
    }
}

// Runs make(); an exception becomes the result's error, logged to `device` when there is one.
template <typename T, typename Make> Created<T> guarded(const gpu::Device* device, Make&& make) noexcept
{
    std::string error;
    try
    {
        return Created<T>(make());
    }
    catch (...)
    {
        error = message_of(std::current_exception());
    }
    if (device)
        device->log(gpu::LogLevel::Error, error);
    return Created<T>(std::move(error));
}

// Runs run() for its effect: false, logged, when it throws.
template <typename Run> bool guarded_call(const gpu::Device& device, Run&& run) noexcept
{
    try
    {
        run();
        return true;
    }
    catch (...)
    {
        device.log(gpu::LogLevel::Error, message_of(std::current_exception()));
        return false;
    }
}

} // namespace

Created<gpu::Device> create_device(const gpu::ExternalDevice& external) noexcept
{
    Created<gpu::Device> made =
        guarded<gpu::Device>(nullptr, [&] { return std::make_unique<gpu::Device>(external); });
    if (!made && external.log)
    {
        try
        {
            external.log(gpu::LogLevel::Error, false, made.error());
        }
        catch (...)
        {
        }
    }
    return made;
}

Created<MaterialSystem> create_material_system(const gpu::Device& device, VkPipelineCache cache) noexcept
{
    return guarded<MaterialSystem>(&device, [&] { return std::make_unique<MaterialSystem>(device, cache); });
}

Created<MaterialSystem> create_material_system(const gpu::Device& device, const RenderTargetDesc& target,
                                               VkPipelineCache cache) noexcept
{
    return guarded<MaterialSystem>(&device,
                                   [&] { return std::make_unique<MaterialSystem>(device, target, cache); });
}

Created<io::LightmapAsset> read_lightmap_asset(const std::filesystem::path& path) noexcept
{
    return guarded<io::LightmapAsset>(
        nullptr, [&] { return std::make_unique<io::LightmapAsset>(io::read_lightmap_asset(path)); });
}

Created<io::PrtAsset> read_prt_asset(const std::filesystem::path& path) noexcept
{
    return guarded<io::PrtAsset>(nullptr,
                                 [&] { return std::make_unique<io::PrtAsset>(io::read_prt_asset(path)); });
}

Created<io::EnvmapAsset> read_envmap_asset(const std::filesystem::path& path) noexcept
{
    return guarded<io::EnvmapAsset>(
        nullptr, [&] { return std::make_unique<io::EnvmapAsset>(io::read_envmap_asset(path)); });
}

Created<LightmapModel> create_lightmap_model(MaterialSystem& system, const io::LightmapAsset& asset,
                                             const std::vector<std::string>& techniques,
                                             gpu::UploadBatch& upload,
                                             const std::map<std::string, std::string>& material_techniques,
                                             const EngineGeometry* geometry, LightmapFilter filter) noexcept
{
    return guarded<LightmapModel>(&system.device(),
                                  [&]
                                  {
                                      return std::make_unique<LightmapModel>(system, asset, techniques,
                                                                             upload, material_techniques,
                                                                             geometry, filter);
                                  });
}

Created<PrtModel> create_prt_model(MaterialSystem& system, const io::PrtAsset& asset,
                                   const PrtModelDesc& desc, gpu::UploadBatch& upload) noexcept
{
    return guarded<PrtModel>(&system.device(),
                             [&] { return std::make_unique<PrtModel>(system, asset, desc, upload); });
}

Created<ProbeObject> create_probe_object(MaterialSystem& system, const io::Mesh& mesh,
                                         const std::vector<io::EncodedImage>& images,
                                         const std::vector<io::Material>& materials,
                                         const std::vector<io::Primitive>& primitives, uint32_t instances,
                                         gpu::UploadBatch& upload, uint32_t frames_in_flight,
                                         const EngineGeometry* geometry) noexcept
{
    return guarded<ProbeObject>(&system.device(),
                                [&]
                                {
                                    return std::make_unique<ProbeObject>(system, mesh, images, materials,
                                                                         primitives, instances, upload,
                                                                         frames_in_flight, geometry);
                                });
}

Created<FrameSet> create_frame_set(const MaterialSystem& system, uint32_t frames_in_flight,
                                   uint32_t max_instances) noexcept
{
    return guarded<FrameSet>(&system.device(), [&]
                             { return std::make_unique<FrameSet>(system, frames_in_flight, max_instances); });
}

Created<FrameSet> create_frame_set(const MaterialSystem& system, std::span<const gpu::BufferRange> uniforms,
                                   std::span<const gpu::BufferRange> instances,
                                   uint32_t max_instances) noexcept
{
    return guarded<FrameSet>(
        &system.device(),
        [&] { return std::make_unique<FrameSet>(system, uniforms, instances, max_instances); });
}

bool add_pass(LightmapModel& model, const PassDesc& pass, size_t& index) noexcept
{
    return guarded_call(model.surfaces().system().device(), [&] { index = model.add_pass(pass); });
}

bool add_pass(PrtModel& model, const PassDesc& pass, size_t& index) noexcept
{
    return guarded_call(model.surfaces().system().device(), [&] { index = model.add_pass(pass); });
}

bool add_pass(ProbeObject& object, const PassDesc& pass, size_t& index) noexcept
{
    return guarded_call(object.surfaces().system().device(), [&] { index = object.add_pass(pass); });
}

bool draw_list(const LightmapModel& model, const std::string& technique, size_t pass,
               std::vector<LightmapDraw>& out) noexcept
{
    out.clear();
    const bool ok =
        guarded_call(model.surfaces().system().device(), [&] { out = model.draw_list(technique, pass); });
    if (!ok)
        out.clear();
    return ok;
}

bool record_uploads(gpu::UploadBatch& upload, VkCommandBuffer cmd) noexcept
{
    return guarded_call(upload.device(), [&] { upload.record(cmd); });
}

} // namespace hemi::render
