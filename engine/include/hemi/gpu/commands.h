#pragma once
// Command recording and submission: a reusable one-shot context (record, submit, wait) and
// GPU timestamp queries.

#include <hemi/gpu/device.h>
#include <hemi/gpu/handle.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace hemi::gpu
{

// One command pool, one primary command buffer and one fence. Not thread-safe; use one per thread.
class CommandContext
{
  public:
    explicit CommandContext(const Device& device);

    // Resets the command buffer and begins recording (one-time-submit).
    VkCommandBuffer begin();
    // Ends recording, submits to the device queue and blocks until the GPU has finished.
    void submit_and_wait();
    // begin(); record(cb); submit_and_wait().
    void run(const std::function<void(VkCommandBuffer)>& record);

  private:
    const Device* device_;
    CommandPool pool_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    Fence fence_;
};

// Records with `record` into a temporary context and waits for completion. For set-up work.
void one_shot(const Device& device, const std::function<void(VkCommandBuffer)>& record);

// A pool of `count` timestamp queries. Reset it in the command buffer before writing.
class TimestampQueries
{
  public:
    TimestampQueries(const Device& device, uint32_t count);
    bool supported() const { return period_ns_ > 0.0; }
    void reset(VkCommandBuffer cmd);
    void write(VkCommandBuffer cmd, uint32_t index, VkPipelineStageFlagBits stage);
    // Waits for and returns the tick values of queries [0, count) converted to nanoseconds.
    std::vector<double> read_ns();

  private:
    VkDevice device_;
    QueryPool pool_;
    uint32_t count_;
    double period_ns_;
};

// A full memory barrier between two commands of one command buffer (compute/transfer/graphics).
void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stages, VkAccessFlags src_access,
                    VkPipelineStageFlags dst_stages, VkAccessFlags dst_access);

} // namespace hemi::gpu
