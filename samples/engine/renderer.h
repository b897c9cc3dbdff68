#pragma once
// The engine sample's renderer: its own render graph over hemi's data.
//
//   shadow map  (the sun's view; D32)          hemi's shadow pipelines for the level and the torus
//   (PassKind::
//                                              Shadow), the engine's own depth shader for its spheres
//   depth prepass (the camera; D32)            the same, PassKind::Depth
//   main pass   (HDR RGBA16F, depth LESS_OR_EQUAL against the prepass, no depth writes)
//                                              the engine's own shaders (shaders/main.*) over hemi's meshes,
//                                              textures, lightmaps, PRT coefficients and parabolic maps,
//                                              composed with hemi's GLSL library
//   post pass   (the swapchain image)          exposure and tonemap
//
// Two frames in flight: each has its own command buffer, fence, uniform block, shadow map, depth and HDR
// images, so a frame only ever waits for the one that used its slot two frames ago. hemi's per-frame work
// (the PRT transfer pass, the frame sets of its depth pipelines) records its own barriers.
#include "assets.h"
#include "context.h"

#include <hemi/gpu/device.h>

#include <hemi/math/camera.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <filesystem>
#include <memory>
#include <string>

namespace engine
{

struct Settings
{
    bool baked_only = false; // the level alone, lit by its lightmap only: what hemi-render draws
    int basis = 0;           // 0: H6 near, H4 far; 1: H6; 2: H4
    bool lighting_only = false;
    bool specular_only = false; // the coat's light alone: the lightmap's specular and the mixed sun's
    float exposure = 1.8f;
    bool tonemap = true;
    float fog = 0.02f;         // density per unit
    float lod_distance = 4.5f; // where H6 gives way to H4
    bool objects = true;
    // The level's mixed sun (when its bake made it mixed): lit at run time; its shadow map (the dynamic
    // objects' shadows) within shadow_distance of the eye, fading out over the last 1.5 units, beyond it the
    // static shadows alone (the shadowmask, the probes' occlusion).
    bool shadow_map = true;
    float shadow_distance = 8.0f;
    bool coat = true; // the polished floor's GGX coat: the lightmap's specular and the sun's
    // The camera (world space, z up; the field of view and the near and far planes are hemi-render's, from
    // the level's bounds): `--camera` of both tools takes the same EYE,TARGET.
    hemi::math::Camera camera{{-3.5f, 0.8f, 1.6f}, {3.0f, -0.6f, 0.9f}};
};

struct FrameState
{
    float env_time = 0.0f, object_time = 0.0f; // seconds of each animation
};

// A probe-lit sphere as the frame drew it: its centre on screen (pixels from the top left), its radius in
// pixels, whether it is in front of the eye, and what the level's probes give at its centre (the luminance
// of their SH9 constant term, and the share of the mixed sun that reaches it: its static shadow).
struct SphereSeen
{
    glm::vec2 centre{0.0f};
    float radius = 0.0f;
    bool in_front = false;
    float light = 0.0f, sun_share = 1.0f;
};

struct FrameStats
{
    uint32_t draws = 0, culled = 0; // main-pass draws of the level's list, and entries culled
    std::array<SphereSeen, 3> spheres;
};

class Renderer
{
  public:
    Renderer(Context& context, Swapchain& swapchain, const hemi::samples::EngineAssets& assets);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    // Records and presents one frame; writes the presented image to `screenshot` (PNG) when not empty.
    // Re-makes the swapchain when it is out of date or the window was resized.
    FrameStats frame(const Settings& settings, const FrameState& state,
                     const std::filesystem::path& screenshot);
    // Waits for every frame in flight.
    void finish();

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace engine
