#pragma once
// The tests' small two-primitive level: a floor z = 0 over [-1, 1]^2 (primitive 0, material 0) and a table
// top z = 0.5 over [-0.5, 0.5]^2 (primitive 1, material 1), both facing up with their own lightmap charts,
// baked under a sky and a sun at 32^2 into `outputs`. The caller gives the two materials and their images.
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/lightmap_asset.h>

#include <glm/geometric.hpp>

#include <string>
#include <vector>

namespace hemi::test
{

inline io::LightmapAsset table_level(const io::Material& floor, const io::Material& top,
                                     std::vector<io::EncodedImage> images,
                                     const std::vector<std::string>& outputs)
{
    io::LightmapAsset a;
    io::Mesh& m = a.mesh;
    auto quad = [&](float half, float z, glm::vec2 uv_origin)
    {
        const uint32_t base = uint32_t(m.positions.size());
        const glm::vec2 corners[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const glm::vec2& c : corners)
        {
            m.positions.emplace_back(half * c.x, half * c.y, z);
            m.normals.emplace_back(0, 0, 1);
            m.tangents.emplace_back(1, 0, 0, 1);
            m.uvs.push_back(c * 0.5f + 0.5f);
            m.uvs1.push_back(uv_origin + (c * 0.5f + 0.5f) * 0.45f);
        }
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    };
    quad(1.0f, 0.0f, {0.02f, 0.02f});
    quad(0.5f, 0.5f, {0.52f, 0.52f});
    a.images = std::move(images);
    a.materials = {floor, top};
    a.primitives = {{0, 6, 0}, {6, 6, 1}};
    bake::LightmapUvReport report;
    const bake::LightmapAtlas atlas = bake::rasterize_lightmap(m, 32, 32, report);
    bake::LightmapLights lights;
    lights.uniform = glm::vec3(0.3f, 0.35f, 0.4f);
    lights.sun = true;
    lights.sun_direction = glm::normalize(glm::vec3(0.5f, -0.3f, 0.7f));
    lights.sun_irradiance = glm::vec3(2.0f, 1.8f, 1.5f);
    bake::LightmapBakeOptions o;
    o.rays = 16;
    const bake::LightmapSh sh = bake::bake_lightmap_sh(m, atlas, lights, o);
    a.width = a.height = 32;
    a.covered_texels = uint32_t(atlas.texels.size());
    for (const std::string& name : outputs)
        a.outputs.push_back(
            {name, uint32_t(bake::lightmap_output_size(name)), bake::lightmap_maps(name, atlas, sh)});
    return a;
}

} // namespace hemi::test
