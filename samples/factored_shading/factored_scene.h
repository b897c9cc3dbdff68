#pragma once
// The factored_shading sample's scenes, shared by the sample program, its test and the benchmark: Heidrich &
// Seidel 1999's objects (a torus, a sphere, a disk) with an optional brick normal map, drawn through the
// material system's environment techniques (factored, banks, env_mirror, env_glossy) under a procedural HDR
// environment baked into parabolic maps.

#include <hemi/gpu/device.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/math/brdf.h>
#include <hemi/render/material/environment_lighting.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_system.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace hemi::samples
{

// A torus about z: major radius R, minor r; u around z from +x (the tangent along it, w = -1: glTF's
// bitangent points towards decreasing v, down the outside of the tube), v around the tube.
io::Mesh make_torus(float major, float minor, uint32_t segments, uint32_t rings);
// A disk in the xy plane facing +z, radius r: u = angle / 2pi, v = radius; the tangent runs around the centre
// (the direction of brushing of a turned metal disk, what Banks' model needs).
io::Mesh make_disk(float radius, uint32_t segments, uint32_t rings);

// A procedural equirectangular HDR environment (z up, sh_environment.h's convention): a blue sky brightening
// to the horizon, a warm ground, coloured panels around the horizon (so that reflections show where they come
// from) and a small sun of radiance `sun` at azimuth 40 degrees, elevation 35 degrees.
io::ImageRgba studio_environment(uint32_t width, uint32_t height, float sun = 2000.0f);
// The sun's direction in studio_environment.
glm::vec3 studio_sun_direction();

// What one view draws: a mesh with a normal map (empty: flat), lit by an environment through one technique.
struct FactoredView
{
    const io::Mesh* mesh = nullptr;
    io::ImageRgba8 normal_map; // RGBA8, glTF convention; empty: a flat map
    float normal_scale = 1.0f;
    glm::vec3 albedo{0.8f};
    render::Technique technique = render::Technique::EnvMirror;
    const io::EnvmapAsset* environment = nullptr;
    // Reflection probes' maps blended in its place (EnvironmentMaps of several probes, one
    // EnvironmentMaterial::probes entry each); empty: `environment` alone.
    std::vector<io::EnvmapAsset> probes;
    render::MapPrecision precision = render::MapPrecision::Auto; // how the environment's maps are stored
    std::vector<math::BrdfTable> brdf; // the factored BRDF's tables (factored, banks)
    render::EnvironmentMaterial material;
    std::vector<render::DynamicLight> lights;
    float specular_exponent = 32.0f,
          specular_strength = 0.0f; // the lights' Blinn-Phong (env_mirror, env_glossy)
    glm::mat4 model{1.0f};
    glm::vec3 eye{0.0f, -3.5f, 1.2f}, target{0.0f};
    float fov_y_degrees = 40.0f;
};

// Renders the view at width x height (linear RGB, alpha 1 where drawn); `aux` receives (u, v, draw id, 1)
// where the mesh covers a pixel. Normal maps are sampled bilinearly from mip 0 (what the tests' CPU
// references do).
io::ImageRgba render_factored(const gpu::Device& device, const FactoredView& view, uint32_t width,
                              uint32_t height, io::ImageRgba* aux = nullptr);

} // namespace hemi::samples
