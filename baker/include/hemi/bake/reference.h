#pragma once
// The ground truth that lightmaps are measured against (hemi-bake reference): a path-traced image of a scene
// under the same lights as the lightmap bake (LightmapLights), framed exactly like hemi-render's view of the
// scene's asset (math/camera.h: the same camera, placement and pixel centres).
//
// What a pixel shows is what the lightmap techniques approximate, without the lightmap: at the surface seen
// through the pixel, the irradiance E(n') at the normal-map normal n' (the material's normal texture in the
// tangent frame of TEXCOORD_0, built like the material system's shader: T orthogonalised against the
// interpolated normal N, B = cross(N, T) w), from the radiance over the hemisphere of N (below the surface's
// own plane it is dark, as in the bake), and the colour albedo E / pi + emission (white: E / pi alone, the
// lighting-only view of hemi-render --white). The light is the environment (uniform, gathered by cosine-
// weighted rays about n'; an image, importance-sampled by luminance), the sun's disc, the punctual lights
// and emissive surfaces, and with bounces the light reflected by the surfaces' albedo up to `bounces` times
// (at a bounce the surface's interpolated normal, which is what a lightmap texel stores). Back faces of
// single-sided materials are not seen (the rasteriser culls them) and carry no light.
//
// With `roughness` > 0 each path also carries the GGX coat's specular (ReferenceOptions).
//
// Each pixel averages `rays` paths through points jittered over its square (so the normal map is box-
// filtered, where the rasteriser filters it with mipmaps). The even and the odd paths are two independent
// stratified sets, and the noise of the pixel's mean is estimated from the difference of their means.
// Counter-based random numbers: the same seed gives the same bytes on any thread count.

#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/math/camera.h>

#include <glm/mat4x4.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>

namespace hemi::bake
{

struct ReferenceOptions
{
    uint32_t width = 800, height = 600;
    bool auto_camera = true;                 // math::auto_camera of the mesh under `model`, as hemi-render
    math::Camera camera;                     // used when !auto_camera (world space, z up)
    glm::mat4 model = math::gltf_to_world(); // the mesh's placement in the world (a rigid transform)
    int rays = 256;                          // paths per pixel
    int bounces = 0;    // surface reflections per path (0: direct light and emission only)
    bool white = false; // E / pi without albedo or emission
    uint64_t seed = 1;
    float ray_offset = 1e-4f; // of the scene's diagonal, as the lightmap bake's
    // A GGX coat over every surface (math/ggx.h; what hemi-render --roughness draws): glTF's roughness in
    // [0.03, 1] (0: none) and f0 in [0, 1]. Its specular at the normal-map normal, from the hemisphere of the
    // surface normal: the sun's disc and the punctual lights sampled as lights, the environment and the
    // surfaces (their emission, and with bounces their diffuse light) along directions drawn from the GGX
    // lobe. Added to the diffuse colour (and to E / pi with `white`).
    double roughness = 0.0;
    double f0 = 0.04;
};

struct ReferenceImage
{
    io::ImageRgba image; // linear RGB; alpha = coverage (the fraction of the pixel's paths that hit the
                         // scene), colour not premultiplied (the mean over the paths that hit)
    math::Camera camera; // the camera it was framed with
    double noise = 0.0;  // RMS over fully covered pixels and channels of the estimated standard error of a
                         // pixel's mean (from its even and odd paths)
    uint64_t rays = 0;
    double seconds = 0.0;
};

// Throws std::invalid_argument for bad options (sizes, rays, bounces, a camera that is not finite or whose
// eye is its target) or lights, and for a mesh without normals, tangents and UVs.
ReferenceImage render_reference(const io::Mesh& mesh, const LightmapSurfaces& surfaces,
                                const LightmapLights& lights, const ReferenceOptions& options,
                                const std::function<void(uint32_t rows_done, uint32_t rows)>& progress = {});

// hemi-bake reference's job: read the glTF scene (lights in hemi's z-up world, the scene placed there by
// math::gltf_to_world(), its punctual lights added, as bake_lightmap_file does) and write the image as a
// linear RGBA EXR (io::write_exr, atomic; checked writable before the render). Throws io::FormatError naming
// the file and the problem.
ReferenceImage
render_reference_file(const std::filesystem::path& scene, const std::filesystem::path& exr,
                      LightmapLights lights, const ReferenceOptions& options,
                      const std::function<void(uint32_t rows_done, uint32_t rows)>& progress = {});

} // namespace hemi::bake
