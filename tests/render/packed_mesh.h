#pragma once
// A mesh in an engine's own packed layout, as the tests build one: two streams, fp16 RGBA positions
// (8 bytes) in stream 0; snorm16 RGBA normal and glTF tangent, then fp32 TEXCOORD_0 and TEXCOORD_1 (the
// first set again where the mesh has no second) in stream 1 (32 bytes); 16-bit indices. `widened` is the
// mesh with the packed values widened back on the CPU, exactly as the device reads them, so that an image
// drawn from the packed streams can be held to one drawn from hemi's fp32 layout of the same values (the
// comparison is then of the data path, not of the quantisation).
#include <hemi/io/mesh.h>
#include <hemi/render/material/material_system.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace hemi::test
{

struct PackedAttributes
{
    int16_t normal[4], tangent[4];
    float uv0[2], uv1[2];
};
static_assert(sizeof(PackedAttributes) == 32);

struct PackedMesh
{
    std::vector<uint16_t> positions; // 4 per vertex
    std::vector<PackedAttributes> attributes;
    std::vector<uint16_t> indices;
    io::Mesh widened;

    static render::VertexLayout layout()
    {
        render::VertexLayout l;
        l.position = {0, VK_FORMAT_R16G16B16A16_SFLOAT, 0};
        l.normal = {1, VK_FORMAT_R16G16B16A16_SNORM, offsetof(PackedAttributes, normal)};
        l.tangent = {1, VK_FORMAT_R16G16B16A16_SNORM, offsetof(PackedAttributes, tangent)};
        l.uv0 = {1, VK_FORMAT_R32G32_SFLOAT, offsetof(PackedAttributes, uv0)};
        l.uv1 = {1, VK_FORMAT_R32G32_SFLOAT, offsetof(PackedAttributes, uv1)};
        l.strides[0] = 8;
        l.strides[1] = sizeof(PackedAttributes);
        return l;
    }
};

// Round-to-nearest fp32 -> fp16 for normal numbers in range (|x| well below 65504); tiny values become 0.
inline uint16_t to_half(float f)
{
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    const uint32_t sign = (bits >> 16) & 0x8000u;
    const int exponent = int((bits >> 23) & 0xffu) - 127 + 15;
    if (exponent <= 0)
        return uint16_t(sign);
    const uint32_t mantissa = bits & 0x7fffffu;
    uint32_t h = sign | (uint32_t(exponent) << 10) | (mantissa >> 13);
    if ((mantissa & 0x1fffu) > 0x1000u || ((mantissa & 0x1fffu) == 0x1000u && (h & 1u)))
        ++h;
    return uint16_t(h);
}

inline float from_half(uint16_t h)
{
    const uint32_t sign = uint32_t(h & 0x8000u) << 16, exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
    const uint32_t bits = exponent == 0 ? sign : sign | ((exponent - 15 + 127) << 23) | (mantissa << 13);
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

inline int16_t to_snorm16(float f)
{
    return int16_t(std::lround(std::clamp(f, -1.0f, 1.0f) * 32767.0f));
}

inline float from_snorm16(int16_t v)
{
    return std::max(-1.0f, float(v) / 32767.0f);
}

inline PackedMesh pack_mesh(const io::Mesh& m)
{
    const size_t n = m.vertex_count();
    if (n >= 65536)
        throw std::invalid_argument("pack_mesh: more vertices than 16-bit indices address");
    PackedMesh p;
    p.positions.resize(n * 4);
    p.attributes.resize(n);
    p.widened = m;
    for (size_t v = 0; v < n; ++v)
    {
        for (int c = 0; c < 3; ++c)
        {
            p.positions[v * 4 + c] = to_half(m.positions[v][c]);
            p.attributes[v].normal[c] = to_snorm16(m.normals[v][c]);
            p.widened.positions[v][c] = from_half(p.positions[v * 4 + c]);
            p.widened.normals[v][c] = from_snorm16(p.attributes[v].normal[c]);
        }
        p.positions[v * 4 + 3] = to_half(1.0f);
        p.attributes[v].normal[3] = 0;
        for (int c = 0; c < 4; ++c)
        {
            p.attributes[v].tangent[c] = to_snorm16(m.tangents[v][c]);
            p.widened.tangents[v][c] = from_snorm16(p.attributes[v].tangent[c]);
        }
        const glm::vec2 uv1 = m.uvs1.empty() ? m.uvs[v] : m.uvs1[v];
        p.attributes[v].uv0[0] = m.uvs[v].x;
        p.attributes[v].uv0[1] = m.uvs[v].y;
        p.attributes[v].uv1[0] = uv1.x;
        p.attributes[v].uv1[1] = uv1.y;
    }
    if (m.uvs1.empty())
        p.widened.uvs1 = m.uvs;
    p.indices.assign(m.indices.begin(), m.indices.end());
    return p;
}

} // namespace hemi::test
