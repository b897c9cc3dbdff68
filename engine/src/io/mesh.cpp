#include <hemi/io/mesh.h>

#include <cmath>
#include <stdexcept>

namespace hemi::io
{

namespace
{
template <typename T> bool all_finite(const std::vector<T>& values)
{
    for (const T& v : values)
        for (int c = 0; c < int(sizeof(T) / sizeof(float)); ++c)
            if (!std::isfinite(v[c]))
                return false;
    return true;
}
} // namespace

std::string mesh_problem(const Mesh& m, MeshNeeds needs)
{
    const size_t n = m.vertex_count();
    if (n == 0 || m.indices.empty() || m.indices.size() % 3)
        return "the mesh needs vertices and a non-empty triangle list (" + std::to_string(m.indices.size()) +
               " indices)";
    for (uint32_t i : m.indices)
        if (i >= n)
            return "mesh index " + std::to_string(i) + " is out of range (" + std::to_string(n) +
                   " vertices)";
    if (m.normals.size() != n)
        return "the mesh needs a normal per vertex";
    if (needs == MeshNeeds::Frames && (m.tangents.size() != n || m.uvs.size() != n))
        return "the mesh needs a normal, tangent and UV for each of its " + std::to_string(n) + " vertices";
    if (!m.uvs1.empty() && m.uvs1.size() != n)
        return "the mesh has " + std::to_string(m.uvs1.size()) + " second UVs (TEXCOORD_1) for " +
               std::to_string(n) + " vertices";
    if (!all_finite(m.positions) || !all_finite(m.normals) || !all_finite(m.tangents) || !all_finite(m.uvs) ||
        !all_finite(m.uvs1))
        return "the mesh has a non-finite position or attribute";
    return {};
}

Mesh make_uv_sphere(float radius, uint32_t segments, uint32_t rings)
{
    if (segments < 3 || rings < 2 || !(radius > 0.0f))
        throw std::invalid_argument("hemi: make_uv_sphere needs segments >= 3, rings >= 2 and radius > 0");
    Mesh m;
    for (uint32_t r = 0; r <= rings; ++r)
    {
        float v = float(r) / float(rings);
        float theta = float(M_PI) * v;
        for (uint32_t s = 0; s <= segments; ++s)
        {
            float u = float(s) / float(segments);
            float phi = 2.0f * float(M_PI) * u;
            glm::vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            m.positions.push_back(n * radius);
            m.normals.push_back(n);
            // dP/du points along +phi; cross(n, t) = -dP/dv / |dP/dv|, so w = +1 (see the header).
            m.tangents.push_back(glm::vec4(-std::sin(phi), std::cos(phi), 0.0f, 1.0f));
            m.uvs.push_back(glm::vec2(u, v));
        }
    }
    const uint32_t stride = segments + 1;
    for (uint32_t r = 0; r < rings; ++r)
        for (uint32_t s = 0; s < segments; ++s)
        {
            uint32_t a = r * stride + s, b = a + 1, c = a + stride, d = c + 1;
            // Counter-clockwise from outside: (a, c, b) and (b, c, d).
            if (r != 0)
                m.indices.insert(m.indices.end(), {a, c, b});
            if (r != rings - 1)
                m.indices.insert(m.indices.end(), {b, c, d});
        }
    return m;
}

} // namespace hemi::io
