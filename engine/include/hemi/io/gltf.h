#pragma once
// glTF 2.0 scenes (.gltf with external or embedded buffers, and .glb) into one hemi Mesh in scene space with
// its materials and images, read with tinygltf (Debian's libtinygltf); and a writer for such scenes.
//
// Every triangle primitive of every mesh node of the default scene (or scene 0, or every mesh when the file
// has no scene) is transformed by its node's world matrix and appended; each becomes one io::Primitive (a run
// of mesh.indices, in the order the node tree is walked depth-first) with its own material. Triangle strips
// and fans become lists; points and lines are skipped with a warning. Attributes may be floats or
// (normalised) integers (KHR_mesh_quantization), sparse or not. Normals are the file's, or area-weighted
// vertex normals when absent. Tangents are the file's, or generated from the UV layout when absent, with
// MikkTSpace's construction: each triangle's UV tangent and bitangent, projected into the plane of the
// corner's vertex normal and normalised, accumulated per vertex weighted by the corner angle, handedness in
// w. It is not a bit-exact MikkTSpace (which Debian does not package): MikkTSpace also splits vertices whose
// neighbouring triangles disagree on handedness, where this keeps the file's vertices.
//
// Materials keep what io::Material holds (base colour, normal and emissive factors and textures,
// KHR_texture_transform, samplers, UV sets 0 and 1, doubleSided; KHR_materials_emissive_strength is folded
// into the emissive factor). Occlusion and metallic-roughness textures are not read. Images stay encoded, one
// per glTF image that a material uses, from external files (URIs relative to the glTF file, percent-decoded),
// .glb buffer views or base64 data URIs; each is checked to be PNG or JPEG by its signature (decoded later,
// by io::decode_image).
//
// What hemi reads as something simpler or ignores is reported in GltfScene::warnings, one line per feature
// naming it (skins: drawn in the bind pose; morph targets; alphaMode MASK/BLEND: opaque; KHR_materials_*,
// KHR_lights_punctual, EXT_texture_webp, KHR_texture_basisu, vertex colours, TEXCOORD_2+, animations, ...).
// What makes the geometry unreadable is a FormatError: Draco or meshopt compression without an uncompressed
// fallback (KHR_draco_mesh_compression, EXT_meshopt_compression in extensionsRequired), any other required
// extension hemi does not know, glTF 1.0.

#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace hemi::io
{

// How a light is baked (glTF: the light's or its node's extras.hemi_bake_mode, "baked", "mixed" or
// "realtime"; the light's own wins): Baked, its direct and indirect light in the lightmap; Mixed, only its
// indirect light in the lightmap and its direct visibility in a shadowmask channel, its direct light given at
// run time (a sun that lights dynamic objects and casts their shadows); Realtime, not baked at all.
enum class LightMode : uint8_t
{
    Baked,
    Mixed,
    Realtime,
};
// "baked", "mixed", "realtime"; and back (false for another name).
const char* light_mode_name(LightMode mode);
bool parse_light_mode(std::string_view name, LightMode& mode);

// A KHR_lights_punctual light placed by a node, in scene space (the node's world transform applied).
// Units as glTF's: point and spot intensity in candela (lm/sr), directional in lux (lm/m^2); hemi's lighting
// unit is glTF's photometric one (a directional light of intensity 1 gives irradiance 1).
struct PunctualLight
{
    enum class Type
    {
        Directional,
        Point,
        Spot,
    };
    Type type = Type::Point;
    std::string name;
    glm::vec3 color{1.0f};
    float intensity = 1.0f;
    float range = 0.0f;                     // 0: infinite (glTF's "undefined")
    float inner_cone = 0.0f;                // spot: radians, 0 <= inner < outer <= pi/2
    float outer_cone = 0.785398163f;        // pi/4, glTF's default
    glm::vec3 position{0.0f};               // point, spot
    glm::vec3 direction{0.0f, 0.0f, -1.0f}; // unit, where the light points (the node's -Z): directional, spot
    LightMode mode = LightMode::Baked;
};

inline constexpr const char* kLightProbeNodePrefix = "hemi_probe";

struct GltfScene
{
    Mesh mesh;                         // every primitive, in scene space; mesh.uvs1 when any has TEXCOORD_1
    std::vector<Material> materials;   // the file's materials, then a default one when a primitive has none
    std::vector<EncodedImage> images;  // every image a material uses (external, .glb buffer view, data URI)
    std::vector<Primitive> primitives; // ranges of mesh.indices, in order, covering all of them
    std::vector<PunctualLight> lights; // KHR_lights_punctual lights placed by the scene's nodes
    // Light probes placed by hand: the origin of every node of the scene whose name starts with
    // kLightProbeNodePrefix (Blender: an empty named "hemi_probe", its copies "hemi_probe.001", ...), in
    // scene space (hemi-bake lightmap --probes gltf bakes them).
    std::vector<glm::vec3> light_probes;
    std::vector<std::string> warnings; // features read as something simpler or ignored, each named once
    bool tangents_generated = false;
};

// Throws FormatError naming the file and the problem: missing or malformed file, glTF 1.0, truncated .glb, a
// required extension hemi cannot read, a primitive that lacks POSITION or has an unknown mode, an accessor
// that reads past its buffer, an index out of range, a non-finite attribute or factor, a node hierarchy that
// is not a forest (a node reached twice), a referenced image that does not exist or is neither PNG nor JPEG,
// or no triangles at all.
GltfScene read_gltf(const std::filesystem::path& path);

// Writes `mesh` (positions, normals, tangents and UVs when present, 32-bit indices) as one glTF 2.0 mesh node
// with one material, buffers embedded: a .glb when the path ends in ".glb", else a .gltf. The texture
// references (URIs relative to the glTF file; empty for none) are written as they are: the files are the
// caller's. Atomic. Throws std::invalid_argument for an inconsistent mesh, FormatError on I/O failure.
void write_gltf(const std::filesystem::path& path, const Mesh& mesh, const std::string& base_color_uri = {},
                const std::string& normal_uri = {});

// Where write_gltf puts an image.
enum class ImageStorage
{
    External,   // a file beside the glTF file: the image's name when it is a plain .png/.jpg file name, else
                // "<glTF stem>_image<i>.<ext>"; the URI percent-encoded
    BufferView, // its bytes in the glTF's buffer (the .glb's binary chunk, or the .gltf's embedded buffer)
    DataUri,    // a base64 data URI in the JSON
};

// Writes `scene` as a glTF 2.0 file the way exporters such as Blender do: one mesh node, one glTF primitive
// per io::Primitive with its own attribute accessors (the vertices it uses, in their order) and its
// material, every material with its textures, samplers and KHR_texture_transform, the light probes as empty
// nodes named hemi_probe, hemi_probe.1, ... at their points, every image stored as
// `storage[i]` says (one entry per image; the single-value overload stores all alike). A primitive whose
// TEXCOORD_1 values are all (0, 0) is written without TEXCOORD_1, which is what read_gltf reads for one
// without it. A .glb when the path ends in ".glb", else a .gltf with its buffer embedded. Atomic (each file).
// Throws std::invalid_argument for an inconsistent scene (io::mesh_problem, io::surface_problem) or a
// storage list of the wrong size, FormatError on I/O failure.
void write_gltf(const std::filesystem::path& path, const GltfScene& scene,
                ImageStorage storage = ImageStorage::BufferView);
void write_gltf(const std::filesystem::path& path, const GltfScene& scene,
                const std::vector<ImageStorage>& storage);

} // namespace hemi::io
