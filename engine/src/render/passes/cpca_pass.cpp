#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/upload.h>
#include <hemi/render/passes/cpca_pass.h>

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

struct CpcaTransferPass::Impl
{
    const gpu::Device* device;
    uint32_t n, k, l, rows, per_cluster;
    InstanceLayout instances;
    VkDeviceSize projected_instance_bytes = 0; // one instance's projections, aligned
    VkDeviceSize projected_stride; // bytes between clusters' projections (aligned for dynamic offsets)
    struct Run
    {
        uint32_t cluster, first_invocation, invocations;
    };
    std::vector<Run> runs; // one dispatch per non-empty cluster
    gpu::Buffer rows_buffer, lighting, projected, weights, slots;
    CoefficientStore coefficients;
    gpu::BufferView coefficient_view, weight_view;
    gpu::Program project, reconstruct;
    std::vector<gpu::Binding> project_bindings, reconstruct_bindings;
    PassDescriptors descriptors;
    std::vector<gpu::BufferView> instance_views;
    std::vector<gpu::DescriptorSet> project_sets, reconstruct_sets; // one each per instance
};

CpcaTransferPass::CpcaTransferPass(const gpu::Device& device, const CpcaMatrices& c, uint32_t instances,
                                   gpu::UploadBatch* upload, gpu::DescriptorAllocator* descriptors,
                                   const gpu::BufferRange& output)
    : impl_(std::make_unique<Impl>())
{
    auto put = [&](const gpu::Buffer& b, const void* data, VkDeviceSize size)
    { upload ? upload->buffer(b, data, size) : gpu::write_buffer(device, b, data, size); };
    validate_cpca(c);
    Impl& s = *impl_;
    s.device = &device;
    s.n = c.vertex_count;
    s.k = c.k;
    s.l = c.l;
    s.instances = instance_layout(device, instances, s.n, s.k);
    const size_t d = size_t(c.k) * c.l;
    s.rows = c.clusters * (c.vectors + 1) * c.k;
    s.per_cluster = (c.vectors + 1) * c.k;
    const VkPhysicalDeviceLimits& limits = device.limits();
    auto storage = [&](VkDeviceSize bytes, const char* what)
    {
        if (bytes > limits.maxStorageBufferRange)
            throw std::runtime_error("hemi: CPCA " + std::string(what) + " (" + std::to_string(bytes) +
                                     " bytes) exceed the device's maxStorageBufferRange");
        return gpu::create_buffer(device, {bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT});
    };
    if (c.vectors > HEMI_CPCA_MAX_VECTORS)
        throw std::invalid_argument("hemi: the CPCA pass supports up to " +
                                    std::to_string(HEMI_CPCA_MAX_VECTORS) + " vectors per cluster, got " +
                                    std::to_string(c.vectors));
    // Rows: per cluster, the mean then the V vectors, each K x L.
    std::vector<float> rows(size_t(s.rows) * c.l);
    for (uint32_t cl = 0; cl < c.clusters; ++cl)
    {
        std::copy_n(&c.means[cl * d], d, &rows[size_t(cl) * (c.vectors + 1) * d]);
        std::copy_n(&c.basis[size_t(cl) * c.vectors * d], size_t(c.vectors) * d,
                    &rows[(size_t(cl) * (c.vectors + 1) + 1) * d]);
    }
    // Slots: vertices grouped by cluster, each cluster's run padded to whole 32-slot blocks (one dispatch per
    // cluster); weights element-interleaved in blocks of 32 slots, as the dense matrices are.
    constexpr uint32_t kNone = 0xffffffffu, kBlock = HEMI_TRANSFER_BLOCK_VERTICES;
    std::vector<std::vector<uint32_t>> members(c.clusters);
    for (uint32_t v = 0; v < c.vertex_count; ++v)
        members[c.cluster[v]].push_back(v);
    std::vector<uint32_t> slot_vertex;
    uint32_t largest_run = 0;
    for (uint32_t cl = 0; cl < c.clusters; ++cl)
    {
        if (members[cl].empty())
            continue;
        const uint32_t first = uint32_t(slot_vertex.size() / HEMI_TRANSFER_VERTICES_PER_INVOCATION);
        slot_vertex.insert(slot_vertex.end(), members[cl].begin(), members[cl].end());
        slot_vertex.resize((slot_vertex.size() + kBlock - 1) / kBlock * kBlock, kNone);
        const uint32_t count = uint32_t(slot_vertex.size() / HEMI_TRANSFER_VERTICES_PER_INVOCATION) - first;
        s.runs.push_back({cl, first, count});
        largest_run = std::max(largest_run, count);
    }
    const VkDeviceSize align = std::max<VkDeviceSize>(1, limits.minUniformBufferOffsetAlignment);
    s.projected_stride = (VkDeviceSize(c.vectors + 1) * c.k * 16 + align - 1) / align * align;
    if (HEMI_CPCA_PROJECTED_BYTES > limits.maxUniformBufferRange)
        throw std::runtime_error(
            "hemi: the device's maxUniformBufferRange is below the CPCA pass's uniform block");
    const uint32_t V = c.vectors, per_block = HEMI_TRANSFER_INVOCATIONS_PER_BLOCK;
    std::vector<float> interleaved(slot_vertex.size() * V, 0.0f);
    for (size_t slot = 0; slot < slot_vertex.size(); ++slot)
    {
        if (slot_vertex[slot] == kNone)
            continue;
        const size_t invocation = slot / 4, block = invocation / per_block, lane = invocation % per_block;
        for (uint32_t j = 0; j < V; ++j)
            interleaved[((block * V + j) * per_block + lane) * 4 + slot % 4] =
                c.weights[size_t(slot_vertex[slot]) * V + j];
    }
    if ((uint64_t(largest_run) + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE >
            limits.maxComputeWorkGroupCount[0] ||
        (uint64_t(s.rows) + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE >
            limits.maxComputeWorkGroupCount[0])
        throw std::runtime_error("hemi: CPCA pass over " + std::to_string(s.n) +
                                 " vertices exceeds the device's maxComputeWorkGroupCount");
    if (uint64_t(s.n) * s.k > limits.maxTexelBufferElements ||
        interleaved.size() / 4 > limits.maxTexelBufferElements)
        throw std::runtime_error("hemi: CPCA data of " + std::to_string(s.n) +
                                 " vertices exceed the device's maxTexelBufferElements");
    s.rows_buffer = storage(rows.size() * 4, "cluster matrices");
    put(s.rows_buffer, rows.data(), rows.size() * 4);
    s.weights =
        gpu::create_buffer(device, {interleaved.size() * 4, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
    put(s.weights, interleaved.data(), interleaved.size() * 4);
    s.weight_view =
        gpu::create_buffer_view(device, s.weights, VK_FORMAT_R32G32B32A32_SFLOAT, 0, interleaved.size() * 4);
    s.slots = storage(slot_vertex.size() * 4, "vertex slots");
    put(s.slots, slot_vertex.data(), slot_vertex.size() * 4);
    // Written by step 1 as a storage buffer, read by step 2 as a uniform block at a dynamic offset: cluster
    // c's projections start at c * stride.
    if (s.projected_stride * (c.clusters - 1) + HEMI_CPCA_PROJECTED_BYTES > limits.maxStorageBufferRange)
        throw std::runtime_error("hemi: CPCA projections of " + std::to_string(c.clusters) +
                                 " clusters exceed the device's maxStorageBufferRange");
    const VkDeviceSize projected_bytes = s.projected_stride * (c.clusters - 1) + HEMI_CPCA_PROJECTED_BYTES;
    s.projected_instance_bytes = align_up(projected_bytes, std::max(limits.minUniformBufferOffsetAlignment,
                                                                    limits.minStorageBufferOffsetAlignment));
    s.projected =
        gpu::create_buffer(device, {s.projected_instance_bytes * instances,
                                    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    s.lighting = create_lighting_buffer(device, s.instances.lighting_stride, instances);
    s.coefficients = coefficient_store(device, s.instances.coefficient_stride * 16 * instances, output);

    const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
    s.project_bindings = {
        {HEMI_CPCA_BINDING_ROWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
        {HEMI_CPCA_BINDING_LIGHTING, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, cs},
        {HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
    };
    s.reconstruct_bindings = {
        {HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, cs},
        {HEMI_CPCA_BINDING_WEIGHTS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, cs},
        {HEMI_CPCA_BINDING_SLOTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs},
        {HEMI_CPCA_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, cs},
    };
    s.project = gpu::create_compute_program(
        device, {gpu::embedded_spirv("cpca_project.comp"), s.project_bindings, sizeof(CpcaPush), {s.l}});
    s.reconstruct = gpu::create_compute_program(device, {gpu::embedded_spirv("cpca_reconstruct.comp"),
                                                         s.reconstruct_bindings,
                                                         sizeof(CpcaPush),
                                                         {s.k, c.vectors}});
    s.descriptors = pass_descriptors(device, descriptors, 2 * instances);
    auto buffer_write =
        [](uint32_t binding, VkDescriptorType type, VkBuffer buffer, VkDeviceSize offset, VkDeviceSize range)
    {
        gpu::DescriptorWrite w;
        w.binding = binding;
        w.type = type;
        w.buffer = {buffer, offset, range};
        return w;
    };
    for (uint32_t i = 0; i < instances; ++i)
    {
        const VkDeviceSize projected_base = i * s.projected_instance_bytes;
        const VkDeviceSize coefficient_base = i * s.instances.coefficient_stride * 16;
        s.instance_views.push_back(gpu::create_buffer_view(
            device, s.coefficients.range.buffer, VK_FORMAT_R32G32B32A32_SFLOAT,
            s.coefficients.range.offset + coefficient_base, VkDeviceSize(s.n) * s.k * 16));
        gpu::DescriptorSet project_set =
            s.descriptors.allocator->allocate(s.project.set_layout, s.project_bindings);
        gpu::DescriptorSet reconstruct_set =
            s.descriptors.allocator->allocate(s.reconstruct.set_layout, s.reconstruct_bindings);
        gpu::DescriptorWrite project_writes[3] = {
            buffer_write(HEMI_CPCA_BINDING_ROWS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, s.rows_buffer, 0,
                         VK_WHOLE_SIZE),
            buffer_write(HEMI_CPCA_BINDING_LIGHTING, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, s.lighting, 0,
                         HEMI_TRANSFER_MAX_L * 16),
            buffer_write(HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, s.projected,
                         projected_base, projected_bytes),
        };
        gpu::write_descriptors(device, project_set, project_writes);
        gpu::DescriptorWrite reconstruct_writes[4] = {
            buffer_write(HEMI_CPCA_BINDING_PROJECTED, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER_DYNAMIC, s.projected,
                         projected_base, HEMI_CPCA_PROJECTED_BYTES),
            {},
            buffer_write(HEMI_CPCA_BINDING_SLOTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, s.slots, 0,
                         VK_WHOLE_SIZE),
            {},
        };
        reconstruct_writes[1].binding = HEMI_CPCA_BINDING_WEIGHTS;
        reconstruct_writes[1].type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
        reconstruct_writes[1].texel_view = s.weight_view;
        reconstruct_writes[3].binding = HEMI_CPCA_BINDING_COEFFICIENTS;
        reconstruct_writes[3].type = VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
        reconstruct_writes[3].texel_view = s.instance_views.back();
        gpu::write_descriptors(device, reconstruct_set, reconstruct_writes);
        s.project_sets.push_back(std::move(project_set));
        s.reconstruct_sets.push_back(std::move(reconstruct_set));
    }
}

CpcaTransferPass::~CpcaTransferPass() = default;

void CpcaTransferPass::record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                              uint32_t first_instance, AccessList* accesses)
{
    Impl& s = *impl_;
    const uint32_t count = lighting_instances(lighting, s.l, s.instances.count, first_instance);
    const uint32_t instances = first_instance + count;
    write_lighting(s.lighting, lighting, s.l, s.instances.lighting_stride, first_instance);
    if (accesses)
    {
        for (const gpu::Buffer* b : {&s.rows_buffer, &s.weights, &s.slots})
            accesses->add(
                {b->handle(), 0, b->size(), VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT});
        accesses->add({s.lighting.handle(), first_instance * s.instances.lighting_stride,
                       count * s.instances.lighting_stride, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_ACCESS_UNIFORM_READ_BIT});
        accesses->add(coefficient_access(first_instance, count, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                         VK_ACCESS_SHADER_WRITE_BIT));
    }
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.project.pipeline);
    const CpcaPush push{s.rows, 0, s.per_cluster, uint32_t(s.projected_stride / 16)};
    vkCmdPushConstants(cmd, s.project.layout, VK_SHADER_STAGE_ALL, 0, sizeof push, &push);
    for (uint32_t i = first_instance; i < instances; ++i)
    {
        const uint32_t lighting_offset = uint32_t(i * s.instances.lighting_stride);
        const VkDescriptorSet set = s.project_sets[i];
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.project.layout, 0, 1, &set, 1,
                                &lighting_offset);
        vkCmdDispatch(cmd, (s.rows + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE, 1, 1);
    }
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_UNIFORM_READ_BIT);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.reconstruct.pipeline);
    for (uint32_t i = first_instance; i < instances; ++i)
        for (const Impl::Run& run : s.runs)
        {
            const uint32_t offset = uint32_t(run.cluster * s.projected_stride);
            const VkDescriptorSet set = s.reconstruct_sets[i];
            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s.reconstruct.layout, 0, 1, &set, 1,
                                    &offset);
            const CpcaPush run_push{run.invocations, run.first_invocation, 0, 0};
            vkCmdPushConstants(cmd, s.reconstruct.layout, VK_SHADER_STAGE_ALL, 0, sizeof run_push, &run_push);
            vkCmdDispatch(cmd,
                          (run.invocations + HEMI_TRANSFER_WORKGROUP_SIZE - 1) / HEMI_TRANSFER_WORKGROUP_SIZE,
                          1, 1);
        }
}

gpu::BufferRange CpcaTransferPass::coefficients() const
{
    return impl_->coefficients.range;
}

void CpcaTransferPass::write_coefficients(std::span<const float> coefficients)
{
    detail::write_coefficients(*impl_->device, impl_->coefficients, coefficients, impl_->n, impl_->k);
}
uint32_t CpcaTransferPass::instances() const
{
    return impl_->instances.count;
}
uint64_t CpcaTransferPass::instance_stride() const
{
    return impl_->instances.coefficient_stride;
}
uint32_t CpcaTransferPass::vertex_count() const
{
    return impl_->n;
}
uint32_t CpcaTransferPass::k() const
{
    return impl_->k;
}
uint32_t CpcaTransferPass::l() const
{
    return impl_->l;
}
const gpu::Device& CpcaTransferPass::device() const
{
    return *impl_->device;
}

} // namespace hemi::render
