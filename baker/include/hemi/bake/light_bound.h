#pragma once
// How bright a bake's light can be, known before the bake: an upper bound on the direct irradiance the
// lights give any point of the scene at any normal. hemi-bake lightmap reports it ("irradiance_bound" in
// the JSON) and refuses light beyond any physical value (kMaxPlausibleIrradiance) before the work, naming
// the light; storage sets no limit below that (the asset's half floats carry a scale, io/half_scale.h).

#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <string>
#include <vector>

namespace hemi::bake
{

// 10^10 (W/m^2, or lux for glTF's photometric lights): 10^5 times direct sunlight at noon. Light beyond it is
// a mistake of units or a typo, not a scene.
inline constexpr double kMaxPlausibleIrradiance = 1e10;

struct LightBoundSource
{
    std::string name;  // for messages: "the sun (--sun)", "the environment image sky.exr (...)", ...
    double irradiance; // the most this light gives a point (brightest channel)
};

struct LightBound
{
    // Each light's own bound, in the order: the sun, glTF lights (directional, point, spot), the
    // environment, emissive materials.
    std::vector<LightBoundSource> sources;
    // Their sum: an upper bound on the direct irradiance at any point and normal of the scene (every light
    // at its most at once).
    double total = 0.0;
    const LightBoundSource* largest() const;
};

// The bound of each light:
// - the sun and glTF directional lights: their irradiance (on a surface facing them);
// - a point or spot light: its intensity / d^2 at the distance d from its position to the nearest triangle
//   of `mesh` (the most it gives any surface; a spot's cone and a range window only lower it, the window is
//   applied at d);
// - the environment: the largest irradiance it gives any normal, max_n sum_pixels L omega max(0, n . w)
//   (each channel): the image summed into at most 128 x 64 cells of exact solid angle, each cell's cosine
//   bounded over the cell's angular radius, over 4096 normals with their covering radius added, so it is an
//   upper bound, within 15% of the exact value (pi L for a uniform sky of radiance L; an image smaller than
//   128 x 64 is split into parts of exact solid angle first);
// - an emissive material: pi times its emissive factor (a hemisphere of it; its texture is at most 1).
// `lights` must have passed check_lights (finite, non-negative).
LightBound lightmap_light_bound(const LightmapLights& lights, const std::vector<io::Material>& materials,
                                const io::Mesh& mesh);

} // namespace hemi::bake
