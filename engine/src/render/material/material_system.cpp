#include <hemi/math/basis.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/gpu_mesh.h>

#include <stdexcept>
#include <string>

namespace hemi::render
{
namespace
{
// The pipeline's vertex input from a layout, checked: streams in range with a stride, formats the device
// reads as vertex attributes.
void vertex_input(const gpu::Device& device, const VertexLayout& layout, gpu::GraphicsProgramDesc& desc)
{
    const std::pair<const char*, const VertexInput*> inputs[5] = {{"position", &layout.position},
                                                                  {"normal", &layout.normal},
                                                                  {"tangent", &layout.tangent},
                                                                  {"uv0", &layout.uv0},
                                                                  {"uv1", &layout.uv1}};
    bool used[VertexLayout::kMaxVertexStreams] = {};
    for (uint32_t location = 0; location < 5; ++location)
    {
        const auto& [name, in] = inputs[location];
        const std::string what = std::string("hemi: the vertex layout's ") + name;
        if (in->binding >= VertexLayout::kMaxVertexStreams)
            throw std::invalid_argument(what + " is in stream " + std::to_string(in->binding) +
                                        "; streams are 0 to " +
                                        std::to_string(VertexLayout::kMaxVertexStreams - 1));
        if (layout.strides[in->binding] == 0)
            throw std::invalid_argument(what + " is in stream " + std::to_string(in->binding) +
                                        ", which has no stride");
        VkFormatProperties props{};
        if (in->format != VK_FORMAT_UNDEFINED)
            vkGetPhysicalDeviceFormatProperties(device.physical_device(), in->format, &props);
        if (!(props.bufferFeatures & VK_FORMAT_FEATURE_VERTEX_BUFFER_BIT))
            throw std::invalid_argument(what + " has format " + std::to_string(int(in->format)) +
                                        ", which the device does not read as a vertex attribute");
        used[in->binding] = true;
        desc.vertex_attributes.push_back({location, in->binding, in->format, in->offset});
    }
    for (uint32_t b = 0; b < VertexLayout::kMaxVertexStreams; ++b)
        if (used[b])
            desc.vertex_bindings.push_back({b, layout.strides[b], VK_VERTEX_INPUT_RATE_VERTEX});
}

const math::BasisDesc& basis_of(int id)
{
    if (id == HEMI_BASIS_VERTEX_IRRADIANCE)
        return math::vertex_irradiance_basis();
    for (const math::BasisDesc& b : math::bases())
        if (b.id == id)
            return b;
    throw std::invalid_argument("hemi: material key names basis id " + std::to_string(id) +
                                ", which hemi does not know");
}

const char* source_name(CoefficientSourceKind kind)
{
    switch (kind)
    {
    case CoefficientSourceKind::Vertex:
        return "vertex";
    case CoefficientSourceKind::Texel:
        return "texel";
    case CoefficientSourceKind::Uniform:
        return "uniform";
    case CoefficientSourceKind::Environment:
        return "environment";
    }
    throw std::invalid_argument("hemi: unknown coefficient source kind");
}
} // namespace

std::vector<gpu::Binding> MaterialSystem::frame_bindings()
{
    return {{HEMI_FRAME_BINDING_UNIFORMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
             VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT},
            {HEMI_FRAME_BINDING_INSTANCES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_VERTEX_BIT}};
}

std::vector<gpu::Binding> MaterialSystem::material_bindings()
{
    const VkShaderStageFlags fs = VK_SHADER_STAGE_FRAGMENT_BIT;
    return {
        {HEMI_MATERIAL_BINDING_UNIFORMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, fs},
        {HEMI_MATERIAL_BINDING_BASE_COLOR, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fs},
        {HEMI_MATERIAL_BINDING_NORMAL, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fs},
        {HEMI_MATERIAL_BINDING_EMISSIVE, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fs},
        {HEMI_MATERIAL_BINDING_OCCLUSION, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fs},
    };
}

std::vector<gpu::Binding> MaterialSystem::source_bindings(CoefficientSourceKind kind)
{
    switch (kind)
    {
    case CoefficientSourceKind::Vertex:
        return {{HEMI_SOURCE_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
                 VK_SHADER_STAGE_VERTEX_BIT}};
    case CoefficientSourceKind::Texel:
        return {{HEMI_SOURCE_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                 VK_SHADER_STAGE_FRAGMENT_BIT},
                {HEMI_SOURCE_BINDING_PAGE_TABLE, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                 VK_SHADER_STAGE_FRAGMENT_BIT},
                {HEMI_SOURCE_BINDING_SHADOWMASK, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                 VK_SHADER_STAGE_FRAGMENT_BIT}};
    case CoefficientSourceKind::Uniform:
        return {{HEMI_SOURCE_BINDING_COEFFICIENTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                 VK_SHADER_STAGE_FRAGMENT_BIT}};
    case CoefficientSourceKind::Environment:
    {
        const VkShaderStageFlags fs = VK_SHADER_STAGE_FRAGMENT_BIT;
        const VkDescriptorType image = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        return {{HEMI_ENV_BINDING_UNIFORMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, fs},
                {HEMI_ENV_BINDING_MIRROR, image, fs},
                {HEMI_ENV_BINDING_GLOSSY, image, fs},
                {HEMI_ENV_BINDING_DIFFUSE, image, fs},
                {HEMI_ENV_BINDING_FRESNEL, image, fs},
                {HEMI_ENV_BINDING_BRDF, image, fs}};
    }
    }
    throw std::invalid_argument("hemi: unknown coefficient source kind");
}

namespace
{
// A pass's target checked: colour attachments for a colour pass (two with aux output), dynamic rendering
// where there is no render pass.
void check_target(const gpu::Device& device, const PassDesc& pass)
{
    const RenderTargetDesc& target = pass.target;
    const bool dynamic = target.render_pass == VK_NULL_HANDLE;
    const uint32_t colors = dynamic ? uint32_t(target.color_formats.size()) : target.color_attachments;
    if (pass.kind == PassKind::Color && colors == 0)
        throw std::invalid_argument("hemi: a colour pass's target needs at least one colour attachment");
    if (pass.kind == PassKind::Color && target.aux_output && colors < 2)
        throw std::invalid_argument("hemi: a material target with aux output needs two colour attachments");
    if (pass.kind != PassKind::Color &&
        (!target.depth_test || (dynamic && target.depth_format == VK_FORMAT_UNDEFINED)))
        throw std::invalid_argument(
            "hemi: a depth or shadow pass's target needs a depth attachment and depth test");
    if (dynamic && !device.dynamic_rendering())
        throw std::invalid_argument(
            "hemi: a material target without a render pass needs dynamic rendering, which "
            "device " +
            std::string(device.name()) + " does not have enabled");
}
} // namespace

MaterialSystem::MaterialSystem(const gpu::Device& device, const RenderTargetDesc& target,
                               VkPipelineCache cache)
    : MaterialSystem(device, cache)
{
    default_pass_.target = target;
    check_target(device, default_pass_);
    has_default_pass_ = true;
}

MaterialSystem::MaterialSystem(const gpu::Device& device, VkPipelineCache cache)
    : device_(&device), cache_(cache)
{
    frame_layout_ = gpu::create_set_layout(device, frame_bindings());
    material_layout_ = gpu::create_set_layout(device, material_bindings());
    for (CoefficientSourceKind kind : {CoefficientSourceKind::Vertex, CoefficientSourceKind::Texel,
                                       CoefficientSourceKind::Uniform, CoefficientSourceKind::Environment})
        source_layouts_[uint32_t(kind)] = gpu::create_set_layout(device, source_bindings(kind));
    descriptors_ = std::make_unique<gpu::DescriptorAllocator>(device);
}

MaterialSystem::~MaterialSystem() = default;

VkDescriptorSetLayout MaterialSystem::source_layout(CoefficientSourceKind kind) const
{
    if (uint32_t(kind) > 3)
        throw std::invalid_argument("hemi: unknown coefficient source kind");
    return source_layouts_[uint32_t(kind)];
}

size_t MaterialSystem::type_count() const
{
    std::lock_guard<std::mutex> lock(mutex_);
    return types_.size();
}

const MaterialType& MaterialSystem::type(const MaterialKey& key)
{
    if (!has_default_pass_)
        throw std::invalid_argument("hemi: MaterialSystem::type(key): this system was made without a default "
                                    "target; give the pass (type(key, pass))");
    return type(key, default_pass_);
}

const MaterialType& MaterialSystem::type(const MaterialKey& key_in, const PassDesc& pass)
{
    // A depth pipeline does not depend on the technique, basis or frame: one per the rest of the key.
    MaterialKey key = key_in;
    if (pass.kind != PassKind::Color)
    {
        key.technique = Technique::Irradiance;
        key.basis = HEMI_BASIS_SH9;
        key.frame = ShadingFrame::Tangent;
    }
    if (pass.kind != PassKind::Color || key.source != CoefficientSourceKind::Texel ||
        key.technique == Technique::Constant || key.technique == Technique::Lambert)
        key.lightmap_filter = LightmapFilter::Linear; // looks no lightmap up
    PassDesc p = pass;
    if (p.kind != PassKind::Shadow)
        p.depth_bias_constant = p.depth_bias_slope = 0.0f;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (auto it = types_.find({key, p}); it != types_.end())
            return *it->second;
    }
    std::unique_ptr<MaterialType> compiled = compile(key, p); // outside the lock: other threads go on
    std::lock_guard<std::mutex> lock(mutex_);
    // Another thread may have compiled the same type meanwhile: the first one in stays.
    compiled->id = uint32_t(types_.size());
    return *types_.emplace(std::pair{key, p}, std::move(compiled)).first->second;
}

void MaterialSystem::prepare(std::span<const MaterialKey> keys, const PassDesc& pass)
{
    for (const MaterialKey& key : keys)
        type(key, pass);
}

std::unique_ptr<MaterialType> MaterialSystem::compile(const MaterialKey& key, const PassDesc& pass) const
{
    check_target(*device_, pass);
    const RenderTargetDesc& target = pass.target;
    const math::BasisDesc& basis = basis_of(key.basis);
    if (key.frame == ShadingFrame::World && key.basis != HEMI_BASIS_SH9)
        throw std::invalid_argument("hemi: world-frame materials evaluate SH9 (the sphere), not basis '" +
                                    std::string(basis.name) +
                                    "', a hemispherical basis of the tangent frame");
    const bool environment_technique =
        key.technique == Technique::Factored || key.technique == Technique::Banks ||
        key.technique == Technique::EnvMirror || key.technique == Technique::EnvGlossy;
    if (pass.kind == PassKind::Color &&
        environment_technique != (key.source == CoefficientSourceKind::Environment))
        throw std::invalid_argument(
            "hemi: the factored, banks, env_mirror and env_glossy techniques, and only they, "
            "take the environment source");
    if (pass.kind == PassKind::Color && environment_technique && key.frame != ShadingFrame::World)
        throw std::invalid_argument("hemi: environment materials shade in the world frame");
    auto type = std::make_unique<MaterialType>();
    type->key = key;
    type->pass = pass.kind;
    type->device = device_;
    type->k = uint32_t(basis.size);

    const bool depth = pass.kind != PassKind::Color;
    const bool alpha_tested =
        key.alpha == io::AlphaMode::Mask || (depth && key.alpha == io::AlphaMode::Blend);
    const std::string source = source_name(key.source);
    // The colour pass's vertex variant in every pass: the same code for positions, so depths match exactly
    // (invariant gl_Position) and a colour pass can test EQUAL against a prepass.
    const std::string vs =
        key.source == CoefficientSourceKind::Vertex ? "surface_vertex.vert" : "surface_other.vert";
    gpu::GraphicsProgramDesc desc;
    desc.vertex_shader = gpu::embedded_spirv(vs);
    if (!depth)
        desc.fragment_shader =
            gpu::embedded_spirv("surface_" + source + (target.aux_output ? "_aux" : "") + ".frag");
    else if (alpha_tested)
        desc.fragment_shader = gpu::embedded_spirv("surface_depth.frag");
    desc.set_layouts = {frame_layout_, material_layout_, source_layout(key.source)};
    desc.push_constant_size = sizeof(shared::DrawPush);
    // Ids HEMI_SPEC_BASIS .. HEMI_SPEC_LIGHTMAP_FILTER, in order.
    desc.specialization = {
        uint32_t(key.basis),          uint32_t(basis.size),
        uint32_t(key.frame),          uint32_t(key.technique),
        key.double_sided ? 1u : 0u,   alpha_tested ? 1u : key.alpha == io::AlphaMode::Blend ? 2u : 0u,
        uint32_t(key.lightmap_filter)};
    vertex_input(*device_, key.vertex, desc);
    desc.render_pass = target.render_pass;
    desc.subpass = target.subpass;
    const bool dynamic = target.render_pass == VK_NULL_HANDLE;
    desc.color_attachments = dynamic ? uint32_t(target.color_formats.size()) : target.color_attachments;
    desc.color_formats = target.color_formats;
    desc.depth_format = target.depth_format;
    desc.samples = target.samples;
    desc.depth_test = target.depth_test && (!dynamic || target.depth_format != VK_FORMAT_UNDEFINED);
    desc.depth_write =
        target.depth_write && !(pass.kind == PassKind::Color && key.alpha == io::AlphaMode::Blend);
    desc.depth_compare = target.depth_compare;
    desc.blend = pass.kind == PassKind::Color && key.alpha == io::AlphaMode::Blend;
    desc.color_writes = !depth;
    desc.written_color_attachments = target.aux_output ? 2 : 1; // the others are the engine's
    if (pass.kind == PassKind::Shadow)
    {
        desc.depth_bias_constant = pass.depth_bias_constant;
        desc.depth_bias_slope = pass.depth_bias_slope;
    }
    desc.cull_mode = key.double_sided ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT;
    // Meshes are counter-clockwise seen from outside; with a y-flipped projection (Vulkan clip space) the
    // facing rule, whose area formula is negated for y-down framebuffers, keeps them counter-clockwise.
    desc.front_face = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    desc.cache = cache_;
    type->program = gpu::create_graphics_program(*device_, desc);
    if (device_->debug_utils())
    {
        static const char* const kPasses[] = {"color", "depth", "shadow"};
        device_->set_name(VK_OBJECT_TYPE_PIPELINE, type->program.pipeline.get(),
                          "hemi material technique " + std::to_string(int(key.technique)) + " basis " +
                              std::string(basis.name) + " source " + source +
                              (key.lightmap_filter == LightmapFilter::Bicubic ? " bicubic " : " ") +
                              kPasses[std::min<size_t>(size_t(pass.kind), 2)] + " pass");
    }
    return type;
}

void bind_material(VkCommandBuffer cmd, const DrawBindings& draw)
{
    if (!draw.type || !draw.frame || !draw.material || !draw.source)
        throw std::invalid_argument("hemi: a draw needs a material type and its three descriptor sets");
    const gpu::Program& p = draw.type->program;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.pipeline);
    const VkDescriptorSet sets[3] = {draw.frame, draw.material, draw.source};
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.layout, 0, 3, sets, 0, nullptr);
    vkCmdPushConstants(cmd, p.layout, VK_SHADER_STAGE_ALL, 0, sizeof draw.push, &draw.push);
}

} // namespace hemi::render
