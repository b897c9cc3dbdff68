#include <hemi/gpu/commands.h>
#include <hemi/gpu/vk_check.h>

#include <stdexcept>

namespace hemi::gpu
{

CommandContext::CommandContext(const Device& device) : device_(&device)
{
    VkDevice d = device.device();
    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = device.queue_family();
    VkCommandPool pool;
    HEMI_VK_CHECK(vkCreateCommandPool(d, &pool_info, nullptr, &pool));
    pool_ = CommandPool(d, pool);
    device.set_name(VK_OBJECT_TYPE_COMMAND_POOL, pool, "hemi one-shot command pool");

    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    HEMI_VK_CHECK(vkAllocateCommandBuffers(d, &alloc, &cmd_));
    device.set_name(VK_OBJECT_TYPE_COMMAND_BUFFER, cmd_, "hemi one-shot command buffer");

    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    HEMI_VK_CHECK(vkCreateFence(d, &fence_info, nullptr, &fence));
    fence_ = Fence(d, fence);
    device.set_name(VK_OBJECT_TYPE_FENCE, fence, "hemi one-shot fence");
}

VkCommandBuffer CommandContext::begin()
{
    HEMI_VK_CHECK(vkResetCommandBuffer(cmd_, 0));
    VkCommandBufferBeginInfo begin_info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin_info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    HEMI_VK_CHECK(vkBeginCommandBuffer(cmd_, &begin_info));
    return cmd_;
}

void CommandContext::submit_and_wait()
{
    HEMI_VK_CHECK(vkEndCommandBuffer(cmd_));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd_;
    VkFence fence = fence_;
    HEMI_VK_CHECK(vkQueueSubmit(device_->queue(), 1, &submit, fence));
    HEMI_VK_CHECK(vkWaitForFences(device_->device(), 1, &fence, VK_TRUE, UINT64_MAX));
    HEMI_VK_CHECK(vkResetFences(device_->device(), 1, &fence));
}

void CommandContext::run(const std::function<void(VkCommandBuffer)>& record)
{
    record(begin());
    submit_and_wait();
}

void one_shot(const Device& device, const std::function<void(VkCommandBuffer)>& record)
{
    CommandContext ctx(device);
    ctx.run(record);
}

TimestampQueries::TimestampQueries(const Device& device, uint32_t count)
    : device_(device.device()), count_(count), period_ns_(device.timestamp_period_ns())
{
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = count;
    VkQueryPool pool;
    HEMI_VK_CHECK(vkCreateQueryPool(device_, &info, nullptr, &pool));
    pool_ = QueryPool(device_, pool);
    device.set_name(VK_OBJECT_TYPE_QUERY_POOL, pool, "hemi timestamp queries");
}

void TimestampQueries::reset(VkCommandBuffer cmd)
{
    vkCmdResetQueryPool(cmd, pool_, 0, count_);
}

void TimestampQueries::write(VkCommandBuffer cmd, uint32_t index, VkPipelineStageFlagBits stage)
{
    if (index >= count_)
        throw std::out_of_range("hemi: timestamp query index out of range");
    vkCmdWriteTimestamp(cmd, stage, pool_, index);
}

std::vector<double> TimestampQueries::read_ns()
{
    if (!supported())
        throw std::runtime_error("hemi: the device queue does not support timestamps");
    std::vector<uint64_t> ticks(count_);
    HEMI_VK_CHECK(vkGetQueryPoolResults(device_, pool_, 0, count_, ticks.size() * sizeof(uint64_t),
                                        ticks.data(), sizeof(uint64_t),
                                        VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    std::vector<double> ns(count_);
    for (uint32_t i = 0; i < count_; ++i)
        ns[i] = double(ticks[i]) * period_ns_;
    return ns;
}

void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags src_stages, VkAccessFlags src_access,
                    VkPipelineStageFlags dst_stages, VkAccessFlags dst_access)
{
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = src_access;
    barrier.dstAccessMask = dst_access;
    vkCmdPipelineBarrier(cmd, src_stages, dst_stages, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

} // namespace hemi::gpu
