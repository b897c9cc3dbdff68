#pragma once
// The prt_normalmap sample's models, shared with the tests: Sloan 2006 compares techniques on a "simple"
// object (~700 vertices) and a "complex" one (~30,000) with self-occlusion and a strong normal map. Both are
// made in code and written as glTF 2.0 with PNG textures, so they go through the same hemi-bake prt path a
// pipeline's assets do.
//   simple : a torus, 703 vertices: concave, mild self-shadowing in its hole.
//   complex: a trefoil knot tube, 29,197 vertices: its strands shadow and light each other.
// Both carry a brick normal map (bevelled, strong) and a brick base colour.

#include <hemi/io/image.h>
#include <hemi/io/mesh.h>

#include <filesystem>
#include <string>

namespace hemi::samples
{

enum class PrtModel
{
    Simple,
    Complex,
};

// The mesh in glTF space (y up). `detail` scales the tessellation in both directions (1 = the sample's).
io::Mesh make_prt_model(PrtModel model, float detail = 1.0f);

// The brick normal map (tangent space, glTF convention) and base colour (sRGB), width x height.
io::ImageRgba8 brick_normal_map(uint32_t width, uint32_t height);
io::ImageRgba8 brick_base_color(uint32_t width, uint32_t height);

// Writes DIR/NAME.gltf (buffers embedded) with DIR/NAME_normal.png and DIR/NAME_base_color.png next to it;
// returns the .gltf path. `flat` leaves the normal map out (the geometric normals alone).
std::filesystem::path write_prt_model(const std::filesystem::path& dir, const std::string& name,
                                      PrtModel model, float detail = 1.0f, bool flat = false);

} // namespace hemi::samples
