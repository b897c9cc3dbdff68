#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/upload.h>
#include <hemi/render/passes/transfer_pass.h>

#include "pass_detail.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hemi::render
{
using namespace detail;

static_assert(sizeof(TransferPush) == 4);

struct TransferPass::Impl
{
    const gpu::Device* device;
    uint32_t n, k, l;
    InstanceLayout instances;
    gpu::Buffer matrices;
    gpu::Buffer lighting;
    CoefficientStore coefficients;
    gpu::Program program;
    std::vector<gpu::Binding> bindings;
    PassDescriptors descriptors;
    struct Segment
    {
        gpu::BufferView matrix_view;
        gpu::BufferView coefficient_view;
        gpu::DescriptorSet set;
        uint32_t vertex_count;
    };
    std::vector<Segment> segments; // instance i's segment s at i * segment_count + s
    uint32_t segment_count = 0;
};

static std::vector<gpu::Binding> transfer_bindings()
{
    return {
        {HEMI_TRANSFER_BINDING_MATRICES, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
         VK_SHADER_STAGE_COMPUTE_BIT},
        {HEMI_TRANSFER_BINDING_LIGHTING, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC,
         VK_SHADER_STAGE_COMPUTE_BIT},
        {HEMI_TRANSFER_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER,
         VK_SHADER_STAGE_COMPUTE_BIT},
    };
}

TransferPass::TransferPass(const gpu::Device& device, const TransferMatrices& m, uint64_t max_view_texels,
                           uint32_t instances, gpu::UploadBatch* upload,
                           gpu::DescriptorAllocator* descriptors, const gpu::BufferRange& output)
    : impl_(std::make_unique<Impl>())
{
    auto put = [&](const gpu::Buffer& b, const void* data, VkDeviceSize size)
    { upload ? upload->buffer(b, data, size) : gpu::write_buffer(device, b, data, size); };
    Impl& s = *impl_;
    s.device = &device;
    s.n = m.vertex_count();
    s.k = m.k();
    s.l = m.l();
    s.instances = instance_layout(device, instances, s.n, s.k);

    const VkDeviceSize matrix_bytes = m.data().size_bytes();
    s.matrices = gpu::create_buffer(device, {matrix_bytes, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
    put(s.matrices, m.data().data(), matrix_bytes);
    s.lighting = create_lighting_buffer(device, s.instances.lighting_stride, instances);
    s.coefficients = coefficient_store(device, s.instances.coefficient_stride * 16 * instances, output);

    s.bindings = transfer_bindings();
    s.program = gpu::create_compute_program(
        device, {gpu::embedded_spirv("prt_transfer.comp"), s.bindings, sizeof(TransferPush), {s.k, s.l}});
    device.set_name(VK_OBJECT_TYPE_BUFFER, s.matrices.handle(), "hemi PRT transfer matrices");
    device.set_name(VK_OBJECT_TYPE_PIPELINE, s.program.pipeline.get(), "hemi PRT transfer pass");

    // Segments: whole blocks, at most maxTexelBufferElements texels of matrices (and of coefficients) per
    // view, with view offsets that respect minTexelBufferOffsetAlignment.
    const VkPhysicalDeviceLimits& limits = device.limits();
    const uint64_t block_texels = uint64_t(s.k) * s.l * HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    const uint64_t block_bytes = block_texels * 16;
    const uint64_t out_block_bytes = uint64_t(HEMI_TRANSFER_BLOCK_VERTICES) * s.k * 16;
    uint64_t max_texels = limits.maxTexelBufferElements;
    if (max_view_texels != 0)
        max_texels = std::min<uint64_t>(max_texels, max_view_texels);
    uint64_t blocks_per_segment = max_texels / block_texels;
    blocks_per_segment =
        std::min<uint64_t>(blocks_per_segment, max_texels / (HEMI_TRANSFER_BLOCK_VERTICES * s.k));
    // One dispatch per segment: its workgroup count must stay within maxComputeWorkGroupCount[0] (65,535 on
    // many drivers, reached by K = 3, L = 9 sets of ~17M vertices before the texel limit is).
    blocks_per_segment = std::min<uint64_t>(blocks_per_segment, uint64_t(limits.maxComputeWorkGroupCount[0]) *
                                                                    HEMI_TRANSFER_WORKGROUP_SIZE /
                                                                    HEMI_TRANSFER_INVOCATIONS_PER_BLOCK);
    const uint64_t align = std::max<uint64_t>(1, limits.minTexelBufferOffsetAlignment);
    const uint64_t step =
        std::lcm(align / std::gcd(align, block_bytes), align / std::gcd(align, out_block_bytes));
    blocks_per_segment -= blocks_per_segment % step;
    if (blocks_per_segment == 0)
        throw std::runtime_error("hemi: device " + std::string(device.name()) +
                                 " cannot hold one block of transfer matrices in a texel buffer");

    const uint32_t total_blocks = m.block_count();
    const uint32_t segment_count = uint32_t((total_blocks + blocks_per_segment - 1) / blocks_per_segment);
    s.segment_count = segment_count;
    s.descriptors = pass_descriptors(device, descriptors, segment_count * instances);
    for (uint32_t instance = 0; instance < instances; ++instance)
        for (uint32_t i = 0; i < segment_count; ++i)
        {
            const VkDeviceSize instance_base = instance * s.instances.coefficient_stride * 16;
            uint64_t first_block = i * blocks_per_segment;
            uint64_t blocks = std::min<uint64_t>(blocks_per_segment, total_blocks - first_block);
            uint64_t first_vertex = first_block * HEMI_TRANSFER_BLOCK_VERTICES;
            Impl::Segment seg;
            seg.vertex_count =
                uint32_t(std::min<uint64_t>(blocks * HEMI_TRANSFER_BLOCK_VERTICES, s.n - first_vertex));
            seg.matrix_view = gpu::create_buffer_view(device, s.matrices, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                      first_block * block_bytes, blocks * block_bytes);
            seg.coefficient_view =
                gpu::create_buffer_view(device, s.coefficients.range.buffer, VK_FORMAT_R32G32B32A32_SFLOAT,
                                        s.coefficients.range.offset + instance_base + first_vertex * s.k * 16,
                                        uint64_t(seg.vertex_count) * s.k * 16);
            seg.set = s.descriptors.allocator->allocate(s.program.set_layout, s.bindings);
            gpu::DescriptorWrite writes[3];
            writes[0].binding = HEMI_TRANSFER_BINDING_MATRICES;
            writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
            writes[0].texel_view = seg.matrix_view;
            writes[1].binding = HEMI_TRANSFER_BINDING_LIGHTING;
            writes[1].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC;
            writes[1].buffer = {s.lighting, 0, HEMI_TRANSFER_MAX_L * 16};
            writes[2].binding = HEMI_TRANSFER_BINDING_COEFFICIENTS;
            writes[2].type = VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
            writes[2].texel_view = seg.coefficient_view;
            gpu::write_descriptors(device, seg.set, writes);
            s.segments.push_back(std::move(seg));
        }
}

TransferPass::~TransferPass() = default;

void TransferPass::record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting, uint32_t first_instance,
                          AccessList* accesses)
{
    Impl& s = *impl_;
    const uint32_t instances = lighting_instances(lighting, s.l, s.instances.count, first_instance);
    write_lighting(s.lighting, lighting, s.l, s.instances.lighting_stride, first_instance);
    if (accesses)
    {
        accesses->add({s.matrices.handle(), 0, s.matrices.size(), VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_ACCESS_SHADER_READ_BIT});
        accesses->add({s.lighting.handle(), first_instance * s.instances.lighting_stride,
                       instances * s.instances.lighting_stride, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_ACCESS_UNIFORM_READ_BIT});
        accesses->add(coefficient_access(first_instance, instances, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                         VK_ACCESS_SHADER_WRITE_BIT));
    }
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.program.pipeline);
    for (uint32_t i = first_instance * s.segment_count; i < (first_instance + instances) * s.segment_count;
         ++i)
    {
        const Impl::Segment& seg = s.segments[i];
        const uint32_t offset = uint32_t((i / s.segment_count) * s.instances.lighting_stride);
        const VkDescriptorSet set = seg.set;
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.program.layout, 0, 1, &set, 1,
                                &offset);
        TransferPush push{seg.vertex_count};
        vkCmdPushConstants(cmd, s.program.layout, VK_SHADER_STAGE_ALL, 0, sizeof push, &push);
        uint32_t invocations = (seg.vertex_count + HEMI_TRANSFER_VERTICES_PER_INVOCATION - 1) /
                               HEMI_TRANSFER_VERTICES_PER_INVOCATION;
        vkCmdDispatch(cmd, (invocations + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE, 1,
                      1);
    }
}

gpu::BufferRange TransferPass::coefficients() const
{
    return impl_->coefficients.range;
}

void TransferPass::write_coefficients(std::span<const float> coefficients)
{
    detail::write_coefficients(*impl_->device, impl_->coefficients, coefficients, impl_->n, impl_->k);
}

uint32_t TransferPass::vertex_count() const
{
    return impl_->n;
}
uint32_t TransferPass::k() const
{
    return impl_->k;
}
uint32_t TransferPass::l() const
{
    return impl_->l;
}
uint32_t TransferPass::segment_count() const
{
    return impl_->segment_count;
}
uint32_t TransferPass::instances() const
{
    return impl_->instances.count;
}
uint64_t TransferPass::instance_stride() const
{
    return impl_->instances.coefficient_stride;
}
const gpu::Device& TransferPass::device() const
{
    return *impl_->device;
}

} // namespace hemi::render
