// gpu::UploadBatch::image_levels: every mip level and layer of an image lands where it belongs (the baked
// solid-angle mipmaps of parabolic maps go through it); read back level by level with the validation layer
// on.
#include "../gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>

#include <cstring>
#include <vector>

namespace
{
class UploadLevels : public hemi::test::GpuTest
{
};
} // namespace

TEST_F(UploadLevels, EveryLevelAndLayerLandsWhereItBelongs)
{
    auto& dev = hemi::test::device();
    const uint32_t size = 8, levels = 4, layers = 2;
    hemi::gpu::Image image = hemi::gpu::create_image(
        dev, {size, size, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_SAMPLED_BIT, levels, layers, true});
    // Texel (x, y) of layer k at level l holds (l, k, x, y): a swapped level, layer or row shows.
    std::vector<std::vector<std::byte>> data(levels);
    for (uint32_t l = 0; l < levels; ++l)
    {
        const uint32_t s = size >> l;
        std::vector<float> texels;
        for (uint32_t k = 0; k < layers; ++k)
            for (uint32_t y = 0; y < s; ++y)
                for (uint32_t x = 0; x < s; ++x)
                    texels.insert(texels.end(), {float(l), float(k), float(x), float(y)});
        data[l].resize(texels.size() * 4);
        std::memcpy(data[l].data(), texels.data(), data[l].size());
    }
    hemi::gpu::UploadBatch upload(dev);
    upload.image_levels(image, data);
    upload.submit_and_wait();

    size_t total = 0;
    for (const auto& d : data)
        total += d.size();
    hemi::gpu::Buffer readback = hemi::gpu::create_buffer(
        dev, {total, VK_BUFFER_USAGE_TRANSFER_DST_BIT, hemi::gpu::MemoryUsage::Readback});
    hemi::gpu::one_shot(
        dev,
        [&](VkCommandBuffer cmd)
        {
            hemi::gpu::transition_image(cmd, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                                        VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
            VkDeviceSize offset = 0;
            for (uint32_t l = 0; l < levels; ++l)
            {
                VkBufferImageCopy region{};
                region.bufferOffset = offset;
                region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, l, 0, layers};
                region.imageExtent = {size >> l, size >> l, 1};
                vkCmdCopyImageToBuffer(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback, 1,
                                       &region);
                offset += data[l].size();
            }
            hemi::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                                      VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
            hemi::gpu::transition_image(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                        VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        });
    std::vector<std::byte> back(total);
    hemi::gpu::read_buffer(dev, readback, back.data(), total);
    size_t offset = 0;
    for (uint32_t l = 0; l < levels; ++l)
    {
        EXPECT_EQ(std::memcmp(back.data() + offset, data[l].data(), data[l].size()), 0) << "level " << l;
        offset += data[l].size();
    }
    // A level count that does not match the image, or a level of the wrong size, is refused.
    EXPECT_THROW(upload.image_levels(image, std::span(data).first(3)), std::invalid_argument);
    data[2].pop_back();
    EXPECT_THROW(upload.image_levels(image, data), std::invalid_argument);
}
