#pragma once
// A baked lightmap level as a glTF 2.0 file (hemi-bake export): the level's mesh, materials and images as
// io::write_gltf writes a scene, with its lightmaps for engines and viewers that do not link hemi. The layout
// and the loaders (three.js, Blender) are in docs/gltf_export.md.
//
// - The plain lightmap (the irradiance at the surface normal, E, per texel of the TEXCOORD_1 atlas) as one
//   RGBM-encoded PNG, which every material names in its extras:
//       "extras": {"lightmap": {"index": T, "texCoord": 1, "encoding": "RGBM", "range": R}}
//   T is a glTF texture (linear filtering, no mipmaps, clamped). The PNG's bytes are data, not sRGB colour:
//   E = rgb / 255 * a / 255 * R per channel. What the encoding keeps (encode_rgbm): every channel within
//   (m + R / 255) / 510 of the baked value, m the texel's brightest channel; that is 0.2% of m plus
//   R / 130050. Values above R are clipped to it (the default R is the brightest texel, so none are).
// - Every output the asset holds ("plain", "rnm" and the directional bases) at the asset's own precision,
//   under the root extension HEMI_lightmaps (in extensionsUsed, not extensionsRequired: a loader that does
//   not know it loses nothing else):
//       "HEMI_lightmaps": {"width": W, "height": H, "texCoord": 1, "rays": N, "bounces": B,
//                          "rgbm": {"index": T, "range": R},
//                          "outputs": [{"name": "sh9", "coefficients": K, "format": "RGB16F",
//                                       "scale": S, "bufferView": V}, ...],
//                          "probes": {"count": [NX, NY, NZ], "min": [x, y, z], "max": [x, y, z],
//                                     "irradiance": V1, "valid": V2, "points": V3,
//                                     "depth": {"resolution": R, "maxDistance": D, "bufferView": V4}},
//                          "shadowmask": {"index": T2, "texCoord": 1},
//                          "lights": [{"name": "sun", "type": "directional", "mode": "mixed",
//                                      "shadowmaskChannel": 0, "color": [r, g, b], "intensity": I,
//                                      "direction": [x, y, z], "angularDiameter": D}, ...],
//                          "reflectionProbes": [{"centre": [x, y, z], "boxMin": [x, y, z],
//                                                "boxMax": [x, y, z], "mirror": M, "glossy": [M, ...],
//                                                "diffuse": M}, ...]}
//   ("outputs" is absent when none is stored.) Buffer view V holds K maps one after the other, each H rows
//   from the top (v = 0) of W texels of three IEEE binary16 values (R, G, B), little-endian: the .hemi
//   asset's half floats, dense over the atlas (texels the scene does not cover are 0); a value is its half
//   times S, a power of two (io/half_scale.h: 1 unless the light's magnitude needs another). The coefficients
//   are the asset's (io/lightmap_asset.h): irradiance in each texel's TEXCOORD_0 tangent frame (the glTF's
//   TANGENT attribute), so that sum_k c_k b_k(n) at the normal-map normal n is E(n). Probes (when the asset
//   has them) as io::LightProbes: V1 holds NX * NY * NZ probes of 9 x 3 float32 (coefficient j, channel c at
//   j * 3 + c), x fastest; V2 one byte per probe (1 valid, 0 inside geometry); scattered probes (count N, 1,
//   1) have "points", V3: per probe float32 x, y, z and its reach (LightProbes::points); V4 the probes' depth
//   maps, per probe R x R texels of 2 float32 (mean distance, deviation; LightProbes::depth). The scene's
//   frame is the glTF's own (hemi reads glTF's y-up space into its z-up world; the probe grid is in the
//   glTF's frame). With mixed lights (hemi-bake lightmap's bake modes), "shadowmask" is texture T2, an RGBA8
//   PNG of the atlas (data, not sRGB colour; the lightmap's sampler): channel c / 255 is the share of the
//   direct light of the mixed light of channel c that reaches the texel, the asset's bytes. "lights" lists
//   every light the bake was given in the glTF's frame (io::LightmapLight): "mode" baked, mixed or realtime,
//   a mixed light's "shadowmaskChannel" (0-3: R, G, B, A), glTF's colour, intensity, range and cone angles,
//   "position" for point and spot lights, "direction" (where the light points) for directional and spot
//   lights, and the sun's "angularDiameter" in degrees. "reflectionProbes" (when the asset has them,
//   io::ReflectionProbe) each give the probe's centre and influence box in the glTF's frame and its maps:
//   each M is {"size": N, "extent": E, "bufferView": V} ("glossy" maps also "exponent": the Phong exponent),
//   V holding Heidrich & Seidel's two parabolic halves (math::ParabolicImage, math/paraboloid.h), the
//   directions in the glTF's frame: half 0 the directions with z >= 0, then half 1 those with z < 0, each N
//   rows from the top (y up the image) of N texels of float32 R, G, B; direction d is at (x, y) = (d.x,
//   d.y) / (1 + |d.z|) of its half, which covers [-E, E]^2. "mirror" is the mirror map's level 0 (radiance),
//   "glossy" the Phong-prefiltered maps, "diffuse" the irradiance / pi map.
#include <hemi/io/lightmap_asset.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hemi::io
{

struct LightmapGltfOptions
{
    // The outputs stored under HEMI_lightmaps, in this order; empty: every output of the asset. The RGBM
    // lightmap is always written (from "plain", which the asset must hold).
    std::vector<std::string> outputs;
    bool all_outputs = true; // false with `outputs` empty: none under HEMI_lightmaps (the RGBM lightmap only)
    float rgbm_range = 0.0f; // R; 0: the brightest channel of the plain lightmap (1 when it is all black)
};

struct LightmapGltfSummary
{
    float rgbm_range = 0.0f;
    uint64_t clipped_texels = 0;      // plain texels with a channel above R (or below 0), clipped
    uint64_t bytes = 0;               // of the binary buffer
    std::vector<std::string> outputs; // stored under HEMI_lightmaps
};

// RGBM as written (8 bits each; a = 0 only for black): a = ceil(m / R * 255) with m the brightest channel
// (clamped to [0, R]), rgb = round(value / (a / 255 * R) * 255).
std::array<uint8_t, 4> encode_rgbm(glm::vec3 value, float range);

// Writes `asset` to `path` (.glb, or .gltf with its buffer embedded), atomically. Throws
// std::invalid_argument when the asset has no "plain" output, an output named in options.outputs is not in
// the asset, the range is not finite and positive, or the binary buffer (outputs, mesh, images, probes)
// would exceed 4 GiB (the message says how large; fewer outputs fit); FormatError when the file cannot be
// written.
LightmapGltfSummary write_lightmap_gltf(const std::filesystem::path& path, const LightmapAsset& asset,
                                        const LightmapGltfOptions& options = {});

} // namespace hemi::io
