#pragma once
// The sh_normalmap sample's scene, shared by the sample program and its test: a UV sphere with a
// procedural brick normal map, lit per pixel by SH9 irradiance from an analytic sky or a constant
// environment.

#include <hemi/gpu/device.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/math/sh.h>

#include <glm/mat4x4.hpp>

#include <cstdint>
#include <vector>

namespace hemi::samples
{

enum class Environment
{
    Sky,     // math::AnalyticSky
    Uniform, // radiance 1 from every direction: E = pi everywhere, the white furnace
};

struct ShNormalMapScene
{
    io::Mesh mesh;
    std::vector<uint8_t> normal_map; // RGBA8
    uint32_t map_width = 0, map_height = 0;
    math::Sh9Rgb irradiance{};
    glm::vec3 albedo{0.8f};
    glm::vec3 eye{0.0f, -3.2f, 1.1f};
};

ShNormalMapScene make_sh_normalmap_scene(Environment environment);

// Running-bond bricks as a height field (w x h, row-major, top row first): `columns` bricks across, `rows`
// rows down, bevelled edges, mortar at height 0, brick tops at `amplitude`. Tiles seamlessly.
std::vector<float> brick_heights(uint32_t w, uint32_t h, float amplitude, float columns = 32.0f,
                                 float rows = 16.0f);

// Renders the scene at width x height; returns the linear colour and, if `aux` is given, the auxiliary
// attachment ((u, v, 0, 1) where the sphere covers the pixel).
io::ImageRgba render_sh_normalmap(const gpu::Device& device, const ShNormalMapScene& scene, uint32_t width,
                                  uint32_t height, io::ImageRgba* aux = nullptr);

} // namespace hemi::samples
