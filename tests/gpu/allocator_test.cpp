// Device memory is sub-allocated: many small buffers and images share a few VkDeviceMemory blocks, freed
// ranges are reused, and a request larger than half a block gets a block of its own that goes back to the
// driver. Objects retired to a DeletionQueue live until their frame is collected.
#include "../gpu_fixture.h"

#include <hemi/gpu/allocator.h>
#include <hemi/gpu/deletion_queue.h>
#include <hemi/gpu/resources.h>

#include <vector>

namespace
{
class Allocator : public hemi::test::GpuTest
{
};
} // namespace

TEST_F(Allocator, ManyBuffersAndImagesShareFewBlocks)
{
    auto& dev = hemi::test::device();
    const auto before = dev.allocator().stats();
    {
        std::vector<hemi::gpu::Buffer> buffers;
        std::vector<hemi::gpu::Image> images;
        for (int i = 0; i < 300; ++i)
            buffers.push_back(hemi::gpu::create_buffer(dev, {4096, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT}));
        for (int i = 0; i < 100; ++i)
            images.push_back(hemi::gpu::create_image(dev, {64, 64, VK_FORMAT_R8G8B8A8_UNORM}));
        const auto during = dev.allocator().stats();
        EXPECT_EQ(during.allocations - before.allocations, 400u);
        // 300 x 4 KiB of buffers and 100 x 16 KiB of images: one linear and one optimal block at most.
        EXPECT_LE(during.blocks - before.blocks, 2u) << "each resource got its own vkAllocateMemory";
        // Distinct, non-overlapping ranges: each buffer keeps what is written to it.
        for (size_t i = 0; i < buffers.size(); ++i)
        {
            const uint32_t v = uint32_t(i) * 2654435761u;
            hemi::gpu::write_buffer(dev, buffers[i], &v, 4, 4092);
        }
        for (size_t i = 0; i < buffers.size(); ++i)
        {
            uint32_t v = 0;
            hemi::gpu::read_buffer(dev, buffers[i], &v, 4, 4092);
            ASSERT_EQ(v, uint32_t(i) * 2654435761u) << "buffer " << i << " overlaps another";
        }
    }
    const auto after = dev.allocator().stats();
    EXPECT_EQ(after.allocations, before.allocations);
    EXPECT_EQ(after.used_bytes, before.used_bytes) << "freed ranges return to their blocks";
    // The freed ranges are reused: a second round needs no new block.
    std::vector<hemi::gpu::Buffer> again;
    for (int i = 0; i < 300; ++i)
        again.push_back(hemi::gpu::create_buffer(dev, {4096, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT}));
    EXPECT_EQ(dev.allocator().stats().blocks, after.blocks);
}

TEST_F(Allocator, LargeRequestsGetADedicatedBlockThatIsFreed)
{
    auto& dev = hemi::test::device();
    const auto before = dev.allocator().stats();
    {
        hemi::gpu::Buffer big =
            hemi::gpu::create_buffer(dev, {VkDeviceSize(48) << 20, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
        EXPECT_EQ(dev.allocator().stats().blocks, before.blocks + 1);
    }
    EXPECT_EQ(dev.allocator().stats().blocks, before.blocks);
}

TEST(DeletionQueue, KeepsObjectsAliveUntilTheirFrameIsCollected)
{
    struct Tracked
    {
        int* alive;
        explicit Tracked(int* a) : alive(a) { ++*alive; }
        Tracked(Tracked&& o) noexcept : alive(o.alive) { o.alive = nullptr; }
        ~Tracked()
        {
            if (alive)
                --*alive;
        }
    };
    int alive = 0;
    hemi::gpu::DeletionQueue q;
    q.retire(5, Tracked(&alive));
    q.retire(7, Tracked(&alive));
    EXPECT_EQ(alive, 2);
    q.collect(4);
    EXPECT_EQ(alive, 2) << "frame 5 has not finished";
    q.collect(5);
    EXPECT_EQ(alive, 1);
    EXPECT_EQ(q.pending(), 1u);
    q.collect(100);
    EXPECT_EQ(alive, 0);
}
