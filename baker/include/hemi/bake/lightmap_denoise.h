#pragma once
// A chart-aware denoiser for baked lightmaps (hemi-bake lightmap --denoise): an edge-avoiding a-trous wavelet
// filter (Dammertz, Sewtz, Hanika and Lensch 2010) over the atlas's covered texels, with the non-local-means
// distance of Monte Carlo denoisers (Rousselle, Knaus and Zwicker 2012) in units of the bake's own noise, a
// first-order fit in place of the weighted mean, and each chart given back the light it was baked with.
//
// The noise: the bake estimates, per texel, the variance of each guide (LightmapSh::noise: each sample
// against its nearest in its stream's pattern). It runs above the actual error by a factor that depends on
// the light (1.4x in RMS on the sample level, 2.8x on a floor and wall under a sky and a sun: a stratified
// set's own samples cannot tell how well the set integrates), and sigma_light was chosen with it. The guides
// are the luminance of the irradiance at the normal (plain) and of SH9's three band-1 coefficients (the
// light's direction). A single texel's guides are single draws: they are prefiltered over its 3 x 3
// neighbours in its chart, weights (1, 2, 1) x (1, 2, 1) / 16, and their variance with the weights squared.
//
// Pass k (k = 0 .. iterations - 1) looks at the 5 x 5 texels 2^k apart in the atlas, weighted by the B3
// spline (1, 4, 6, 4, 1) / 16 along each axis times
//   - the chart: texels of another chart (triangles not joined in lightmap UV space) weigh 0;
//   - the geometry: 0 for a texel that is not where the chart's surface continues (further from the centre's
//     sample point than 1.5x the texel spacing times the texels' world size, plus one world size), else
//     exp(-|(p_j - p_i) . g_i| / (sigma_plane * world size)) (g_i the centre's geometric normal: a step out
//     of its plane), times max(0, n_i . n_j)^sigma_normal (a crease: the shading normals turn);
//   - the light: exp(-max(0, D)), D the mean over the four guides c of
//         ((g_jc - g_ic)^2 - (v_ic + min(v_ic, v_jc))) / (sigma_light^2 (v_ic + v_jc)),
//     v the guides' variances averaged over each texel's 3 x 3 neighbours: about 0 (weight 1) for a
//     neighbour whose light differs from the centre's by noise alone, growing with the square of a real
//     difference. Where the centre's variance of a guide is 0 (its samples agreed: in a sealed room, none
//     saw light), only texels with exactly its value of that guide weigh anything, so a sealed room stays 0.
// With those weights the texel fits v ~ b0 + b1 dx + b2 dy over the window (dx, dy its offsets; the slopes
// damped by a ridge of 1% of the total weight, so that a window without the spread to fit them gives the
// weighted mean) and takes b0 = sum l_j v_j: exact, but for the ridge's small pull, for light that changes
// linearly along the surface, also where the window is one-sided (a chart's border, beside a shadow), where a
// weighted mean would be pulled towards the side that has neighbours. Where the centre's noise is known, the
// light's term is then taken again against the guides' fitted planes rather than the centre's values, and the
// fit repeated: a neighbour off the plane by more than the noise (across an edge, or where the light curves)
// weighs less, one along the gradient does not. Every value of a texel (its SH9 irradiance, plain's and rnm's
// directly integrated values) and its guides go through the same l_j, the guides' variances through l_j^2.
// sum l_j = 1, so a constant stays constant (to rounding).
//
// Each chart keeps its light: a texel's weights sum to 1 but its neighbours' weights on it need not (a flat,
// dim region takes more from a bright feature than the feature takes back), which moves light from features
// into the regions around them (1-3% of a real level's under a bright sky). So at the end plain and rnm are
// kept >= 0 and each chart is scaled, per colour channel, until its plain sums to what the bake's did (the
// unbiased estimate of its light); every value of its texels by the same factor, a chart without light as it
// is. Texels inside geometry (LightmapSh::valid 0) are neither filtered nor used. Deterministic on any thread
// count (every texel reads only the previous pass).
#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/mesh.h>

#include <cstddef>

namespace hemi::bake
{

struct LightmapDenoiseOptions
{
    int iterations = 3;          // a-trous passes: a reach of 2 (2^iterations - 1) texels
    float sigma_light = 1.25f;   // how far past its noise a neighbour's light may differ (the distance's k)
    float sigma_normal = 128.0f; // exponent on the shading normals' cosine
    float sigma_plane = 1.0f;    // distance off the centre's plane, in the centre texel's world sizes
    // A bake in tiles (LightmapSh::tiles) is filtered in bands of atlas rows, each read from the tile file
    // with the rows its result depends on around it (1 + 2 (2^iterations - 1) + iterations above and below)
    // and written to the file's other copy: at most this many texels a band with those rows (but at least
    // one row), 0 for 2^20. The same bytes as the whole atlas filtered in memory.
    size_t tile_texels = 0;
};

struct LightmapDenoiseReport
{
    size_t texels = 0; // texels filtered
    size_t charts = 0; // charts of the atlas (connected in lightmap UV space)
};

// Denoises `sh` (from bake_lightmap_sh on this mesh and atlas, with LightmapBakeOptions::keep_noise) in
// place, and releases its noise estimate; a bake in tiles in its tile file, in bands
// (LightmapDenoiseOptions::tile_texels), whose other copy then holds the result (LightmapSh::tiles_copy).
// Throws
// std::invalid_argument when `sh` lacks the noise estimate or the directly integrated values, or its sizes do
// not match the atlas, or for options out of range (iterations in [0, 10], sigmas > 0).
LightmapDenoiseReport denoise_lightmap(const io::Mesh& mesh, const LightmapAtlas& atlas, LightmapSh& sh,
                                       const LightmapDenoiseOptions& options = {});

// The chart of every triangle of `mesh`: triangles that share a vertex in lightmap UV space (the same
// position and the same TEXCOORD_1, bit for bit) are one chart. Charts are numbered 0, 1, ... in the order of
// their first triangle. Returns the number of charts in `count` when given.
std::vector<uint32_t> lightmap_charts(const io::Mesh& mesh, size_t* count = nullptr);

} // namespace hemi::bake
