#include <hemi/render/material/environment_lighting.h>
#include <hemi/render/material/frame_set.h>

#include <glm/gtc/packing.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::render
{
namespace
{
bool filters_linearly(const gpu::Device& device, VkFormat format)
{
    VkFormatProperties props{};
    vkGetPhysicalDeviceFormatProperties(device.physical_device(), format, &props);
    const VkFormatFeatureFlags need =
        VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
    return (props.optimalTilingFeatures & need) == need;
}

// E5B9G9R9 of one RGB value, as the Vulkan specification converts to it ("Shared Exponent Format
// Conversion"): 9-bit mantissas with a common exponent (bias 15), each channel rounded to the nearest.
uint32_t pack_shared_exponent(const float* rgb)
{
    constexpr int N = 9, B = 15;
    constexpr float max_value = float((1 << N) - 1) / float(1 << N) * float(1 << (31 - B)); // 65408
    float c[3];
    for (int i = 0; i < 3; ++i)
        c[i] = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, max_value) : 0.0f;
    const float max_c = std::max({c[0], c[1], c[2]});
    int exponent = std::max(-B - 1, max_c > 0.0f ? int(std::floor(std::log2(max_c))) : -B - 1) + 1 + B;
    if (std::floor(max_c / std::ldexp(1.0f, exponent - B - N) + 0.5f) >= float(1 << N))
        ++exponent;
    uint32_t packed = uint32_t(exponent) << 27;
    for (int i = 0; i < 3; ++i)
        packed |= uint32_t(std::floor(c[i] / std::ldexp(1.0f, exponent - B - N) + 0.5f)) << (9 * i);
    return packed;
}

// RGB floats into texels of `format`: RGBA32F, RGBA16F (clamped to half's range; alpha 1) or E5B9G9R9.
std::vector<std::byte> pack(std::span<const float> rgb, VkFormat format)
{
    const size_t texels = rgb.size() / 3;
    std::vector<std::byte> out;
    if (format == VK_FORMAT_R32G32B32A32_SFLOAT)
    {
        out.resize(texels * 16);
        float* p = reinterpret_cast<float*>(out.data());
        for (size_t i = 0; i < texels; ++i)
            p[i * 4] = rgb[i * 3], p[i * 4 + 1] = rgb[i * 3 + 1], p[i * 4 + 2] = rgb[i * 3 + 2],
                  p[i * 4 + 3] = 1.0f;
    }
    else if (format == VK_FORMAT_E5B9G9R9_UFLOAT_PACK32)
    {
        out.resize(texels * 4);
        uint32_t* p = reinterpret_cast<uint32_t*>(out.data());
        for (size_t i = 0; i < texels; ++i)
            p[i] = pack_shared_exponent(&rgb[i * 3]);
    }
    else
    {
        out.resize(texels * 8);
        uint16_t* p = reinterpret_cast<uint16_t*>(out.data());
        for (size_t i = 0; i < texels; ++i)
            for (int c = 0; c < 4; ++c)
                p[i * 4 + c] = glm::packHalf1x16(c < 3 ? std::min(rgb[i * 3 + c], 65504.0f) : 1.0f);
    }
    return out;
}

// Each probe's chain of levels (probes[k][l]: level l of probe k, all probes alike) as one image, probe k's
// halves in layers 2k and 2k + 1.
gpu::Image parabolic_image(const gpu::Device& device,
                           const std::vector<std::vector<const math::ParabolicImage*>>& probes,
                           VkFormat format, gpu::UploadBatch& upload, VkDeviceSize& bytes_total)
{
    const std::vector<const math::ParabolicImage*>& first = probes[0];
    gpu::Image image =
        gpu::create_image(device, {first[0]->size, first[0]->size, format, VK_IMAGE_USAGE_SAMPLED_BIT,
                                   uint32_t(first.size()), uint32_t(2 * probes.size()), true});
    std::vector<std::vector<std::byte>> bytes;
    for (size_t l = 0; l < first.size(); ++l)
    {
        std::vector<float> rgb;
        for (const std::vector<const math::ParabolicImage*>& probe : probes)
            rgb.insert(rgb.end(), probe[l]->rgb.begin(), probe[l]->rgb.end());
        bytes.push_back(pack(rgb, format));
        bytes_total += bytes.back().size();
    }
    upload.image_levels(image, bytes);
    return image;
}

// What differs between reflection probe `k` and probe 0 (the sizes, levels, extents and exponents that one
// set of images needs alike), or empty.
std::string probe_difference(const io::EnvmapAsset& a, const io::EnvmapAsset& b)
{
    auto same = [](const math::ParabolicImage& x, const math::ParabolicImage& y)
    { return x.size == y.size && x.extent == y.extent; };
    if (a.mirror.size() != b.mirror.size() || !same(a.mirror[0], b.mirror[0]))
        return "its mirror map is " + std::to_string(b.mirror[0].size) + " texels a side in " +
               std::to_string(b.mirror.size()) + " levels, probe 0's " + std::to_string(a.mirror[0].size) +
               " in " + std::to_string(a.mirror.size());
    if (a.exponents != b.exponents)
        return "its glossy maps' exponents differ from probe 0's";
    for (size_t g = 0; g < a.glossy.size(); ++g)
        if (!same(a.glossy[g], b.glossy[g]))
            return "its glossy map " + std::to_string(g) + " differs in size or extent from probe 0's";
    if (!same(a.diffuse, b.diffuse))
        return "its diffuse map differs in size or extent from probe 0's";
    return {};
}

// The format for `precision`: Auto takes Half where every value fits it. Explicit Half and SharedExponent
// refuse radiance beyond their range (a sun clamped to 65504 would darken every glossy reflection of it).
VkFormat choose_map_format(const gpu::Device& device, std::span<const io::EnvmapAsset> probes,
                           MapPrecision precision)
{
    float largest = 0.0f;
    auto scan = [&](const math::ParabolicImage& m)
    {
        for (float v : m.rgb)
            largest = std::max(largest, v);
    };
    for (const io::EnvmapAsset& env : probes)
    {
        for (const math::ParabolicImage& m : env.mirror)
            scan(m);
        for (const math::ParabolicImage& m : env.glossy)
            scan(m);
        scan(env.diffuse);
    }
    const VkFormat float4 = VK_FORMAT_R32G32B32A32_SFLOAT, half4 = VK_FORMAT_R16G16B16A16_SFLOAT;
    auto refuse_beyond = [&](float range, const char* name)
    {
        if (largest > range)
            throw std::invalid_argument("hemi: the environment's radiance reaches " +
                                        std::to_string(largest) + ", beyond " + name + "'s range (" +
                                        std::to_string(range) + "): store it as MapPrecision::Float or Auto");
    };
    switch (precision)
    {
    case MapPrecision::Half:
        refuse_beyond(65504.0f, "RGBA16F");
        return half4;
    case MapPrecision::SharedExponent:
        refuse_beyond(65408.0f, "E5B9G9R9");
        return VK_FORMAT_E5B9G9R9_UFLOAT_PACK32;
    case MapPrecision::Auto:
        if (largest <= 65504.0f)
            return half4;
        [[fallthrough]];
    case MapPrecision::Float:
        break;
    }
    return filters_linearly(device, float4) ? float4 : half4;
}
} // namespace

EnvironmentMaps::EnvironmentMaps(const gpu::Device& device, const io::EnvmapAsset& env,
                                 gpu::UploadBatch& upload, MapPrecision precision)
    : EnvironmentMaps(device, std::span(&env, 1), upload, precision)
{
}

EnvironmentMaps::EnvironmentMaps(const gpu::Device& device, std::span<const io::EnvmapAsset> probes,
                                 gpu::UploadBatch& upload, MapPrecision precision)
{
    if (probes.empty() || probes.size() > HEMI_MAX_REFLECTION_PROBES)
        throw std::invalid_argument("hemi: " + std::to_string(probes.size()) +
                                    " environments in one set of maps: 1 to " +
                                    std::to_string(HEMI_MAX_REFLECTION_PROBES));
    for (size_t k = 0; k < probes.size(); ++k)
    {
        if (const std::string problem = io::envmap_problem(probes[k]); !problem.empty())
            throw std::invalid_argument(
                "hemi: an inconsistent environment" +
                (probes.size() > 1 ? " (reflection probe " + std::to_string(k) + ")" : std::string()) + ": " +
                problem);
        if (const std::string d = probe_difference(probes[0], probes[k]); !d.empty())
            throw std::invalid_argument("hemi: reflection probe " + std::to_string(k) +
                                        " cannot share images with probe 0: " + d);
    }
    const io::EnvmapAsset& env = probes[0];
    probe_count_ = uint32_t(probes.size());
    map_format_ = choose_map_format(device, probes, precision);
    auto levels = [&](auto&& of)
    {
        std::vector<std::vector<const math::ParabolicImage*>> out;
        for (const io::EnvmapAsset& p : probes)
            out.push_back(of(p));
        return out;
    };
    mirror_ = parabolic_image(device,
                              levels(
                                  [](const io::EnvmapAsset& p)
                                  {
                                      std::vector<const math::ParabolicImage*> chain;
                                      for (const math::ParabolicImage& m : p.mirror)
                                          chain.push_back(&m);
                                      return chain;
                                  }),
                              map_format_, upload, map_bytes_);
    diffuse_ = parabolic_image(
        device,
        levels([](const io::EnvmapAsset& p) { return std::vector<const math::ParabolicImage*>{&p.diffuse}; }),
        map_format_, upload, map_bytes_);
    device.set_name(VK_OBJECT_TYPE_IMAGE, mirror_.handle(), "hemi environment mirror map");
    device.set_name(VK_OBJECT_TYPE_IMAGE, diffuse_.handle(), "hemi environment diffuse map");
    for (size_t g = 0; g < env.glossy.size(); ++g)
    {
        glossy_.push_back(
            parabolic_image(device,
                            levels([g](const io::EnvmapAsset& p)
                                   { return std::vector<const math::ParabolicImage*>{&p.glossy[g]}; }),
                            map_format_, upload, map_bytes_));
        glossy_extents_.push_back(float(env.glossy[g].extent));
        device.set_name(VK_OBJECT_TYPE_IMAGE, glossy_.back().handle(),
                        "hemi environment glossy map " + std::to_string(glossy_.size() - 1));
    }
    mirror_extent_ = float(env.mirror[0].extent);
    diffuse_extent_ = float(env.diffuse.extent);

    // The Fresnel tables, a row each (a 2 x 1 table of 1 without any).
    fresnel_count_ = uint32_t(env.iors.size());
    fresnel_rows_ = std::max<uint32_t>(1, fresnel_count_);
    fresnel_samples_ = env.iors.empty() ? 2 : env.fresnel_samples;
    std::vector<float> fresnel_rgb;
    for (uint32_t r = 0; r < fresnel_rows_; ++r)
        for (uint32_t i = 0; i < fresnel_samples_; ++i)
        {
            const float f = env.iors.empty() ? 1.0f : env.fresnel[size_t(r) * fresnel_samples_ + i];
            fresnel_rgb.insert(fresnel_rgb.end(), {f, f, f});
        }
    const VkFormat half4 = VK_FORMAT_R16G16B16A16_SFLOAT;
    fresnel_ = gpu::create_image(device, {fresnel_samples_, fresnel_rows_, half4});
    const std::vector<std::byte> fresnel_bytes = pack(fresnel_rgb, half4);
    upload.image(fresnel_, fresnel_bytes.data(), fresnel_bytes.size());
    sampler_ = gpu::create_sampler(device, {VK_FILTER_LINEAR, VK_SAMPLER_MIPMAP_MODE_LINEAR,
                                            VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, VK_LOD_CLAMP_NONE});
}

const gpu::Image& EnvironmentMaps::glossy_map(uint32_t i) const
{
    if (glossy_.empty())
        return diffuse_;
    return glossy_.at(i);
}

float EnvironmentMaps::glossy_extent(uint32_t i) const
{
    if (glossy_extents_.empty())
        return diffuse_extent_;
    return glossy_extents_.at(i);
}

namespace
{
// A material's weights and rotation (the constructor's and record_update's check).
void check_values(const EnvironmentMaterial& material)
{
    if (!std::isfinite(material.kd) || !std::isfinite(material.ks))
        throw std::invalid_argument("hemi: an environment material's kd and ks must be finite");
    const glm::mat3 identity = glm::transpose(material.world_to_env) * material.world_to_env;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (!std::isfinite(material.world_to_env[i][j]) ||
                std::abs(identity[i][j] - (i == j ? 1.0f : 0.0f)) > 1e-4f)
                throw std::invalid_argument(
                    "hemi: an environment's world_to_env must be a rotation (orthonormal)");
    if (material.box_projection)
    {
        const glm::vec3& o = material.world_to_env_offset;
        if (material.probes.empty() || material.probes.size() > HEMI_MAX_REFLECTION_PROBES)
            throw std::invalid_argument("hemi: an environment's box projection needs 1 to " +
                                        std::to_string(HEMI_MAX_REFLECTION_PROBES) + " probes, not " +
                                        std::to_string(material.probes.size()));
        for (const EnvironmentMaterial::Probe& p : material.probes)
        {
            const glm::vec3 &c = p.centre, &lo = p.box_min, &hi = p.box_max;
            if (!std::isfinite(o.x + o.y + o.z + c.x + c.y + c.z + lo.x + lo.y + lo.z + hi.x + hi.y + hi.z) ||
                !(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z) || !(p.fade >= 0.0f) || !std::isfinite(p.fade))
                throw std::invalid_argument(
                    "hemi: an environment's box projection needs a finite offset, and "
                    "per probe a finite centre, a box whose minimum is below its "
                    "maximum and a fade of 0 or more");
        }
    }
}

// The material's probes against the maps' (one entry per probe the maps hold).
void check_probes(const EnvironmentMaps& maps, const EnvironmentMaterial& material)
{
    const size_t given = material.box_projection ? material.probes.size() : 1;
    if (given != maps.probe_count())
        throw std::invalid_argument("hemi: the environment's maps hold " +
                                    std::to_string(maps.probe_count()) +
                                    " reflection probes and the material gives " +
                                    (material.box_projection ? std::to_string(given) + " probes' boxes"
                                                             : std::string("no box projection")) +
                                    ": blending several probes needs box_projection and one box each");
}

// What a material asks of its environment and tables, checked before anything is uploaded (a refused
// material leaves nothing of its own in the caller's upload batch).
void check_material(uint32_t glossy_count, uint32_t fresnel_count, std::span<const math::BrdfTable> brdf,
                    const EnvironmentMaterial& material)
{
    if (glossy_count != 0 && material.glossy >= glossy_count)
        throw std::invalid_argument("hemi: glossy map " + std::to_string(material.glossy) +
                                    " of an environment with " + std::to_string(glossy_count));
    if (fresnel_count != 0 && material.fresnel >= fresnel_count)
        throw std::invalid_argument("hemi: Fresnel table " + std::to_string(material.fresnel) +
                                    " of an environment with " + std::to_string(fresnel_count));
    for (const math::BrdfTable& t : brdf)
    {
        if (t.size != brdf[0].size || t.size < 2)
            throw std::invalid_argument(
                "hemi: the BRDF tables of one material must all have one size (>= 2)");
        if (t.channels == 0 || t.values.size() != size_t(t.size) * t.size * t.channels)
            throw std::invalid_argument("hemi: a BRDF table of " + std::to_string(t.size) + "^2 x " +
                                        std::to_string(t.channels) + " channels holds " +
                                        std::to_string(t.values.size()) + " values");
        for (float v : t.values)
            if (!std::isfinite(v) || std::abs(v) > 65504.0f)
                throw std::invalid_argument("hemi: a BRDF table value does not fit a half float");
    }
    // What the techniques read: Torrance-Sparrow's two one-channel tables (factored) or Banks' one
    // two-channel table (banks).
    const bool torrance_sparrow = brdf.size() == 2 && brdf[0].channels == 1 && brdf[1].channels == 1;
    const bool banks = brdf.size() == 1 && brdf[0].channels == 2;
    if (!brdf.empty() && !torrance_sparrow && !banks)
        throw std::invalid_argument("hemi: BRDF tables must be Torrance-Sparrow's two (FD, G) or Banks' one "
                                    "(diffuse, specular)");
    check_values(material);
}

std::shared_ptr<const EnvironmentMaps> checked_maps(const gpu::Device& device, const io::EnvmapAsset& env,
                                                    std::span<const math::BrdfTable> brdf,
                                                    const EnvironmentMaterial& material,
                                                    gpu::UploadBatch& upload)
{
    if (const std::string problem = io::envmap_problem(env); !problem.empty())
        throw std::invalid_argument("hemi: an inconsistent environment: " + problem);
    check_material(uint32_t(env.glossy.size()), uint32_t(env.iors.size()), brdf, material);
    return std::make_shared<const EnvironmentMaps>(device, env, upload);
}
} // namespace

EnvironmentLighting::EnvironmentLighting(const MaterialSystem& system, const io::EnvmapAsset& env,
                                         std::span<const math::BrdfTable> brdf,
                                         const EnvironmentMaterial& material, gpu::UploadBatch& upload)
    : EnvironmentLighting(system, checked_maps(system.device(), env, brdf, material, upload), brdf, material,
                          upload)
{
}

EnvironmentLighting::EnvironmentLighting(const MaterialSystem& system,
                                         std::shared_ptr<const EnvironmentMaps> maps,
                                         std::span<const math::BrdfTable> brdf,
                                         const EnvironmentMaterial& material, gpu::UploadBatch& upload)
    : maps_(std::move(maps))
{
    const gpu::Device& device = system.device();
    if (!maps_)
        throw std::invalid_argument("hemi: an environment material needs its environment's maps");
    check_material(maps_->glossy_count(), maps_->fresnel_count(), brdf, material);
    check_probes(*maps_, material);
    glossy_ = material.glossy;
    fresnel_row_ = material.fresnel;
    const VkFormat half4 = VK_FORMAT_R16G16B16A16_SFLOAT;
    // The BRDF tables, a layer each, channels into r, g (2 x 2 zeros without any).
    table_size_ = brdf.empty() ? 2 : brdf[0].size;
    const uint32_t layers = std::max<uint32_t>(1, uint32_t(brdf.size()));
    std::vector<float> table_rgb(size_t(table_size_) * table_size_ * layers * 3, 0.0f);
    for (size_t k = 0; k < brdf.size(); ++k)
        for (size_t i = 0; i < size_t(table_size_) * table_size_; ++i)
            for (uint32_t c = 0; c < std::min(brdf[k].channels, 3u); ++c)
            {
                table_rgb[(k * table_size_ * table_size_ + i) * 3 + c] =
                    brdf[k].values[i * brdf[k].channels + c];
            }
    brdf_ = gpu::create_image(device,
                              {table_size_, table_size_, half4, VK_IMAGE_USAGE_SAMPLED_BIT, 1, layers, true});
    const std::vector<std::byte> table_bytes = pack(table_rgb, half4);
    upload.image(brdf_, table_bytes.data(), table_bytes.size());

    uniforms_ =
        gpu::create_buffer(device, {sizeof(shared::EnvironmentUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    const shared::EnvironmentUniforms u = uniforms(material);
    upload.buffer(uniforms_, &u, sizeof u);

    const std::vector<gpu::Binding> bindings =
        MaterialSystem::source_bindings(CoefficientSourceKind::Environment);
    set_ = system.descriptors().allocate(system.source_layout(CoefficientSourceKind::Environment), bindings);
    gpu::DescriptorWrite writes[6];
    writes[0].binding = HEMI_ENV_BINDING_UNIFORMS;
    writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    writes[0].buffer = {uniforms_, 0, VK_WHOLE_SIZE};
    const gpu::Image* images[5] = {&maps_->mirror_map(), &maps_->glossy_map(glossy_), &maps_->diffuse_map(),
                                   &maps_->fresnel_table(), &brdf_};
    const uint32_t binding[5] = {HEMI_ENV_BINDING_MIRROR, HEMI_ENV_BINDING_GLOSSY, HEMI_ENV_BINDING_DIFFUSE,
                                 HEMI_ENV_BINDING_FRESNEL, HEMI_ENV_BINDING_BRDF};
    for (int i = 0; i < 5; ++i)
    {
        writes[1 + i].binding = binding[i];
        writes[1 + i].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        writes[1 + i].image = {maps_->sampler(), images[i]->view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    gpu::write_descriptors(device, set_, writes);
}

shared::EnvironmentUniforms EnvironmentLighting::uniforms(const EnvironmentMaterial& m) const
{
    check_values(m);
    check_probes(*maps_, m);
    shared::EnvironmentUniforms u{};
    u.extents =
        glm::vec4(maps_->mirror_extent(), maps_->glossy_extent(glossy_), maps_->diffuse_extent(), 0.0f);
    u.material = glm::vec4(m.kd, m.ks, (float(fresnel_row_) + 0.5f) / float(maps_->fresnel_rows()),
                           m.coating ? 1.0f : 0.0f);
    u.tables = glm::vec4(float(table_size_), float(maps_->fresnel_samples()),
                         m.box_projection ? float(m.probes.size()) : 0.0f, 0.0f);
    for (int r = 0; r < 3; ++r) // rows of world_to_env (glm is column-major: element [column][row])
        u.world_to_env[r] = glm::vec4(m.world_to_env[0][r], m.world_to_env[1][r], m.world_to_env[2][r],
                                      m.box_projection ? m.world_to_env_offset[r] : 0.0f);
    for (size_t k = 0; k < m.probes.size() && m.box_projection; ++k)
    {
        u.probe_centre[k] = glm::vec4(m.probes[k].centre, m.probes[k].fade);
        u.probe_box_min[k] = glm::vec4(m.probes[k].box_min, 0.0f);
        u.probe_box_max[k] = glm::vec4(m.probes[k].box_max, 0.0f);
    }
    return u;
}

void EnvironmentLighting::record_update(VkCommandBuffer cmd, const EnvironmentMaterial& material) const
{
    const shared::EnvironmentUniforms u = uniforms(material);
    record_uniform_update(cmd, uniforms_, &u, sizeof u);
}

} // namespace hemi::render
