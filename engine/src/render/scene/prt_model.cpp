#include "../passes/pass_detail.h"
#include "../refuse.h"
#include <hemi/math/sh.h>
#include <hemi/render/scene/prt_model.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <stdexcept>

namespace hemi::render
{

namespace
{
// What turns world lighting into the object frame of `model`, after the environment's turn of
// `rotate_degrees` about world z: the environment turned (g(d) = f(Rz^T d): coefficients D(Rz) l,
// math::ShRotation's contract), then seen in object coordinates (f_o(d) = g(M d): D(M^T)); D(A) D(B) =
// D(AB). The model's uniform scale is divided out so that only its rotation acts. False for a singular or
// non-finite matrix.
bool object_rotation(const glm::mat4& model, float rotate_degrees, glm::mat3& out) noexcept
{
    glm::mat3 linear(model);
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(linear[c].x + linear[c].y + linear[c].z))
            return false;
    const float scale = std::cbrt(std::abs(glm::determinant(linear)));
    if (!(scale > 0.0f) || !std::isfinite(scale) || !std::isfinite(rotate_degrees))
        return false;
    linear /= scale;
    // A finite matrix far from a rotation (one axis 1e38, the others 1e-20) overflows here.
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(linear[c].x + linear[c].y + linear[c].z))
            return false;
    const glm::mat3 turn =
        glm::mat3(glm::rotate(glm::mat4(1.0f), glm::radians(rotate_degrees), glm::vec3(0.0f, 0.0f, 1.0f)));
    out = glm::transpose(linear) * turn;
    return true;
}
} // namespace

std::vector<glm::vec3> object_lighting(std::span<const glm::vec3> world_lighting, int order,
                                       const glm::mat4& model, float rotate_degrees)
{
    const size_t l = size_t(order) * order;
    if (order < 1 || order > math::kMaxShOrder)
        throw std::invalid_argument("hemi: lighting SH order " + std::to_string(order) + " out of range");
    if (world_lighting.size() < l)
        throw std::invalid_argument("hemi: the lighting has " + std::to_string(world_lighting.size()) +
                                    " SH coefficients, the asset needs " + std::to_string(l));
    glm::mat3 rotation;
    if (!object_rotation(model, rotate_degrees, rotation))
        throw std::invalid_argument("hemi: the model matrix is singular or not finite");
    std::vector<glm::vec3> out(l);
    math::ShRotation(order, rotation).apply(world_lighting.subspan(0, l), out);
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
    lighting_.resize(size_t(instances_) * l());
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

bool PrtModel::check_slot(const char* call, uint32_t frame) const noexcept
{
    if (frame >= frames_)
        return detail::refuse(system_->device(), call,
                              "frame slot %u of a model made for %u frame(s) in flight", frame, frames_);
    return true;
}

bool PrtModel::check_instance(const char* call, uint32_t instance, uint32_t frame) const noexcept
{
    if (instance >= instances_)
        return detail::refuse(system_->device(), call, "instance %u of a model made for %u", instance,
                              instances_);
    return check_slot(call, frame);
}

bool PrtModel::check_lighting(const char* call, std::span<const glm::vec3> lighting,
                              uint32_t frame) const noexcept
{
    if (!check_slot(call, frame))
        return false;
    if (lighting.empty() || lighting.size() % l() != 0 || lighting.size() > size_t(instances_) * l())
        return detail::refuse(system_->device(), call,
                              "%zu lighting coefficients: L = %u for each of 1 to %u instance(s)",
                              lighting.size(), l(), instances_);
    for (size_t i = 0; i < lighting.size(); ++i)
        if (!std::isfinite(lighting[i].x + lighting[i].y + lighting[i].z))
            return detail::refuse(system_->device(), call,
                                  "instance %zu's lighting coefficient %zu is not finite", i / l(), i % l());
    return true;
}

bool PrtModel::lighting_of(std::span<const PrtInstance> instances) noexcept
{
    if (instances.size() > instances_)
        return detail::refuse(system_->device(), "PrtModel::record_transfer",
                              "%zu instances of a model made for %u", instances.size(), instances_);
    for (size_t i = 0; i < instances.size(); ++i)
    {
        const PrtInstance& in = instances[i];
        if (in.world_lighting.size() < l())
            return detail::refuse(system_->device(), "PrtModel::record_transfer",
                                  "instance %zu's lighting has %zu SH coefficients, the asset needs %u", i,
                                  in.world_lighting.size(), l());
        glm::mat3 rotation;
        if (!object_rotation(in.model, in.rotate_degrees, rotation))
            return detail::refuse(system_->device(), "PrtModel::record_transfer",
                                  "instance %zu's model matrix (or turn) is singular or not finite", i);
        math::ShRotation(int(order_), rotation)
            .apply(in.world_lighting.subspan(0, l()), std::span(lighting_).subspan(i * l(), l()));
    }
    return true;
}

bool PrtModel::record_transfer(VkCommandBuffer cmd, std::span<const PrtInstance> instances, uint32_t frame,
                               AccessList& accesses) noexcept
{
    return lighting_of(instances) &&
           record_transfer_object_space(cmd, std::span(lighting_).first(instances.size() * l()), frame,
                                        accesses);
}

bool PrtModel::record_transfer_object_space(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                                            uint32_t frame, AccessList& accesses) noexcept
{
    if (!check_lighting("PrtModel::record_transfer", lighting, frame))
        return false;
    source_->record(cmd, lighting, first_instance(frame), &accesses);
    return true;
}

bool PrtModel::record_transfer(VkCommandBuffer cmd, std::span<const PrtInstance> instances, uint32_t frame,
                               bool to_vertex_shaders) noexcept
{
    if (!lighting_of(instances))
        return false;
    const std::span<const glm::vec3> lighting = std::span(lighting_).first(instances.size() * l());
    if (!check_lighting("PrtModel::record_transfer", lighting, frame))
        return false;
    record_with_barriers(cmd, lighting, frame, to_vertex_shaders);
    return true;
}

bool PrtModel::record_transfer_object_space(VkCommandBuffer cmd, std::span<const glm::vec3> lighting,
                                            uint32_t frame, bool to_vertex_shaders) noexcept
{
    if (!check_lighting("PrtModel::record_transfer_object_space", lighting, frame))
        return false;
    record_with_barriers(cmd, lighting, frame, to_vertex_shaders);
    return true;
}

void PrtModel::record_with_barriers(VkCommandBuffer cmd, std::span<const glm::vec3> lighting, uint32_t frame,
                                    bool to_vertex_shaders) noexcept
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
    source_->record(cmd, lighting, first, &accesses);
    if (to_vertex_shaders)
        record_barrier(cmd, accesses.accesses(), draw_accesses(frame).accesses());
}

bool PrtModel::draw_accesses(uint32_t frame, AccessList& accesses, bool as_stream) const noexcept
{
    if (!check_slot("PrtModel::draw_accesses", frame))
        return false;
    accesses.add(source_->coefficient_access(
        first_instance(frame), instances_,
        as_stream ? VK_PIPELINE_STAGE_VERTEX_INPUT_BIT : VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
        as_stream ? VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT : VK_ACCESS_SHADER_READ_BIT));
    return true;
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

AccessList PrtModel::draw_accesses(uint32_t frame) const noexcept
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

bool PrtModel::draw(VkCommandBuffer cmd, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model,
                    size_t pass, uint32_t frame_slot) const noexcept
{
    if (!check_instance("PrtModel::draw", instance, frame_slot) ||
        !surfaces_.check("PrtModel::draw", frame, coefficient_set_->set(), 0, pass))
        return false;
    return surfaces_.draw(cmd, frame, coefficient_set_->set(),
                          uint32_t(source_->instance_offset(first_instance(frame_slot) + instance)), model, 0,
                          pass);
}

bool PrtModel::enqueue(DrawQueue& queue, VkDescriptorSet frame, uint32_t instance, const glm::mat4& model,
                       size_t pass, uint32_t frame_slot, uint32_t layer, float depth) const noexcept
{
    if (!check_instance("PrtModel::enqueue", instance, frame_slot) ||
        !surfaces_.check("PrtModel::enqueue", frame, coefficient_set_->set(), 0, pass))
        return false;
    return surfaces_.enqueue(queue, frame, coefficient_set_->set(),
                             uint32_t(source_->instance_offset(first_instance(frame_slot) + instance)), model,
                             0, pass, layer, depth);
}

bool PrtModel::enqueue_instances(DrawQueue& queue, VkDescriptorSet frame, InstanceRange instances,
                                 size_t pass, uint32_t layer, float depth) const noexcept
{
    if (instances.count == 0)
        return detail::refuse(system_->device(), "PrtModel::enqueue_instances",
                              "an instanced draw of 0 instances");
    if (!surfaces_.check("PrtModel::enqueue_instances", frame, coefficient_set_->set(), 0, pass))
        return false;
    return surfaces_.enqueue(queue, frame, coefficient_set_->set(), 0, glm::mat4(1.0f), 0, pass, layer, depth,
                             instances);
}

shared::DrawPush PrtModel::instance_record(uint32_t instance, const glm::mat4& model,
                                           uint32_t frame_slot) const noexcept
{
    shared::DrawPush r{};
    r.model = glm::mat4(0.0f);
    if (!check_instance("PrtModel::instance_record", instance, frame_slot))
        return r;
    r.model = model;
    r.coefficient_offset = uint32_t(source_->instance_offset(first_instance(frame_slot) + instance));
    return r;
}

} // namespace hemi::render
