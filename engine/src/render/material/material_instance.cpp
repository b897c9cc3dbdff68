#include <hemi/gpu/vk_check.h>
#include <hemi/io/image.h>
#include <hemi/render/material/material_instance.h>

#include <stdexcept>
#include <string>

namespace hemi::render
{
namespace
{
VkSamplerAddressMode address(io::Wrap w)
{
    switch (w)
    {
    case io::Wrap::ClampToEdge:
        return VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    case io::Wrap::MirroredRepeat:
        return VK_SAMPLER_ADDRESS_MODE_MIRRORED_REPEAT;
    case io::Wrap::Repeat:
        break;
    }
    return VK_SAMPLER_ADDRESS_MODE_REPEAT;
}
VkFilter filter(io::Filter f)
{
    return f == io::Filter::Nearest ? VK_FILTER_NEAREST : VK_FILTER_LINEAR;
}
} // namespace

TextureSet::TextureSet(const gpu::Device& device, std::span<const io::EncodedImage> images,
                       std::span<const io::Material> materials, gpu::UploadBatch& upload)
    : device_(&device)
{
    // Decode only what a material uses (an unused image may be anything).
    std::vector<io::ImageRgba8> decoded(images.size());
    for (const io::Material& m : materials)
        for (const io::TextureRef* r : {&m.base_color, &m.normal, &m.emissive, &m.occlusion})
        {
            if (r->image >= 0 && size_t(r->image) >= images.size())
                throw std::invalid_argument("hemi: material '" + m.name + "' uses image " +
                                            std::to_string(r->image) + " of " +
                                            std::to_string(images.size()));
            if (r->image >= 0 && decoded[size_t(r->image)].pixels.empty())
                decoded[size_t(r->image)] = io::decode_image(images[size_t(r->image)]);
        }
    create(decoded, materials, upload);
    // Named as the scene names them (a glTF image's name, else its index).
    for (const auto& [slot, image] : images_)
        if (slot.first >= 0)
        {
            const std::string& name = images[size_t(slot.first)].name;
            device.set_name(VK_OBJECT_TYPE_IMAGE, image.handle(),
                            "hemi texture '" + (name.empty() ? std::to_string(slot.first) : name) +
                                (slot.second ? "' (sRGB)" : "'"));
        }
}

TextureSet::TextureSet(const gpu::Device& device, std::span<const io::ImageRgba8> images,
                       std::span<const io::Material> materials, gpu::UploadBatch& upload)
    : device_(&device)
{
    create(images, materials, upload);
}

void TextureSet::create(std::span<const io::ImageRgba8> images, std::span<const io::Material> materials,
                        gpu::UploadBatch& upload)
{
    const gpu::Device& device = *device_;
    auto need = [&](int index, bool srgb)
    {
        if (index < 0)
            return;
        if (size_t(index) >= images.size())
            throw std::invalid_argument("hemi: a material uses image " + std::to_string(index) + " of " +
                                        std::to_string(images.size()));
        if (images_.count({index, srgb}))
            return;
        const io::ImageRgba8& texels = images[size_t(index)];
        if (texels.width == 0 || texels.height == 0 ||
            texels.pixels.size() != size_t(texels.width) * texels.height * 4)
            throw std::invalid_argument("hemi: image " + std::to_string(index) +
                                        " is empty or not RGBA8 of its size");
        gpu::Image image = gpu::create_image(
            device, {texels.width, texels.height, srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM,
                     VK_IMAGE_USAGE_SAMPLED_BIT, gpu::full_mip_count(texels.width, texels.height)});
        upload.image(image, texels.pixels.data(), texels.pixels.size());
        images_.emplace(std::make_pair(index, srgb), std::move(image));
    };
    for (const io::Material& m : materials)
    {
        need(m.base_color.image, true);
        need(m.emissive.image, true);
        need(m.normal.image, false);
        need(m.occlusion.image, false);
    }
    const uint8_t white[4] = {255, 255, 255, 255}, flat[4] = {128, 128, 255, 255};
    for (bool srgb : {true, false})
    {
        gpu::Image image =
            gpu::create_image(device, {1, 1, srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM});
        upload.image(image, srgb ? white : flat, 4);
        images_.emplace(std::make_pair(-1, srgb), std::move(image));
    }
}

const gpu::Image& TextureSet::image(int index, bool srgb) const
{
    auto it = images_.find({index < 0 ? -1 : index, srgb});
    if (it == images_.end())
        throw std::invalid_argument("hemi: image " + std::to_string(index) + " is not in the texture set");
    return it->second;
}

VkSampler TextureSet::sampler(const io::TextureSampler& state) const
{
    for (const auto& [s, sampler] : samplers_)
        if (s == state)
            return sampler;
    VkSamplerCreateInfo info{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    info.magFilter = filter(state.mag_filter);
    info.minFilter = filter(state.min_filter);
    info.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
    info.addressModeU = address(state.wrap_s);
    info.addressModeV = address(state.wrap_t);
    info.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
    info.maxLod = state.mipmaps ? VK_LOD_CLAMP_NONE : 0.0f; // no mipmapped minification: mip 0 only
    VkSampler sampler;
    HEMI_VK_CHECK(vkCreateSampler(device_->device(), &info, nullptr, &sampler));
    device_->set_name(VK_OBJECT_TYPE_SAMPLER, sampler, "hemi material sampler");
    samplers_.emplace_back(state, gpu::Sampler(device_->device(), sampler));
    return samplers_.back().second;
}

shared::MaterialUniforms material_uniforms(const io::Material& m)
{
    shared::MaterialUniforms u{};
    u.base_color_factor = m.base_color_factor;
    // glTF: emissive = factor * texture; without a texture the factor alone (the default image is white).
    // Without a normal texture the default texel (128, 128, 255) decodes to a normal tilted by 0.32 degrees
    // (8 bits have no 0.5): a normal scale of 0 makes it the surface normal exactly (mirror reflections show
    // it).
    u.emissive_factor = glm::vec4(m.emissive_factor, m.normal.present() ? m.normal_scale : 0.0f);
    const io::TextureRef* refs[4] = {&m.base_color, &m.normal, &m.emissive, &m.occlusion};
    for (int t = 0; t < 4; ++t)
    {
        const glm::mat3 x = refs[t]->present() ? refs[t]->uv_transform() : glm::mat3(1.0f);
        // Rows of the 2x3 affine part: u' = x[0][0] u + x[1][0] v + x[2][0] (glm is column-major).
        u.uv_transform[t * 2] = glm::vec4(x[0][0], x[1][0], x[2][0], 0.0f);
        u.uv_transform[t * 2 + 1] = glm::vec4(x[0][1], x[1][1], x[2][1], 0.0f);
    }
    u.texcoord =
        glm::uvec4(m.base_color.texcoord, m.normal.texcoord, m.emissive.texcoord, m.occlusion.texcoord);
    u.occlusion = glm::vec4(m.occlusion_strength, m.alpha_cutoff, 0.0f, 0.0f);
    return u;
}

MaterialInstance::MaterialInstance(const MaterialSystem& system, const TextureSet& textures,
                                   const io::Material& material, gpu::UploadBatch& upload,
                                   const MaterialTextures& engine)
    : double_sided_(material.double_sided), alpha_mode_(material.alpha_mode)
{
    const gpu::Device& device = system.device();
    for (const io::TextureRef* r :
         {&material.base_color, &material.normal, &material.emissive, &material.occlusion})
        if (r->texcoord > 1)
            throw std::invalid_argument("hemi: material '" + material.name + "' uses TEXCOORD_" +
                                        std::to_string(r->texcoord) +
                                        "; hemi reads TEXCOORD_0 and TEXCOORD_1");
    const shared::MaterialUniforms u = material_uniforms(material);
    uniforms_ = gpu::create_buffer(device, {sizeof u, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    upload.buffer(uniforms_, &u, sizeof u);
    const auto bindings = MaterialSystem::material_bindings();
    set_ = system.descriptors().allocate(system.material_layout(), bindings);
    gpu::DescriptorWrite writes[5];
    writes[0].binding = HEMI_MATERIAL_BINDING_UNIFORMS;
    writes[0].type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    writes[0].buffer = {uniforms_, 0, VK_WHOLE_SIZE};
    // Without an occlusion texture the default is the white sRGB texel (1: no occlusion), not the flat
    // normal.
    const bool occlusion_srgb = !material.occlusion.present();
    struct Slot
    {
        uint32_t binding;
        const io::TextureRef* ref;
        bool srgb;
        const EngineTexture* engine;
        const char* name;
    };
    const Slot maps[4] = {
        {HEMI_MATERIAL_BINDING_BASE_COLOR, &material.base_color, true, &engine.base_color, "base colour"},
        {HEMI_MATERIAL_BINDING_NORMAL, &material.normal, false, &engine.normal, "normal"},
        {HEMI_MATERIAL_BINDING_EMISSIVE, &material.emissive, true, &engine.emissive, "emissive"},
        {HEMI_MATERIAL_BINDING_OCCLUSION, &material.occlusion, occlusion_srgb, &engine.occlusion,
         "occlusion"},
    };
    for (int i = 0; i < 4; ++i)
    {
        const Slot& m = maps[i];
        writes[i + 1].binding = m.binding;
        writes[i + 1].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        if (m.engine->view != VK_NULL_HANDLE)
        {
            if (m.engine->sampler == VK_NULL_HANDLE)
                throw std::invalid_argument("hemi: material '" + material.name + "': the engine's " + m.name +
                                            " texture has a view and no sampler");
            writes[i + 1].image = {m.engine->sampler, m.engine->view,
                                   VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
        }
        else
            writes[i + 1].image = {textures.sampler(m.ref->sampler),
                                   textures.image(m.ref->image, m.srgb).view(),
                                   VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    gpu::write_descriptors(device, set_, writes);
}

} // namespace hemi::render
