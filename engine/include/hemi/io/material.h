#pragma once
// Surface materials as glTF 2.0 describes them, the part hemi draws: what io::read_gltf delivers per
// primitive, what a baked asset stores (self-contained: the images travel inside it) and what the render
// layer's material instances are made from.

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hemi::io
{

// glTF sampler state, the subset that maps onto a Vulkan sampler.
enum class Wrap : uint8_t
{
    Repeat,
    ClampToEdge,
    MirroredRepeat,
};
enum class Filter : uint8_t
{
    Linear,
    Nearest,
};
struct TextureSampler
{
    Filter mag_filter = Filter::Linear;
    Filter min_filter = Filter::Linear;
    bool mipmaps = true; // glTF's *_MIPMAP_* minification filters (and its default when unspecified)
    Wrap wrap_s = Wrap::Repeat;
    Wrap wrap_t = Wrap::Repeat;
    bool operator==(const TextureSampler&) const = default;
};

// An image as the source file stores it: PNG or JPEG bytes, kept encoded so that an asset embeds them
// losslessly and at their original size. decode_image() (io/image.h) turns them into texels.
struct EncodedImage
{
    std::string name;      // for messages: the URI, or "<scene file> image N" for embedded ones
    std::string mime_type; // "image/png" or "image/jpeg"
    std::vector<uint8_t> bytes;
    bool operator==(const EncodedImage&) const = default;
};

// Decodes every image once (decode_image), so that a job that will carry or read them finds a corrupt one
// before it starts; the texels are dropped. Throws FormatError naming `container`, the image and the problem.
void check_images(const std::vector<EncodedImage>& images, const std::string& container);

// A material's use of an image.
struct TextureRef
{
    int image = -1;        // index into the scene's (or asset's) images; -1 = no texture
    uint32_t texcoord = 0; // the UV set: 0 = TEXCOORD_0, 1 = TEXCOORD_1 (KHR_texture_transform's applied)
    TextureSampler sampler;
    // KHR_texture_transform: uv' = T(offset) * R(rotation) * S(scale) * uv, rotation in radians,
    // counter-clockwise seen in the UV map (u right, v down): u' = cos r * u + sin r * v,
    // v' = -sin r * u + cos r * v. That is what the extension's TextureTransformTest sample model, Blender,
    // Babylon.js and Cesium do; the GLSL listing in the extension's README has the transposed matrix
    // (KhronosGroup/glTF#1563).
    glm::vec2 offset{0.0f};
    glm::vec2 scale{1.0f};
    float rotation = 0.0f;

    bool present() const { return image >= 0; }
    // The 3x3 matrix of the transform above, applied to (u, v, 1) (column-major, as GLSL and GLM).
    glm::mat3 uv_transform() const;
    bool operator==(const TextureRef&) const = default;
};

// glTF's alphaMode: OPAQUE ignores alpha; MASK draws where the base colour's alpha reaches alphaCutoff;
// BLEND blends by alpha (not depth-written, not in depth prepasses). The bakes treat every surface as
// opaque (read_gltf warns for MASK and BLEND).
enum class AlphaMode
{
    Opaque,
    Mask,
    Blend,
};

// glTF's metallic-roughness material, the inputs hemi's techniques read. Metallic and roughness are not
// read by any technique yet (the precomputed-lighting techniques are diffuse).
struct Material
{
    std::string name;
    glm::vec4 base_color_factor{1.0f}; // linear
    TextureRef base_color;             // sRGB
    TextureRef normal;                 // tangent space, glTF convention (+Y up), linear
    float normal_scale = 1.0f;         // scales the map's x and y
    glm::vec3 emissive_factor{0.0f};   // linear
    TextureRef emissive;               // sRGB
    TextureRef occlusion;            // glTF's occlusionTexture: ambient occlusion in the red channel, linear
    float occlusion_strength = 1.0f; // occlusion = 1 + strength (texel.r - 1)
    bool double_sided = false;       // no back-face culling; back faces are lit with the flipped normal
    AlphaMode alpha_mode = AlphaMode::Opaque;
    // The lighting technique this material asks for when a level is drawn (e.g. "ssbump" for a wall whose
    // normal-map slot holds an SSBump map), from glTF's material extras {"hemi_technique": "..."}; empty: the
    // level's. render::LightmapModel draws it so (and can override it at load).
    std::string technique;
    float alpha_cutoff = 0.5f; // MASK: alpha (base colour factor x texture) below it is cut
    bool operator==(const Material&) const = default;
};

// A run of triangles drawn with one material: indices [first_index, first_index + index_count) of the mesh.
struct Primitive
{
    uint32_t first_index = 0;
    uint32_t index_count = 0;
    uint32_t material = 0; // index into the materials
    bool operator==(const Primitive&) const = default;
};

struct Mesh;

// The first problem with a mesh's surfaces, or an empty string: the one check io::read_gltf's result, the
// glTF writer and the PRT asset (both ways) share. Primitives must be non-empty runs of whole triangles that
// follow each other from index 0 to the last index, each naming an existing material; a texture must name an
// existing image and read UV set 0 or 1 (1 only when the mesh has uvs1); factors and transforms must be
// finite; images must be non-empty PNG or JPEG bytes whose signature matches their mime type.
std::string surface_problem(const Mesh& mesh, const std::vector<Material>& materials,
                            const std::vector<EncodedImage>& images,
                            const std::vector<Primitive>& primitives);

// "image/png" or "image/jpeg" from the bytes' signature (PNG's 8-byte magic, JPEG's SOI marker FF D8 FF), or
// an empty string for anything else.
std::string sniff_image_mime_type(const uint8_t* bytes, size_t size);

} // namespace hemi::io
