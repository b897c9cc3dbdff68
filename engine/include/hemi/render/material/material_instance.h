#pragma once
// Material instances: one glTF material's factors and textures as descriptor set 1 of the material system,
// and the GPU textures of a scene's images they sample (decoded once, mipmapped, shared by every material
// and every object instance that uses them).

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/resources.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/image.h>
#include <hemi/io/material.h>
#include <hemi/render/material/material_system.h>

#include <map>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace hemi::render
{

class TextureSet
{
  public:
    // Decodes every image (io::decode_image: FormatError naming the image when it is corrupt) and creates
    // it with a full mip chain, filled through `upload`. `materials` say how each image is used: base colour
    // and emissive maps are sRGB, normal maps linear (an image used both ways is created twice).
    TextureSet(const gpu::Device& device, std::span<const io::EncodedImage> images,
               std::span<const io::Material> materials, gpu::UploadBatch& upload);
    // The same from decoded RGBA8 images (procedural textures, an engine's own decoder).
    TextureSet(const gpu::Device& device, std::span<const io::ImageRgba8> images,
               std::span<const io::Material> materials, gpu::UploadBatch& upload);

    // The image `index` (or, for -1, a 1x1 default: white for colour, the flat normal (0, 0, 1) for normals).
    const gpu::Image& image(int index, bool srgb) const;
    // A sampler for glTF's sampler state (cached: one per distinct state; not thread-safe).
    VkSampler sampler(const io::TextureSampler& state) const;

  private:
    void create(std::span<const io::ImageRgba8> images, std::span<const io::Material> materials,
                gpu::UploadBatch& upload);
    const gpu::Device* device_;
    std::map<std::pair<int, bool>, gpu::Image> images_;
    mutable std::vector<std::pair<io::TextureSampler, gpu::Sampler>> samplers_;
};

// A texture of the engine's own for one slot of a material: a 2D view of an image in
// SHADER_READ_ONLY_OPTIMAL (sRGB formats for base colour and emissive, linear for the normal map and
// occlusion, as glTF stores them) and the sampler to read it with. The engine keeps both alive while the
// instance is drawn. A null view leaves the slot to the material's TextureSet image (or its default).
struct EngineTexture
{
    VkImageView view = VK_NULL_HANDLE;
    VkSampler sampler = VK_NULL_HANDLE;
};
struct MaterialTextures
{
    EngineTexture base_color, normal, emissive, occlusion;
};

class MaterialInstance
{
  public:
    // The material's factors, UV sets and texture transforms from `material`; each texture from `engine`
    // where it names a view, else from `textures` (an empty TextureSet gives the defaults: white, the flat
    // normal). Throws std::invalid_argument when the material refers to an image the set does not have, or
    // an engine texture has a view and no sampler.
    MaterialInstance(const MaterialSystem& system, const TextureSet& textures, const io::Material& material,
                     gpu::UploadBatch& upload, const MaterialTextures& engine = {});
    VkDescriptorSet set() const { return set_.get(); }
    bool double_sided() const { return double_sided_; }
    io::AlphaMode alpha_mode() const { return alpha_mode_; }

  private:
    gpu::Buffer uniforms_;
    gpu::DescriptorSet set_;
    bool double_sided_ = false;
    io::AlphaMode alpha_mode_ = io::AlphaMode::Opaque;
};

// The MaterialUniforms block of a material (KHR_texture_transform rows, factors, UV sets): what the surface
// shader reads, for tests that evaluate the material on the CPU.
shared::MaterialUniforms material_uniforms(const io::Material& material);

} // namespace hemi::render
