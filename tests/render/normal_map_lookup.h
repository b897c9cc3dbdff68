#pragma once
// The CPU side of a normal-map lookup, as VkSampler with VK_FILTER_LINEAR and REPEAT does it: the
// independent evaluation that the GPU materials are compared with.
#include "scene.h"

#include <hemi/io/image.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cmath>

namespace hemi::test
{

inline glm::vec3 sample_bilinear(const hemi::samples::ShNormalMapScene& s, glm::vec2 uv)
{
    float x = uv.x * s.map_width - 0.5f, y = uv.y * s.map_height - 0.5f;
    int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    float fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi)
    {
        xi = ((xi % int(s.map_width)) + int(s.map_width)) % int(s.map_width);
        yi = ((yi % int(s.map_height)) + int(s.map_height)) % int(s.map_height);
        const uint8_t* p = &s.normal_map[(size_t(yi) * s.map_width + xi) * 4];
        return glm::vec3(p[0], p[1], p[2]) / 255.0f;
    };
    return (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) +
           (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
}

// Whether pixel (x, y) of a render of make_uv_sphere is one the CPU references compare: the mesh covers its 5
// x 5 neighbourhood (not a silhouette, where frames are interpolated across the edge) and its UV (returned)
// is away from the poles (degenerate tangents) and the u seam.
inline bool comparable_sphere_pixel(const hemi::io::ImageRgba& aux, uint32_t x, uint32_t y, glm::vec2& uv)
{
    for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx)
            if (aux.at(x + dx, y + dy)[3] != 1.0f)
                return false;
    uv = glm::vec2(aux.at(x, y)[0], aux.at(x, y)[1]);
    return uv.y >= 0.1f && uv.y <= 0.9f && uv.x >= 0.01f && uv.x <= 0.99f;
}

} // namespace hemi::test
