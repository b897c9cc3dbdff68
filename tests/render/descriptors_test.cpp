// One descriptor allocator per material system (gpu/descriptors.h): a thousand material instances and a
// thousand probe-lit objects take the two pools the README states (before it, one pool each: 2,000), each
// object's set is its own, sets go back to their pool when their owners go (making them again takes no new
// pool), and a small allocator's pools fill by sets and by descriptors of each type exactly, and refill.
// Under validation.
#include "../gpu_fixture.h"

#include "engine_pass.h"

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/upload.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/material/material_system.h>

#include <memory>
#include <set>
#include <vector>

namespace
{
using namespace hemi;

class Descriptors : public test::GpuTest
{
};

TEST_F(Descriptors, ThousandsOfMaterialsAndProbesShareAFewPools)
{
    gpu::Device& dev = test::device();
    const test::EnginePass pass(8, 8, {VK_FORMAT_R8G8B8A8_UNORM});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    const io::Material material; // glTF's default: the texture set's 1 x 1 defaults
    const render::TextureSet textures(dev, std::span<const io::ImageRgba8>(),
                                      std::span<const io::Material>(&material, 1), upload);
    gpu::DescriptorAllocator& descriptors = system.descriptors();
    size_t pools = 0;
    for (int round = 0; round < 2; ++round)
    {
        std::vector<std::unique_ptr<render::MaterialInstance>> materials;
        std::vector<std::unique_ptr<render::ProbeBuffer>> probes;
        for (int i = 0; i < 1000; ++i)
        {
            materials.push_back(
                std::make_unique<render::MaterialInstance>(system, textures, material, upload));
            probes.push_back(std::make_unique<render::ProbeBuffer>(system, 1));
        }
        upload.submit_and_wait();
        EXPECT_EQ(descriptors.pool_count(), 2u);
        EXPECT_EQ(descriptors.live_sets(), 2000u);
        std::set<VkDescriptorSet> distinct;
        for (size_t i = 0; i < materials.size(); ++i)
        {
            distinct.insert(materials[i]->set());
            distinct.insert(probes[i]->set());
        }
        EXPECT_EQ(distinct.size(), 2000u);
        if (round == 0)
            pools = descriptors.pool_count();
        else
            EXPECT_EQ(descriptors.pool_count(), pools) << "the freed sets were not reused";
    }
    EXPECT_EQ(descriptors.live_sets(), 0u);
}

TEST_F(Descriptors, PoolsFillBySetsAndByDescriptorsAndRefill)
{
    gpu::Device& dev = test::device();
    // Pools of 4 sets and 16 descriptors of each type.
    gpu::DescriptorAllocator allocator(dev, 4);
    const std::vector<gpu::Binding> small = {{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
                                             {1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}};
    const gpu::DescriptorSetLayout small_layout = gpu::create_set_layout(dev, small);
    std::vector<gpu::DescriptorSet> sets;
    for (int i = 0; i < 10; ++i)
        sets.push_back(allocator.allocate(small_layout, small));
    EXPECT_EQ(allocator.pool_count(), 3u);      // 4 + 4 + 2 sets
    sets.erase(sets.begin(), sets.begin() + 4); // the first pool's
    for (int i = 0; i < 6; ++i)
        sets.push_back(allocator.allocate(small_layout, small));
    EXPECT_EQ(allocator.pool_count(), 3u) << "4 sets back in the first pool, 2 left in the third";
    EXPECT_EQ(allocator.live_sets(), 12u);
    sets.clear();
    EXPECT_EQ(allocator.live_sets(), 0u);

    // Six image samplers a set: two sets fill a pool's 16 samplers to 12, the third needs another pool.
    const std::vector<gpu::Binding> wide = {
        {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_ALL, 6}};
    const gpu::DescriptorSetLayout wide_layout = gpu::create_set_layout(dev, wide);
    gpu::DescriptorAllocator wide_allocator(dev, 4);
    for (int i = 0; i < 3; ++i)
        sets.push_back(wide_allocator.allocate(wide_layout, wide));
    EXPECT_EQ(wide_allocator.pool_count(), 2u);
    sets.clear();

    // More descriptors of one type than a pool holds: refused, naming the sizes.
    const std::vector<gpu::Binding> huge = {
        {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_SHADER_STAGE_ALL, 17}};
    const gpu::DescriptorSetLayout huge_layout = gpu::create_set_layout(dev, huge);
    EXPECT_THROW(wide_allocator.allocate(huge_layout, huge), std::invalid_argument);
}

} // namespace
