#pragma once
// The sections every baked asset (PRT, lightmap) stores the same way: the mesh and the scene's surfaces.
//   mesh.positions  N x 3 f32      mesh.normals   N x 3 f32      mesh.tangents  N x 4 f32 (glTF, w = sign)
//   mesh.uvs        N x 2 f32      mesh.indices   u32 triangle list
//   mesh.uvs1       N x 2 f32, TEXCOORD_1; only when the mesh has it
//   scene.materials UTF-8 JSON {"materials": [...], "images": [{"name", "mime_type", "bytes"}]}: every
//                   io::Material field by name (textures as {"image", "texcoord", "offset", "scale",
//                   "rotation", "sampler": {"mag", "min", "mipmaps", "wrap_s", "wrap_t"}}, absent when none),
//                   and each image's name, mime type and byte count
//   scene.primitives P x 3 u32: first index, index count, material (io::Primitive), covering mesh.indices
//   image.<i>       image i's encoded PNG or JPEG bytes, as the source scene stored them
// Private to the io library.

#include <hemi/io/asset.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <string>
#include <vector>

namespace hemi::io
{

void write_scene_sections(AssetWriter& w, const Mesh& mesh, const std::vector<Material>& materials,
                          const std::vector<EncodedImage>& images, const std::vector<Primitive>& primitives);
// Throws FormatError naming `file` for a missing or malformed section (the checks of what the values mean,
// mesh_problem and surface_problem, are the caller's).
void read_scene_sections(const AssetReader& r, const std::string& file, Mesh& mesh,
                         std::vector<Material>& materials, std::vector<EncodedImage>& images,
                         std::vector<Primitive>& primitives);

} // namespace hemi::io
