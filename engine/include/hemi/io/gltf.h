#pragma once
// glTF 2.0 scenes (.gltf with external or embedded buffers, and .glb) into one hemi Mesh in scene space,
// read with tinygltf (Debian's libtinygltf).
//
// Every triangle primitive of every mesh node of the default scene (or scene 0, or every mesh when the file
// has no scene) is transformed by its node's world matrix and appended. Normals are the file's, or
// area-weighted vertex normals when absent. Tangents are the file's, or generated from the UV layout when
// absent, with MikkTSpace's construction: each triangle's UV tangent and bitangent, projected into the
// plane of the corner's vertex normal and normalised, accumulated per vertex weighted by the corner angle,
// handedness in w. It is not a bit-exact MikkTSpace (which Debian does not package): MikkTSpace also splits
// vertices whose neighbouring triangles disagree on handedness, where this keeps the file's vertices. Texture references are resolved relative to the
// file and must exist.

#include <hemi/io/mesh.h>

#include <filesystem>

namespace hemi::io
{

struct GltfScene
{
    Mesh mesh;
    std::filesystem::path base_color_texture; // empty when the material has none
    std::filesystem::path normal_texture;     // empty when the material has none
    bool tangents_generated = false;
    // Primitives whose material differs from the first one's: their geometry is read, but the textures are
    // the first material's (hemi reads one base colour and one normal map per scene for now).
    size_t ignored_material_primitives = 0;
};

// Throws FormatError naming the file and the problem: missing or malformed file, truncated .glb, a
// primitive that is not a triangle list or lacks POSITION, an accessor that reads past its buffer, an index
// out of range, a non-finite attribute, a referenced texture that does not exist, or no triangles at all.
GltfScene read_gltf(const std::filesystem::path& path);

// Writes `mesh` (positions, normals, tangents and UVs when present, 32-bit indices) as one glTF 2.0 mesh node
// with one material, buffers embedded: a .glb when the path ends in ".glb", else a .gltf. The texture
// references (URIs relative to the glTF file; empty for none) are written as they are: the files are the
// caller's. Atomic. Throws std::invalid_argument for an inconsistent mesh, FormatError on I/O failure.
void write_gltf(const std::filesystem::path& path, const Mesh& mesh, const std::string& base_color_uri = {},
                const std::string& normal_uri = {});

} // namespace hemi::io
