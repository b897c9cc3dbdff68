#include "../refuse.h"

#include <hemi/math/basis.h>
#include <hemi/render/scene/scene_surfaces.h>

#include <glm/common.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::render
{

namespace
{
int basis_size(int id)
{
    if (id == math::vertex_irradiance_basis().id)
        return math::vertex_irradiance_basis().size;
    for (const math::BasisDesc& b : math::bases())
        if (b.id == id)
            return b.size;
    throw std::invalid_argument("hemi: unknown basis id " + std::to_string(id));
}
} // namespace

SceneSurfaces::SceneSurfaces(MaterialSystem& system, const io::Mesh& mesh,
                             const std::vector<io::EncodedImage>& images,
                             const std::vector<io::Material>& asset_materials,
                             const std::vector<io::Primitive>& asset_primitives, CoefficientSourceKind source,
                             const std::vector<SurfaceVariant>& variants, gpu::UploadBatch& upload,
                             const EngineGeometry* geometry)
    : system_(&system), textures_(system.device(), images, asset_materials, upload)
{
    if (variants.empty())
        throw std::invalid_argument("hemi: scene surfaces need at least one variant");
    if (geometry)
    {
        if (geometry->buffers.streams == 0 || geometry->buffers.streams > VertexLayout::kMaxVertexStreams ||
            geometry->buffers.index_buffer == VK_NULL_HANDLE)
            throw std::invalid_argument(
                "hemi: the engine's geometry needs 1 to 4 vertex streams and an index "
                "buffer");
        for (uint32_t i = 0; i < geometry->buffers.streams; ++i)
            if (geometry->buffers.vertex_buffers[i] == VK_NULL_HANDLE)
                throw std::invalid_argument("hemi: the engine's vertex stream " + std::to_string(i) +
                                            " has no buffer");
        const VertexLayout& l = geometry->layout;
        for (const VertexInput* input : {&l.position, &l.normal, &l.tangent, &l.uv0, &l.uv1})
            if (input->binding >= geometry->buffers.streams)
                throw std::invalid_argument("hemi: the engine's layout reads stream " +
                                            std::to_string(input->binding) + ", but its geometry binds " +
                                            std::to_string(geometry->buffers.streams) + " stream(s)");
        engine_buffers_ = geometry->buffers;
        binding_ = &engine_buffers_;
    }
    else
    {
        mesh_ = std::make_unique<GpuMesh>(system.device(), mesh, upload);
        binding_ = &mesh_->binding();
    }
    std::vector<io::Material> materials = asset_materials;
    if (materials.empty())
        materials.emplace_back(); // glTF's default material
    for (const io::Material& m : materials)
        materials_.push_back(std::make_unique<MaterialInstance>(system, textures_, m, upload));
    material_data_ = materials;
    std::vector<io::Primitive> primitives = asset_primitives;
    if (primitives.empty())
        primitives.push_back({0, uint32_t(mesh.indices.size()), 0});
    if (geometry && !geometry->primitives.empty() && geometry->primitives.size() != primitives.size())
        throw std::invalid_argument("hemi: the engine's geometry maps " +
                                    std::to_string(geometry->primitives.size()) +
                                    " primitives, the asset has " + std::to_string(primitives.size()));
    for (size_t i = 0; i < primitives.size(); ++i)
    {
        const io::Primitive& p = primitives[i];
        if (p.material >= materials_.size())
            throw std::invalid_argument("hemi: a primitive uses material " + std::to_string(p.material) +
                                        " of " + std::to_string(materials_.size()));
        if (uint64_t(p.first_index) + p.index_count > mesh.indices.size())
            throw std::invalid_argument("hemi: primitive " + std::to_string(i) + " draws indices [" +
                                        std::to_string(p.first_index) + ", +" +
                                        std::to_string(p.index_count) + ") past the mesh's " +
                                        std::to_string(mesh.indices.size()));
        Draw d{p.first_index,
               p.index_count,
               p.material,
               0,
               glm::vec3(INFINITY),
               glm::vec3(-INFINITY),
               {},
               {},
               {}};
        if (geometry && !geometry->primitives.empty())
        {
            d.first_index = geometry->primitives[i].first_index;
            d.index_count = geometry->primitives[i].index_count;
            d.vertex_offset = geometry->primitives[i].vertex_offset;
        }
        for (uint32_t j = p.first_index; j < p.first_index + p.index_count; ++j)
        {
            if (mesh.indices[j] >= mesh.positions.size())
                throw std::invalid_argument("hemi: index " + std::to_string(j) +
                                            " of the mesh names vertex " + std::to_string(mesh.indices[j]) +
                                            " of " + std::to_string(mesh.positions.size()));
            d.bounds_min = glm::min(d.bounds_min, mesh.positions[mesh.indices[j]]);
            d.bounds_max = glm::max(d.bounds_max, mesh.positions[mesh.indices[j]]);
        }
        for (const SurfaceVariant& v : variants)
        {
            MaterialKey key;
            key.technique = v.technique;
            key.source = source;
            key.basis = v.basis;
            key.frame = v.frame;
            key.double_sided = materials_[p.material]->double_sided();
            key.alpha = materials_[p.material]->alpha_mode();
            key.lightmap_filter = v.lightmap_filter;
            if (geometry)
                key.vertex = geometry->layout;
            d.keys.push_back(key);
            d.coefficient_shift.push_back(source == CoefficientSourceKind::Vertex && d.vertex_offset != 0
                                              ? uint32_t(d.vertex_offset) * uint32_t(basis_size(v.basis))
                                              : 0u);
        }
        draws_.push_back(std::move(d));
    }
    if (system.has_default_pass())
        add_pass(system.default_pass());
}

size_t SceneSurfaces::add_pass(const PassDesc& pass)
{
    // Every type first: a compile that throws part of the way leaves the surfaces as they were (a later pass
    // must not take this one's index with some draws holding its pipelines).
    std::vector<std::vector<const MaterialType*>> types(draws_.size());
    for (size_t i = 0; i < draws_.size(); ++i)
        for (const MaterialKey& key : draws_[i].keys)
            types[i].push_back(&system_->type(key, pass));
    passes_.reserve(passes_.size() + 1);
    for (Draw& d : draws_)
        d.types.reserve(d.types.size() + 1);
    for (size_t i = 0; i < draws_.size(); ++i)
        draws_[i].types.push_back(std::move(types[i])); // no allocation: reserved above
    passes_.push_back(pass.kind);
    return passes_.size() - 1;
}

SceneSurfaces::~SceneSurfaces() = default;

bool SceneSurfaces::check(const char* call, VkDescriptorSet frame, VkDescriptorSet source, size_t variant,
                          size_t pass) const noexcept
{
    const gpu::Device& device = system_->device();
    if (frame == VK_NULL_HANDLE)
        return detail::refuse(device, call, "the frame set is VK_NULL_HANDLE (released, or never made)");
    if (source == VK_NULL_HANDLE)
        return detail::refuse(device, call, "the coefficient set is VK_NULL_HANDLE (released)");
    if (pass >= passes_.size())
        return detail::refuse(device, call,
                              "pass %zu was not added (%zu pass(es); add_pass() returns the index)", pass,
                              passes_.size());
    const size_t variants = draws_.empty() ? 0 : draws_.front().keys.size();
    if (variant >= variants)
        return detail::refuse(device, call, "variant %zu does not exist (%zu loaded)", variant, variants);
    return true;
}

bool SceneSurfaces::draw(VkCommandBuffer cmd, VkDescriptorSet frame, VkDescriptorSet source,
                         uint32_t coefficient_offset, const glm::mat4& model, size_t variant,
                         size_t pass) const noexcept
{
    if (!check("SceneSurfaces::draw", frame, source, variant, pass))
        return false;
    thread_local std::vector<DrawPacket>
        packets; // grown once per thread, then reused: no allocation per call
    packets.resize(draws_.size());
    size_t n = 0;
    for (size_t i = 0; i < draws_.size(); ++i)
        n += packet(packets[n], frame, source, coefficient_offset, model, variant, pass, i) ? 1 : 0;
    return record_packets(cmd, std::span(packets).first(n)).refused == 0;
}

bool SceneSurfaces::enqueue(DrawQueue& queue, VkDescriptorSet frame, VkDescriptorSet source,
                            uint32_t coefficient_offset, const glm::mat4& model, size_t variant, size_t pass,
                            uint32_t layer, float depth, InstanceRange instances) const noexcept
{
    if (!check("SceneSurfaces::enqueue", frame, source, variant, pass))
        return false;
    if (layer > 0xffu)
        return detail::refuse(system_->device(), "SceneSurfaces::enqueue", "layer %u exceeds 255", layer);
    DrawPacket p;
    for (size_t i = 0; i < draws_.size(); ++i)
        if (packet(p, frame, source, coefficient_offset, model, variant, pass, i))
        {
            if (instances.count)
                make_instanced(p, instances.first, instances.count);
            p.key = draw_key(layer, *p.type, p.material, p.source, depth);
            queue.add(p);
        }
    return true;
}

bool SceneSurfaces::packet(DrawPacket& out, VkDescriptorSet frame, VkDescriptorSet source,
                           uint32_t coefficient_offset, const glm::mat4& model, size_t variant, size_t pass,
                           size_t primitive, const glm::vec4& lightmap_scale_offset) const noexcept
{
    if (!check("SceneSurfaces::packet", frame, source, variant, pass))
        return false;
    if (primitive >= draws_.size())
        return detail::refuse(system_->device(), "SceneSurfaces::packet",
                              "primitive %zu does not exist (%zu)", primitive, draws_.size());
    const Draw& d = draws_[primitive];
    if (passes_[pass] == PassKind::Depth && d.keys[variant].alpha == io::AlphaMode::Blend)
        return false;
    out.type = d.types[pass][variant];
    out.frame = frame;
    out.material = materials_[d.material]->set();
    out.source = source;
    out.mesh = binding_;
    out.first_index = d.first_index;
    out.index_count = d.index_count;
    out.vertex_offset = d.vertex_offset;
    out.instance_count = 1;
    out.first_instance = 0;
    out.push = {};
    out.push.model = model;
    // Per-vertex coefficients are read at coefficient_offset + gl_VertexIndex K, and gl_VertexIndex counts
    // the engine's vertex offset: taken out here (modulo 2^32, as the shader's sum is).
    out.push.coefficient_offset = coefficient_offset - d.coefficient_shift[variant];
    out.push.draw_id = uint32_t(primitive + 1);
    out.push.lightmap_scale_offset = lightmap_scale_offset;
    return true;
}

bool SceneSurfaces::draw_primitive(VkCommandBuffer cmd, VkDescriptorSet frame, VkDescriptorSet source,
                                   uint32_t coefficient_offset, const glm::mat4& model, size_t variant,
                                   size_t pass, size_t primitive,
                                   const glm::vec4& lightmap_scale_offset) const noexcept
{
    if (!check("SceneSurfaces::draw_primitive", frame, source, variant, pass))
        return false;
    if (primitive >= draws_.size())
        return detail::refuse(system_->device(), "SceneSurfaces::draw_primitive",
                              "primitive %zu does not exist (%zu)", primitive, draws_.size());
    DrawPacket p;
    if (packet(p, frame, source, coefficient_offset, model, variant, pass, primitive, lightmap_scale_offset))
        return record_packets(cmd, {&p, 1}).refused == 0;
    return true;
}

const GpuMesh& SceneSurfaces::mesh() const
{
    if (!mesh_)
        throw std::logic_error("hemi: these surfaces draw from the engine's geometry: hemi holds no mesh");
    return *mesh_;
}

SceneSurfaces::Primitive SceneSurfaces::primitive(size_t p) const
{
    const Draw& d = draws_.at(p);
    return {d.first_index, d.index_count, d.material, d.bounds_min, d.bounds_max};
}

const MaterialType& SceneSurfaces::type(size_t primitive, size_t variant, size_t pass) const
{
    return *draws_.at(primitive).types.at(pass).at(variant);
}

VkDescriptorSet SceneSurfaces::material_set(size_t primitive) const
{
    return materials_.at(draws_.at(primitive).material)->set();
}

const io::Material& SceneSurfaces::material(size_t primitive) const
{
    return material_data_.at(draws_.at(primitive).material);
}

} // namespace hemi::render
