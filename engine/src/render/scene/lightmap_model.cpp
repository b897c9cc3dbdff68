#include "../refuse.h"

#include <hemi/math/sh.h>
#include <hemi/render/scene/lightmap_model.h>

#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hemi::render
{

const math::BasisDesc& lightmap_basis(const std::string& output)
{
    if (output == "plain")
        return math::vertex_irradiance_basis();
    if (output == "rnm" || output == "ssbump" || output == "rnm_ao")
        throw std::invalid_argument(
            "hemi: the 'rnm' lightmap colours are drawn by the rnm and ssbump techniques "
            "(radiosity normal mapping), not by a basis");
    return math::basis(output);
}

bool probe_lighting(const io::LightmapAsset& asset, const glm::vec3& world_position, const glm::mat4& model,
                    std::array<glm::vec3, 9>& out, std::array<float, 4>* occlusion) noexcept
{
    out.fill(glm::vec3(0.0f));
    if (occlusion)
        occlusion->fill(1.0f);
    if (asset.probes.empty() || !std::isfinite(world_position.x + world_position.y + world_position.z))
        return false;
    // The level's irradiance function f in its own frame is g(d) = f(R^T d) in the world: math::ShRotation(R)
    // with R the model's rotation (its uniform scale divided out).
    for (int c = 0; c < 4; ++c)
        if (!std::isfinite(model[c].x + model[c].y + model[c].z + model[c].w))
            return false;
    glm::mat3 rotation(model);
    const float scale = std::cbrt(std::abs(glm::determinant(rotation)));
    if (!(scale > 0.0f) || !std::isfinite(scale))
        return false;
    rotation /= scale;
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(rotation[c].x + rotation[c].y + rotation[c].z))
            return false;
    const glm::vec3 p = glm::vec3(glm::inverse(model) * glm::vec4(world_position, 1.0f));
    const std::array<glm::vec3, 9> scene = asset.probes.at(p);
    math::ShRotation(3, rotation).apply(scene, out);
    if (occlusion)
        *occlusion = asset.probes.occlusion_at(p);
    return true;
}

std::vector<DynamicLight> mixed_lights(const io::LightmapAsset& asset, const glm::mat4& model)
{
    const glm::mat3 linear(model);
    const float scale = std::cbrt(std::abs(glm::determinant(linear)));
    if (!(scale > 0.0f) || !std::isfinite(scale))
        throw std::invalid_argument("hemi: mixed_lights: the model matrix is singular or not finite");
    std::vector<DynamicLight> out;
    for (const io::LightmapLight& l : asset.lights)
    {
        const io::PunctualLight& p = l.light;
        if (p.mode != io::LightMode::Mixed)
            continue;
        DynamicLight d;
        d.point = p.type != io::PunctualLight::Type::Directional;
        d.spot = p.type == io::PunctualLight::Type::Spot;
        d.range = p.range * scale; // distances scale with the model
        d.spot_direction = glm::normalize(linear * p.direction);
        d.inner_cone = p.inner_cone;
        d.outer_cone = p.outer_cone;
        d.position = d.point ? glm::vec3(model * glm::vec4(p.position, 1.0f))
                             : glm::normalize(linear * -p.direction); // towards the light
        d.irradiance = p.color * p.intensity * (d.point ? scale * scale : 1.0f);
        d.shadowmask_channel = l.channel;
        out.push_back(d);
    }
    return out;
}

LightmapModel::LightmapModel(MaterialSystem& system, const io::LightmapAsset& asset,
                             const std::vector<std::string>& default_techniques, gpu::UploadBatch& upload,
                             const std::map<std::string, std::string>& material_techniques,
                             const EngineGeometry* geometry, LightmapFilter filter)
    : device_(&system.device())
{
    if (default_techniques.empty())
        throw std::invalid_argument("hemi: a lightmap model needs at least one technique");
    // Each material's own technique (the asset's, or the caller's override by material name).
    std::vector<std::string> material_technique;
    for (const io::Material& m : asset.materials)
    {
        const auto it = material_techniques.find(m.name);
        material_technique.push_back(it != material_techniques.end() ? it->second : m.technique);
    }
    std::vector<std::string> techniques = default_techniques;
    for (const std::string& t : material_technique)
        if (!t.empty() && std::find(techniques.begin(), techniques.end(), t) == techniques.end())
            techniques.push_back(t);
    std::vector<SurfaceVariant> variants;
    for (const std::string& technique_name : techniques)
    {
        // "<output>+ggx": the output's irradiance with the frame's GGX coat (Technique::Ggx).
        const std::string_view suffix = "+ggx";
        const bool ggx = technique_name.size() > suffix.size() && technique_name.ends_with(suffix);
        const std::string name =
            ggx ? technique_name.substr(0, technique_name.size() - suffix.size()) : technique_name;
        // rnm and ssbump draw the "rnm" output (K = 3, carried by the 3-function HL2 basis's id); the others
        // their own output with their basis.
        const bool rnm = name == "rnm" || name == "ssbump" || name == "rnm_ao";
        // "constant" (the base colour factor) and "lambert" (the textures and dynamic lights alone):
        // hemi-bench's baselines, binding some output they do not read.
        const bool baseline = name == "constant" || name == "lambert";
        const Technique baseline_technique = name == "constant" ? Technique::Constant : Technique::Lambert;
        if (baseline && asset.outputs.empty())
            throw std::invalid_argument("hemi: the lightmap asset has no outputs");
        // A baseline binds the output with the fewest coefficients (it reads none of them).
        const io::LightmapOutput* smallest = asset.outputs.empty() ? nullptr : &asset.outputs.front();
        for (const io::LightmapOutput& o : asset.outputs)
            if (o.k < smallest->k)
                smallest = &o;
        const std::string source = rnm ? "rnm" : baseline ? smallest->name : name;
        if (ggx && (rnm || baseline || source == "rnm"))
            throw std::invalid_argument(
                "hemi: '" + technique_name +
                "': the GGX coat's specular needs a basis's coefficients (sh9, h6, ..., "
                "plain), not " +
                name);
        const io::LightmapOutput& output = asset.output(source); // lists what the asset has
        if (rnm)
            variants.push_back({name == "rnm"      ? Technique::Rnm
                                : name == "rnm_ao" ? Technique::RnmAo
                                                   : Technique::Ssbump,
                                HEMI_BASIS_HL2});
        else if (source == "rnm")
            variants.push_back({baseline_technique, HEMI_BASIS_HL2});
        else
            variants.push_back({baseline ? baseline_technique
                                : ggx    ? Technique::Ggx
                                         : Technique::Irradiance,
                                lightmap_basis(source).id});
        variants.back().lightmap_filter = filter;
        names_.push_back(technique_name);
        // Each technique's source carries the mixed lights' shadowmask in its slots (a frame's mixed lights
        // read it: DynamicLight::shadowmask_channel).
        coefficients_.push_back(std::make_unique<TexelCoefficients>(
            system, output.maps, upload, false, asset.shadowmask.k == 4 ? &asset.shadowmask : nullptr));
        system.device().set_name(VK_OBJECT_TYPE_IMAGE, coefficients_.back()->pages().handle(),
                                 "hemi lightmap '" + name + "'");
        system.device().set_name(VK_OBJECT_TYPE_IMAGE, coefficients_.back()->page_table().handle(),
                                 "hemi lightmap '" + name + "' page table");
    }
    surfaces_ =
        std::make_unique<SceneSurfaces>(system, asset.mesh, asset.images, asset.materials, asset.primitives,
                                        CoefficientSourceKind::Texel, variants, upload, geometry);
    for (size_t p = 0; p < surfaces_->primitive_count(); ++p)
    {
        const uint32_t m = surfaces_->primitive(p).material;
        const std::string own = m < material_technique.size() ? material_technique[m] : std::string();
        primitive_variant_.push_back(
            own.empty() ? -1 : int(std::find(names_.begin(), names_.end(), own) - names_.begin()));
    }
}

LightmapModel::~LightmapModel() = default;

std::vector<LightmapDraw> LightmapModel::draw_list(const std::string& technique, size_t pass) const
{
    const auto it = std::find(names_.begin(), names_.end(), technique);
    if (it == names_.end())
        throw std::invalid_argument("hemi: technique '" + technique +
                                    "' is not loaded in this lightmap model");
    if (pass >= surfaces_->pass_count())
        throw std::invalid_argument("hemi: LightmapModel::draw_list: pass " + std::to_string(pass) +
                                    " was not added (" + std::to_string(surfaces_->pass_count()) +
                                    " pass(es); add_pass() returns the index)");
    const size_t fallback = size_t(it - names_.begin());
    std::vector<LightmapDraw> list;
    for (size_t p = 0; p < surfaces_->primitive_count(); ++p)
    {
        const SceneSurfaces::Primitive prim = surfaces_->primitive(p);
        LightmapDraw d;
        d.primitive = p;
        d.first_index = prim.first_index;
        d.index_count = prim.index_count;
        d.material = &surfaces_->material(p);
        d.variant = primitive_variant_[p] >= 0 ? size_t(primitive_variant_[p]) : fallback;
        d.technique = &names_[d.variant];
        d.type = &surfaces_->type(p, d.variant, pass);
        d.bounds_min = prim.bounds_min;
        d.bounds_max = prim.bounds_max;
        list.push_back(d);
    }
    return list;
}

const TexelCoefficients& LightmapModel::coefficients(const std::string& technique) const
{
    const auto it = std::find(names_.begin(), names_.end(), technique);
    if (it == names_.end())
        throw std::invalid_argument("hemi: technique '" + technique +
                                    "' is not loaded in this lightmap model");
    return *coefficients_[size_t(it - names_.begin())];
}

bool LightmapModel::check(const char* call, const LightmapDraw& entry) const noexcept
{
    if (entry.variant >= coefficients_.size() || entry.primitive >= surfaces_->primitive_count() ||
        entry.material != &surfaces_->material(entry.primitive))
        return detail::refuse(
            *device_, call, "the entry (primitive %zu, technique %zu) is not one of this model's draw_list()",
            entry.primitive, entry.variant);
    return true;
}

bool LightmapModel::draw(VkCommandBuffer cmd, VkDescriptorSet frame, const LightmapDraw& entry,
                         const glm::mat4& model, size_t pass,
                         const glm::vec4& lightmap_scale_offset) const noexcept
{
    if (!check("LightmapModel::draw", entry))
        return false;
    const VkDescriptorSet source = coefficients_[entry.variant]->set();
    if (!surfaces_->check("LightmapModel::draw", frame, source, entry.variant, pass))
        return false;
    return surfaces_->draw_primitive(cmd, frame, source, 0, model, entry.variant, pass, entry.primitive,
                                     lightmap_scale_offset);
}

bool LightmapModel::enqueue(DrawQueue& queue, VkDescriptorSet frame, const LightmapDraw& entry,
                            const glm::mat4& model, size_t pass, const glm::vec4& lightmap_scale_offset,
                            uint32_t layer, float depth) const noexcept
{
    if (!check("LightmapModel::enqueue", entry))
        return false;
    const VkDescriptorSet source = coefficients_[entry.variant]->set();
    if (!surfaces_->check("LightmapModel::enqueue", frame, source, entry.variant, pass))
        return false;
    if (layer > 0xffu)
        return detail::refuse(*device_, "LightmapModel::enqueue", "layer %u exceeds 255", layer);
    DrawPacket p;
    if (surfaces_->packet(p, frame, source, 0, model, entry.variant, pass, entry.primitive,
                          lightmap_scale_offset))
    {
        p.key = draw_key(layer, *p.type, p.material, p.source, depth);
        queue.add(p);
    }
    return true;
}

bool LightmapModel::enqueue_instances(DrawQueue& queue, VkDescriptorSet frame, const LightmapDraw& entry,
                                      InstanceRange instances, size_t pass, uint32_t layer,
                                      float depth) const noexcept
{
    if (!check("LightmapModel::enqueue_instances", entry))
        return false;
    if (instances.count == 0)
        return detail::refuse(*device_, "LightmapModel::enqueue_instances",
                              "an instanced draw of 0 instances");
    const VkDescriptorSet source = coefficients_[entry.variant]->set();
    if (!surfaces_->check("LightmapModel::enqueue_instances", frame, source, entry.variant, pass))
        return false;
    if (layer > 0xffu)
        return detail::refuse(*device_, "LightmapModel::enqueue_instances", "layer %u exceeds 255", layer);
    DrawPacket p;
    if (surfaces_->packet(p, frame, source, 0, glm::mat4(1.0f), entry.variant, pass, entry.primitive))
    {
        make_instanced(p, instances.first, instances.count);
        p.key = draw_key(layer, *p.type, p.material, p.source, depth);
        queue.add(p);
    }
    return true;
}

shared::DrawPush LightmapModel::instance_record(const glm::mat4& model,
                                                const glm::vec4& lightmap_scale_offset,
                                                uint32_t draw_id) noexcept
{
    shared::DrawPush r{};
    r.model = model;
    r.draw_id = draw_id;
    r.lightmap_scale_offset = lightmap_scale_offset;
    return r;
}

bool LightmapModel::draw(VkCommandBuffer cmd, VkDescriptorSet frame, std::string_view technique,
                         const glm::mat4& model, size_t pass) const noexcept
{
    const auto it = std::find(names_.begin(), names_.end(), technique);
    if (it == names_.end())
        return detail::refuse(*device_, "LightmapModel::draw", "technique '%.*s' is not loaded in this model",
                              int(technique.size()), technique.data());
    const size_t fallback = size_t(it - names_.begin());
    if (!surfaces_->check("LightmapModel::draw", frame, coefficients_[fallback]->set(), fallback, pass))
        return false;
    // draw_list()'s entries, without making the list.
    for (size_t p = 0; p < surfaces_->primitive_count(); ++p)
    {
        const size_t variant = primitive_variant_[p] >= 0 ? size_t(primitive_variant_[p]) : fallback;
        surfaces_->draw_primitive(cmd, frame, coefficients_[variant]->set(), 0, model, variant, pass, p);
    }
    return true;
}

} // namespace hemi::render
