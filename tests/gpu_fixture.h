#pragma once
// Every GPU test runs on one shared hemi::gpu::Device with the Khronos validation layer on. Any validation
// warning or error fails the test that was running when it arrived; messages that arrive while the device
// is destroyed (the object tracker's leak reports) fail the run at exit.

#include <hemi/gpu/device.h>
#include <hemi/gpu/resources.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include <gtest/gtest.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace hemi::test
{

struct ValidationLog
{
    std::mutex mutex;
    std::vector<std::string> messages;

    void add(std::string m)
    {
        std::lock_guard<std::mutex> lock(mutex);
        messages.push_back(std::move(m));
    }
    std::vector<std::string> take()
    {
        std::lock_guard<std::mutex> lock(mutex);
        return std::exchange(messages, {});
    }
};

ValidationLog& validation_log();
// A log callback that records validation warnings/errors into validation_log().
gpu::LogCallback recording_log();
// The shared device (created on first use with validation on).
gpu::Device& device();

// The SPIR-V of a test-only shader of tests/shaders/ by file name (throws when unknown).
std::span<const uint32_t> test_spirv(std::string_view name);

// One dispatch of the test compute shader `name` (set 0: storage buffer i at binding i, in order; the push
// constants `push`; `specialization` value i to constant_id i), submitted and waited for.
void dispatch_storage(std::string_view name, const std::vector<const gpu::Buffer*>& buffers,
                      std::span<const std::byte> push, const std::vector<uint32_t>& specialization,
                      uint32_t groups);

class GpuTest : public ::testing::Test
{
  protected:
    void SetUp() override { validation_log().take(); }
    void TearDown() override
    {
        for (const std::string& m : validation_log().take())
            ADD_FAILURE() << "validation message: " << m;
    }
};

} // namespace hemi::test
