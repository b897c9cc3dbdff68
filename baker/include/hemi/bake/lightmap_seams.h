#pragma once
// Lightmap seams: edges where a surface continues in 3D from one lightmap chart into another. On each side
// the runtime's bilinear lookup reads its own chart's texels, so whatever the two texel rows baked shows as a
// step across the edge. find_lightmap_seams finds them and measure_lightmap_seams says how large the step is
// (what hemi-bake lightmap reports in its JSON) and LightmapSeamStitch changes the texels along them, in
// least squares, until both sides' lookups agree.

#include <hemi/io/block_maps.h>
#include <hemi/io/mesh.h>

#include <glm/vec2.hpp>

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

namespace hemi::bake
{

// One seam edge: the lightmap UVs (TEXCOORD_1) of its two ends on side a and on side b; a0 and b0 are the
// same point in 3D, and so are a1 and b1.
struct LightmapSeam
{
    glm::vec2 a0, a1, b0, b1;
    // The two sides' tangent frames agree at both ends (the same handedness, and tangents within the crease
    // angle of each other in the surface's plane). Every output but plain holds its coefficients in the
    // texel's tangent frame, so only where the frames agree do equal coefficients mean equal light: the
    // directional outputs are measured and stitched along those seams only, plain along all.
    bool frames_agree = true;
};

// Every edge two triangles share in 3D (the same positions at both ends, bit for bit, as exporters write the
// vertices they split at a UV seam) with lightmap UVs that differ on the two sides, where the surface is
// continuous: the two triangles face the same side (not a sliver folded back over its neighbour, as a
// patch's tessellation leaves them) and the vertex normals at each end agree within `crease_degrees` (a
// crease keeps its step). An edge of three or more triangles is no seam. Deterministic: in the order of the
// first triangle's edges.
std::vector<LightmapSeam> find_lightmap_seams(const io::Mesh& mesh, float crease_degrees = 10.0f);

// How far the two sides of the seams disagree in `maps` (every coefficient, every channel): along each seam,
// at points a texel apart on the longer side (at least 2), the bilinear lookups on side a and side b (as the
// runtime's sampler reads them: io::BlockMaps::bilinear). `mean` and `p95` are the mean and 95th percentile
// of |a - b| over every point, coefficient and channel, relative to the mean of (|a| + |b|) / 2 over the
// same.
struct LightmapSeamMetric
{
    size_t seams = 0, points = 0;
    double mean = 0.0, p95 = 0.0;
};
LightmapSeamMetric measure_lightmap_seams(std::span<const LightmapSeam> seams, const io::BlockMaps& maps);

// The blocks of `grid` that a bilinear lookup at any point of the seams reads (each side's segment walked
// in steps of a quarter texel, each step's footprint widened by a texel): a grid over which
// measure_lightmap_seams and LightmapSeamStitch give what they give over `grid` itself, so that a bake in
// tiles measures and stitches its outputs over these blocks alone.
io::BlockGrid lightmap_seam_blocks(std::span<const LightmapSeam> seams, const io::BlockGrid& grid);

// Seam stitching (Sloan's least-squares seams; Liu, Ferguson, Jacobson and Gingold 2017, "Seamless"): the
// smallest change d of the texels along the seams that makes the two sides' bilinear lookups agree,
//     minimise  sum over seams of  integral over the edge of |L_a(x + d) - L_b(x + d)|^2  +  closeness |d|^2,
// where L_a and L_b are the runtime's bilinear lookups along side a and side b. Along an edge a lookup is a
// quadratic in the edge's parameter between the texel-grid lines either side crosses, so each piece's
// integral is exact with 3 Gauss-Legendre points; an edge's integral is scaled by its length in texels (the
// longer side's). The unknowns are the texels those lookups read (4 per point and side, clamped to the atlas
// as the sampler clamps it) that the grid stores; a texel it does not store reads 0 and stays 0. The system
// (S + closeness I) d = -S x is the same for every map, coefficient and channel, so it is factored once
// (sparse Cholesky, double precision) and solved for each: a constant or any field the seams already agree on
// is left exactly as it is (S x = 0), and a texel no seam reads is never touched. Linear in the values, so
// what is stitched is what the runtime interpolates (every output basis, every coefficient). Deterministic:
// no threads, assembly in the seams' order.
//
// `closeness` weighs keeping a texel's baked value against one texel of seam length agreeing: smaller
// stitches tighter and lets texels move further. With the default a step between two charts closes to about
// 1/100 of itself (the tests measure it).
class LightmapSeamStitch
{
  public:
    static constexpr double kDefaultCloseness = 0.01;

    // Throws std::invalid_argument for a closeness that is not positive.
    LightmapSeamStitch(std::span<const LightmapSeam> seams, const io::BlockGrid& grid,
                       double closeness = kDefaultCloseness);
    ~LightmapSeamStitch();
    LightmapSeamStitch(LightmapSeamStitch&&) noexcept;
    LightmapSeamStitch& operator=(LightmapSeamStitch&&) noexcept;

    // The slots (io::BlockGrid) of the texels the stitch may change, ascending.
    const std::vector<size_t>& slots() const;
    // Stitches every map and channel of `maps`, whose grid must be the one given above (else
    // std::invalid_argument).
    void apply(io::BlockMaps& maps) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace hemi::bake
