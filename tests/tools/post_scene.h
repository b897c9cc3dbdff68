#pragma once
#include "../png_writer.h"

#include <hemi/io/gltf.h>

#include <glm/geometric.hpp>

#include <filesystem>
#include <vector>

namespace hemi::test
{

// A small level for the command-line tests of whole bakes (export, distributed), written to `p`: a floor of
// 4 x 4 quads in glTF's y-up space with a post standing on it (so that the light has a shadow and a bounce
// to bake), two materials, the floor's with a base colour PNG and a technique in its extras, and
// TEXCOORD_1 laid out by hand: the floor over [0, 0.75] x [0, 1], the post's four sides in columns of
// [0.8, 1] x [0, 1].
inline std::filesystem::path write_post_scene(const std::filesystem::path& p)
{
    hemi::io::GltfScene s;
    hemi::io::Mesh& m = s.mesh;
    auto quad = [&](glm::vec3 o, glm::vec3 du, glm::vec3 dv, glm::vec2 uv0, glm::vec2 uv_size)
    {
        const uint32_t base = uint32_t(m.positions.size());
        const glm::vec3 n = glm::normalize(glm::cross(dv, du));
        const glm::vec2 corners[4] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
        for (const glm::vec2& c : corners)
        {
            m.positions.push_back(o + c.x * du + c.y * dv);
            m.normals.push_back(n);
            m.tangents.emplace_back(glm::normalize(du), 1.0f);
            m.uvs.push_back(c);
            m.uvs1.push_back(uv0 + c * uv_size);
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    };
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i)
            quad({-1.0f + 0.5f * i, 0.0f, -1.0f + 0.5f * j}, {0.5f, 0, 0}, {0, 0, 0.5f},
                 {0.75f * i / 4.0f, j / 4.0f}, {0.75f / 4.0f, 0.25f});
    s.primitives.push_back({0, uint32_t(m.indices.size()), 0});
    // The post, 0.2 wide and 0.8 high, its sides facing out (counter-clockwise seen from outside).
    const float r = 0.1f, hgt = 0.8f;
    const glm::vec3 side[4][2] = {{{-r, 0, r}, {2 * r, 0, 0}},
                                  {{r, 0, r}, {0, 0, -2 * r}},
                                  {{r, 0, -r}, {-2 * r, 0, 0}},
                                  {{-r, 0, -r}, {0, 0, 2 * r}}};
    for (int k = 0; k < 4; ++k)
        quad(side[k][0], side[k][1], {0, hgt, 0}, {0.8f + 0.05f * k, 0.02f}, {0.04f, 0.96f});
    s.primitives.push_back(
        {s.primitives[0].index_count, uint32_t(m.indices.size()) - s.primitives[0].index_count, 1});
    s.materials.resize(2);
    s.materials[0].name = "floor";
    s.materials[0].technique = "sh9";
    s.materials[0].base_color.image = 0;
    s.materials[1].name = "post";
    s.materials[1].base_color_factor = {0.8f, 0.5f, 0.3f, 1.0f};
    std::vector<uint16_t> texels;
    for (int i = 0; i < 16; ++i)
        texels.insert(texels.end(), {uint16_t(i * 16), 128, uint16_t(255 - i * 16)});
    s.images.push_back({"checker.png", "image/png", hemi::test::encode_png_samples(4, 4, 3, 8, texels)});
    hemi::io::write_gltf(p, s);
    return p;
}

} // namespace hemi::test
