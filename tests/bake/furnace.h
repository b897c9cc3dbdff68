#pragma once
// The furnace of the lightmap tests: a closed box whose every surface looks in and emits radiance 1, lit by
// nothing from outside. With albedo 0.5 and B bounces every texel's irradiance is pi * sum_{k=0..B} 0.5^k.
#include "quads.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>

#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace hemi::test
{

// `mesh` (unit_box(true) unless given) with one material of base colour `albedo` and emission 1, its
// surfaces, its width x height atlas from its own lightmap UVs, and `dark`: a uniform sky of 0. Not copyable:
// `surfaces` points at `mesh`. Throws if the UVs do not rasterise cleanly.
struct FurnaceBox
{
    io::Mesh mesh;
    std::vector<io::Material> materials;
    std::vector<io::Primitive> primitives;
    bake::LightmapSurfaces surfaces;
    bake::LightmapAtlas atlas;
    bake::LightmapLights dark;

    explicit FurnaceBox(glm::vec3 albedo = glm::vec3(0.5f), io::Mesh box = unit_box(true),
                        uint32_t width = 48, uint32_t height = 32)
        : mesh(std::move(box)), materials{emitter(albedo)}, primitives{{0, uint32_t(mesh.indices.size()), 0}},
          surfaces(mesh, materials, {}, primitives)
    {
        bake::LightmapUvReport report;
        atlas = bake::rasterize_lightmap(mesh, width, height, report);
        if (!report.ok())
            throw std::runtime_error("the furnace box's lightmap UVs: " + report.problems[0]);
        dark.uniform = glm::vec3(0.0f);
    }
    FurnaceBox(const FurnaceBox&) = delete;
    FurnaceBox& operator=(const FurnaceBox&) = delete;

  private:
    static io::Material emitter(glm::vec3 albedo)
    {
        io::Material m;
        m.base_color_factor = glm::vec4(albedo, 1.0f);
        m.emissive_factor = glm::vec3(1.0f);
        return m;
    }
};

} // namespace hemi::test
