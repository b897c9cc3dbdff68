#pragma once
// A chart-aware denoiser for baked lightmaps (hemi-bake lightmap --denoise): an edge-avoiding a-trous wavelet
// filter (Dammertz, Sewtz, Hanika and Lensch 2010) over the atlas's covered texels, with edge-stopping
// functions in the manner of SVGF (Schied et al. 2017), cross-filtering the two halves of the bake's
// samples (LightmapSh::half; the dual buffers of Rousselle, Manzi and Zwicker 2013), and a first-order fit
// in place of the weighted mean.
//
// Why two halves: a weight taken from the same noise as the value it weighs is biased wherever the noise is
// skewed (an importance-sampled sky through a window: most samples dim, a few bright). It keeps a dim texel
// from its brighter neighbours and lets a bright one take its dimmer ones, and the mean darkens (a
// single-buffer version of this filter lost 4% of a real level's light). Here half A is filtered with
// weights computed from half B and B with weights from A, and the result is A + B.
//
// Pass k (k = 0 .. iterations - 1) looks at the 5 x 5 texels 2^k apart in the atlas, weighted by the B3
// spline (1, 4, 6, 4, 1) / 16 along each axis times
//   - the chart: texels of another chart (triangles not joined in lightmap UV space) weigh 0;
//   - the geometry: 0 for a texel that is not where the chart's surface continues (further from the centre's
//     sample point than 1.5x the texel spacing times the texels' world size, plus one world size), else
//     exp(-|(p_j - p_i) . g_i| / (sigma_plane * world size)) (g_i the centre's geometric normal: a step out
//     of its plane), times max(0, n_i . n_j)^sigma_normal (a crease: the shading normals turn);
//   - the light: exp(-max_c |g_jc - g_ic| / (sigma_luminance * sd_ijc)) over four guides c of the weighing
//     half, the luminance of the irradiance at the normal and of SH9's three band-1 coefficients (the
//     light's direction); sd_ijc^2 is the mean of the two texels' variances of that guide, each averaged
//     over its 3 x 3 neighbours in the chart (one texel's estimate is a single draw: (A - B)^2 / 2 to begin
//     with, then what the previous passes left of it, sum l_j^2 v_j). Where the weighing half's variance of
//     a guide is 0 at the centre (its halves agreed, like all of a sealed room's: no light), only texels with
//     exactly its value of that guide in the weighing half weigh anything: where every texel in reach saw no
//     light in either half (a sealed room), the result is exactly 0. (A texel black only by chance, where the
//     light is dim, must still take its neighbours' light: requiring them black in both halves kept 16% of a
//     dim level's light out.)
// With those weights the texel fits v ~ b0 + b1 dx + b2 dy over the window (dx, dy its offsets; the slopes
// damped by a ridge of 1% of the total weight, so that a window without the spread to fit them gives the
// weighted mean) and takes b0 = sum l_j v_j: exact, but for the ridge's small pull, for light that changes
// linearly along the surface, also where the window is one-sided (a chart's border, beside a shadow), where a
// weighted mean would be pulled towards the side that has neighbours. Where the centre's noise is known, the
// light's term is then taken again against the guides' fitted planes rather than the centre's values, and the
// fit repeated: a neighbour off the plane by more than the noise (across an edge, or where the light curves)
// weighs less, one along the gradient does not. sum l_j = 1, so a constant stays constant (to rounding).
// Every value of a texel (its SH9 irradiance, and plain's and rnm's directly integrated values) goes through
// the same l_j, so the outputs stay consistent with each other; plain's and rnm's are kept >= 0. Texels
// inside geometry (LightmapSh::valid 0) are neither filtered nor used. Deterministic on any thread count
// (every texel reads only the previous pass).
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/mesh.h>

#include <cstddef>

namespace hemi::bake
{

struct LightmapDenoiseOptions
{
    int iterations = 3;           // a-trous passes: a reach of 2 (2^iterations - 1) texels
    float sigma_luminance = 1.0f; // standard deviations of noise a neighbour's guides may differ by
    float sigma_normal = 128.0f;  // exponent on the shading normals' cosine
    float sigma_plane = 1.0f;     // distance off the centre's plane, in the centre texel's world sizes
};

struct LightmapDenoiseReport
{
    size_t texels = 0; // texels filtered
    size_t charts = 0; // charts of the atlas (connected in lightmap UV space)
};

// Denoises `sh` (from bake_lightmap_sh on this mesh and atlas, with LightmapBakeOptions::keep_halves) in
// place (its halves too). Throws
// std::invalid_argument when `sh` lacks the halves or the directly integrated values, or its sizes do not
// match the atlas, or for options out of range (iterations in [0, 10], sigmas > 0).
LightmapDenoiseReport denoise_lightmap(const io::Mesh& mesh, const LightmapAtlas& atlas, LightmapSh& sh,
                                       const LightmapDenoiseOptions& options = {});

// The chart of every triangle of `mesh`: triangles that share a vertex in lightmap UV space (the same
// position and the same TEXCOORD_1, bit for bit) are one chart. Charts are numbered 0, 1, ... in the order of
// their first triangle. Returns the number of charts in `count` when given.
std::vector<uint32_t> lightmap_charts(const io::Mesh& mesh, size_t* count = nullptr);

} // namespace hemi::bake
