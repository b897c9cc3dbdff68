#include <hemi/render/view/lightmap_view.h>

#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>

namespace hemi::render
{

LightmapView::LightmapView(const gpu::Device& device, const io::LightmapAsset& asset,
                           const std::vector<std::string>& techniques, uint32_t width, uint32_t height)
    : asset_(&asset), view_(device, width, height)
{
    gpu::UploadBatch upload(device);
    model_ = std::make_unique<LightmapModel>(view_.system(), asset, techniques, upload);
    upload.submit_and_wait();
}

LightmapView::~LightmapView() = default;

io::ImageRgba LightmapView::render(const LightmapFrame& frame)
{
    gpu::one_shot(view_.device(), [&](VkCommandBuffer cmd) {
        view_.record_frame(cmd, frame.camera, asset_->mesh, frame.model, frame.white);
        view_.target().begin(cmd);
        model_->draw(cmd, view_.frame(), frame.technique, frame.model);
        view_.target().end(cmd);
    });
    return view_.read();
}

} // namespace hemi::render
