#include "gpu_fixture.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace hemi::test
{
namespace
{
std::unique_ptr<gpu::Device> g_device;

class DeviceEnvironment : public ::testing::Environment
{
  public:
    void TearDown() override
    {
        g_device.reset();
        std::vector<std::string> late = validation_log().take();
        for (const std::string& m : late)
            std::fprintf(stderr, "validation message at device destruction: %s\n", m.c_str());
        if (!late.empty())
            std::_Exit(1); // after gtest's own summary: a leak report fails the run
    }
};
[[maybe_unused]] ::testing::Environment* const g_env =
    ::testing::AddGlobalTestEnvironment(new DeviceEnvironment);

} // namespace

ValidationLog& validation_log()
{
    static ValidationLog log;
    return log;
}

gpu::LogCallback recording_log()
{
    return [](gpu::LogLevel level, bool validation, std::string_view message)
    {
        if (validation && level >= gpu::LogLevel::Warning)
            validation_log().add(std::string(message));
    };
}

gpu::Device& device()
{
    if (!g_device)
    {
        gpu::DeviceDesc desc;
        desc.validation = true;
        desc.log = recording_log();
        g_device = std::make_unique<gpu::Device>(desc);
    }
    return *g_device;
}

} // namespace hemi::test

namespace hemi::shaders::detail
{
struct EmbeddedShader
{
    std::string_view name;
    const uint32_t* code;
    size_t words;
};
extern const EmbeddedShader kTestShaders[];
extern const size_t kTestShadersCount;
} // namespace hemi::shaders::detail

std::span<const uint32_t> hemi::test::test_spirv(std::string_view name)
{
    using namespace hemi::shaders::detail;
    for (size_t i = 0; i < kTestShadersCount; ++i)
        if (kTestShaders[i].name == name)
            return {kTestShaders[i].code, kTestShaders[i].words};
    throw std::invalid_argument("no test shader named '" + std::string(name) + "'");
}

void hemi::test::dispatch_storage(std::string_view name, const std::vector<const gpu::Buffer*>& buffers,
                                  std::span<const std::byte> push,
                                  const std::vector<uint32_t>& specialization, uint32_t groups)
{
    gpu::Device& dev = device();
    std::vector<gpu::Binding> bindings;
    for (uint32_t i = 0; i < buffers.size(); ++i)
        bindings.push_back({i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_COMPUTE_BIT});
    gpu::Program program =
        gpu::create_compute_program(dev, {test_spirv(name), bindings, uint32_t(push.size()), specialization});
    gpu::DescriptorPool pool = gpu::create_descriptor_pool(dev, bindings, 1);
    VkDescriptorSet set = gpu::allocate_descriptor_set(dev, pool, program.set_layout);
    std::vector<gpu::DescriptorWrite> writes(buffers.size());
    for (uint32_t i = 0; i < buffers.size(); ++i)
    {
        writes[i].binding = i;
        writes[i].buffer = {*buffers[i], 0, VK_WHOLE_SIZE};
    }
    gpu::write_descriptors(dev, set, writes);
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.pipeline);
                      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, program.layout, 0, 1, &set,
                                              0, nullptr);
                      if (!push.empty())
                          vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0,
                                             uint32_t(push.size()), push.data());
                      vkCmdDispatch(cmd, groups, 1, 1);
                  });
}
