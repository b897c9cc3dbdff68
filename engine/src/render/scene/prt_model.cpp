#include "../passes/pass_detail.h"
#include <hemi/math/sh.h>
#include <hemi/render/scene/prt_model.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <stdexcept>

namespace hemi::render
{

std::vector<glm::vec3> object_lighting(std::span<const glm::vec3> world_lighting, int order,
                                       const glm::mat4& model, float rotate_degrees)
{
    const size_t l = size_t(order) * order;
    if (order < 1 || order > math::kMaxShOrder)
        throw std::invalid_argument("hemi: lighting SH order " + std::to_string(order) + " out of range");
    if (world_lighting.size() < l)
        throw std::invalid_argument("hemi: the lighting has " + std::to_string(world_lighting.size()) +
                                    " SH coefficients, the asset needs " + std::to_string(l));
    // The environment turned about world z (g(d) = f(Rz^T d): coefficients D(Rz) l, math::ShRotation's
    // contract), then seen in object coordinates (f_o(d) = g(M d): D(M^T)); D(A) D(B) = D(AB). The model's
    // uniform scale is divided out so that only its rotation acts.
    glm::mat3 linear(model);
    const float scale = std::cbrt(std::abs(glm::determinant(linear)));
    if (!(scale > 0.0f) || !std::isfinite(scale))
        throw std::invalid_argument("hemi: the model matrix is singular or not finite");
    linear /= scale;
    const glm::mat3 world_to_object = glm::transpose(linear);
    const glm::mat3 turn =
        glm::mat3(glm::rotate(glm::mat4(1.0f), glm::radians(rotate_degrees), glm::vec3(0.0f, 0.0f, 1.0f)));
    const math::ShRotation rotation(order, world_to_object * turn);
    std::vector<glm::vec3> out(l);
    rotation.apply(world_lighting.subspan(0, l), out);
    return out;
}

namespace
{
std::unique_ptr<CoefficientSource> make_source(const gpu::Device& device, const io::PrtAsset& asset,
                                               const PrtModelDesc& desc, gpu::UploadBatch& upload,
                                               gpu::DescriptorAllocator& descriptors)
{
    const io::PrtTechnique& t = asset.technique(desc.technique);
    const uint32_t n = uint32_t(asset.mesh.vertex_count());
    if (desc.cpca)
    {
        if (!t.cpca)
            throw std::invalid_argument("hemi: the asset has no CPCA data for '" + desc.technique +
                                        "' (bake it with --cpca)");
        const io::PrtCpca& c = *t.cpca;
        return std::make_unique<CpcaTransferPass>(
            device,
            CpcaMatrices{n, t.k, asset.l(), c.clusters, c.vectors, c.means, c.basis, c.cluster, c.weights},
            desc.instances * desc.frames_in_flight, &upload, &descriptors, desc.coefficient_output);
    }
    if (t.matrices.empty())
        throw std::invalid_argument("hemi: the asset holds only CPCA data for '" + desc.technique +
                                    "' (use --cpca)");
    return std::make_unique<TransferPass>(device, TransferMatrices(n, t.k, asset.l(), t.matrices), 0,
                                          desc.instances * desc.frames_in_flight, &upload, &descriptors,
                                          desc.coefficient_output);
}
} // namespace

PrtModel::PrtModel(MaterialSystem& system, const io::PrtAsset& asset, const PrtModelDesc& desc,
                   gpu::UploadBatch& upload)
    : system_(&system), instances_(desc.instances), frames_(desc.frames_in_flight), order_(asset.order),
      basis_(&math::technique(desc.technique)),
      surfaces_(system, asset.mesh, asset.images, asset.materials, asset.primitives,
                CoefficientSourceKind::Vertex, {SurfaceVariant{Technique::Irradiance, basis_->id}}, upload,
                desc.geometry)
{
    const gpu::Device& device = system.device();
    if (desc.instances == 0 || desc.frames_in_flight == 0)
        throw std::invalid_argument("hemi: a PRT model needs at least one instance and one frame in flight");
    source_ = make_source(device, asset, desc, upload, system.descriptors());
    if (int(source_->k()) != basis_->size)
        throw std::invalid_argument("hemi: technique '" + desc.technique +
                                    "' has K = " + std::to_string(source_->k()) +
                                    " in the asset, its basis needs " + std::to_string(basis_->size));
    coefficient_set_ = std::make_unique<VertexCoefficients>(
        system, source_->coefficients(), source_->instance_stride() * source_->instances());
}

PrtModel::~PrtModel() = default;

uint32_t PrtModel::first_instance(uint32_t frame) const
{
    if (frame >= frames_)
        throw std::invalid_argument("hemi: frame slot " + std::to_string(frame) +
                                    " of a PRT model made for " + std::to_string(frames_) +
                                    " frame(s) in flight");
    return frame * instances_;
}

std::vector<glm::vec3> PrtModel::lighting_of(std::span<const PrtInstance> instances) const
{
    std::vector<glm::vec3> lighting;
    lighting.reserve(instances.size() * l());
    for (const PrtInstance& i : instances)
    {
        const std::vector<glm::vec3> o =
            object_lighting(i.world_lighting, int(order_), i.model, i.rotate_degrees);
        lighting.insert(lighting.end(), o.begin(), o.end());
    }
    return lighting;
}

void PrtModel::record_transfer(VkCommandBuffer cmd, std::span<const PrtInstance> instances, uint32_t frame,
                               AccessList& accesses)
{
    record_transfer_object_space(cmd, lighting_of(instances), frame, accesses);
}

void PrtModel::record_transfer_object_space(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                                            uint32_t frame, AccessList& accesses)
{
    if (lighting.size() > size_t(instances_) * l())
        throw std::invalid_argument("hemi: lighting for " + std::to_string(lighting.size() / l()) +
                                    " instances of a PRT model made for " + std::to_string(instances_));
    source_->record(cmd, lighting, first_instance(frame), &accesses);
}

void PrtModel::record_transfer(VkCommandBuffer cmd, std::span<const PrtInstance> instances, uint32_t frame,
                               bool to_vertex_shaders)
{
    record_transfer_object_space(cmd, lighting_of(instances), frame, to_vertex_shaders);
}

void PrtModel::record_transfer_object_space(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                                            uint32_t frame, bool to_vertex_shaders)
{
    // Earlier uses of the slot's coefficients (any stage of this queue) before the pass overwrites them.
    const uint32_t first = first_instance(frame);
    const BufferAccess earlier =
        source_->coefficient_access(first, instances_, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                    VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    const BufferAccess write = source_->coefficient_access(
        first, instances_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    record_barrier(cmd, {&earlier, 1}, {&write, 1});
    AccessList accesses;
    record_transfer_object_space(cmd, lighting, frame, accesses);
    if (to_vertex_shaders)
        record_barrier(cmd, accesses.accesses(), draw_accesses(frame).accesses());
}

void PrtModel::draw_accesses(uint32_t frame, AccessList& accesses, bool as_stream) const
{
    accesses.add(source_->coefficient_access(
        first_instance(frame), instances_,
        as_stream ? VK_PIPELINE_STAGE_VERTEX_INPUT_BIT : VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
        as_stream ? VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT : VK_ACCESS_SHADER_READ_BIT));
}

VkDeviceSize PrtModel::coefficient_bytes(const gpu::Device& device, const io::PrtAsset& asset,
                                         const PrtModelDesc& desc)
{
    const io::PrtTechnique& t = asset.technique(desc.technique);
    const uint32_t instances = desc.instances * desc.frames_in_flight;
    return detail::instance_layout(device, instances, uint32_t(asset.mesh.vertex_count()), t.k)
               .coefficient_stride *
           16 * instances;
}

gpu::BufferRange PrtModel::coefficient_stream(uint32_t instance, uint32_t frame) const
{
    if (instance >= instances_)
        throw std::invalid_argument("hemi: instance " + std::to_string(instance) +
                                    " of a PRT model made for " + std::to_string(instances_));
    const BufferAccess a = source_->coefficient_access(first_instance(frame) + instance, 1, 0, 0);
    return {a.buffer, a.offset, VkDeviceSize(source_->vertex_count()) * coefficient_stride()};
}

AccessList PrtModel::draw_accesses(uint32_t frame) const
{
    AccessList accesses;
    draw_accesses(frame, accesses);
    return accesses;
}

PrtModel::BufferRange PrtModel::coefficient_range(uint32_t frame) const
{
    const BufferAccess a = source_->coefficient_access(first_instance(frame), instances_, 0, 0);
    return {a.buffer, a.offset, a.size};
}

void PrtModel::draw(VkCommandBuffer cmd, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model,
                    size_t pass, uint32_t frame_slot) const
{
    if (instance >= instances_)
        throw std::invalid_argument("hemi: instance " + std::to_string(instance) + " of a model made for " +
                                    std::to_string(instances_));
    surfaces_.draw(cmd, frame, coefficient_set_->set(),
                   uint32_t(source_->instance_offset(first_instance(frame_slot) + instance)), model, 0, pass);
}

void PrtModel::enqueue(DrawQueue& queue, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model,
                       size_t pass, uint32_t frame_slot, uint32_t layer, float depth) const
{
    if (instance >= instances_)
        throw std::invalid_argument("hemi: instance " + std::to_string(instance) + " of a model made for " +
                                    std::to_string(instances_));
    surfaces_.enqueue(queue, frame, coefficient_set_->set(),
                      uint32_t(source_->instance_offset(first_instance(frame_slot) + instance)), model, 0,
                      pass, layer, depth);
}

void PrtModel::enqueue_instances(DrawQueue& queue, VkDescriptorSet frame, InstanceRange instances,
                                 size_t pass, uint32_t layer, float depth) const
{
    if (instances.count == 0)
        throw std::invalid_argument("hemi: an instanced draw of 0 instances");
    surfaces_.enqueue(queue, frame, coefficient_set_->set(), 0, glm::mat4(1.0f), 0, pass, layer, depth,
                      instances);
}

shared::DrawPush PrtModel::instance_record(uint32_t instance, const glm::mat4& model,
                                           uint32_t frame_slot) const
{
    if (instance >= instances_)
        throw std::invalid_argument("hemi: instance " + std::to_string(instance) + " of a model made for " +
                                    std::to_string(instances_));
    shared::DrawPush r{};
    r.model = model;
    r.coefficient_offset = uint32_t(source_->instance_offset(first_instance(frame_slot) + instance));
    return r;
}

} // namespace hemi::render
