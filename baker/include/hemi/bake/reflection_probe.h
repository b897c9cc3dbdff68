#pragma once
// Reflection probes (issue 44): what a point of a lit level sees in every direction, as Heidrich & Seidel's
// parabolic maps (io::EnvmapAsset: the mirror map's mip chain, glossy maps prefiltered for Phong exponents,
// the diffuse map), the way an engine's reflection probe stores it. The radiance comes from the finished
// lightmap, as the light probes' does: a ray that lands on the front of a surface carries its emission plus
// its albedo / pi times the lightmap's irradiance there (the mixed lights' direct light included), the back
// of a single-sided surface nothing, and a ray that escapes the environment; a baked sun adds its disc where
// the point sees it. hemi's prefiltering (bake_envmap) makes the glossy and diffuse maps.

#include <hemi/bake/factored.h>
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/image.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace hemi::bake
{

// ReflectionProbeOptions and ReflectionProbePlacement are in lightmap_bake.h (LightmapFileOptions holds
// them).

// The reflection probe at `position` (the mesh's space) of the level `mesh` lit by `sh` (its finished
// lightmap, bake_lightmap_sh) under `lights`. `radiance`, when given, receives the equirectangular image the
// maps were made from. Throws std::invalid_argument for bad options, a position that is not finite, or a
// lightmap that does not match its atlas.
io::EnvmapAsset bake_reflection_probe(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                                      const LightmapLights& lights, const LightmapSurfaces* surfaces,
                                      const glm::vec3& position, const ReflectionProbeOptions& options,
                                      io::ImageRgba* radiance = nullptr);

} // namespace hemi::bake
