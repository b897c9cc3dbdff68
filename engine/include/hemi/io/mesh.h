#pragma once
// A triangle mesh as hemi's readers deliver it and its renderers consume it (glTF 2.0 conventions:
// tangent.w is the handedness, bitangent = cross(normal, tangent.xyz) * tangent.w, which points toward
// decreasing v, i.e. "up" in an OpenGL-style (+Y up) normal map).

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hemi::io
{

struct Mesh
{
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec4> tangents;
    std::vector<glm::vec2> uvs;
    std::vector<glm::vec2> uvs1;   // TEXCOORD_1 (lightmap UVs); empty when the source has none
    std::vector<uint32_t> indices; // triangle list, counter-clockwise seen from outside

    size_t vertex_count() const { return positions.size(); }
};

// What a consumer of a mesh needs beyond positions and triangles.
enum class MeshNeeds
{
    Normals, // a normal per vertex (the bake)
    Frames,  // a normal, tangent and UV per vertex (materials, baked assets)
};

// The first problem with `mesh`, or an empty string: no vertices or triangles, an index count that is not a
// multiple of 3, an index out of range, a missing attribute, uvs1 neither empty nor one per vertex, a
// non-finite position or attribute. The one check every reader, baker and renderer of meshes shares.
std::string mesh_problem(const Mesh& mesh, MeshNeeds needs);

// A UV sphere of radius `radius` centred at the origin, z up: u = phi / 2pi (around z, from +x),
// v = theta / pi (from +z down). `segments` >= 3 around, `rings` >= 2 from pole to pole; the seam and the
// poles have duplicated vertices so that UVs and tangents are continuous per triangle.
Mesh make_uv_sphere(float radius, uint32_t segments, uint32_t rings);

} // namespace hemi::io
