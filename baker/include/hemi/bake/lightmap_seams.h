#pragma once
// Lightmap seams: edges where a surface continues in 3D from one lightmap chart into another. On each side
// the runtime's bilinear lookup reads its own chart's texels, so whatever the two texel rows baked shows as a
// step across the edge. find_lightmap_seams finds them and measure_lightmap_seams says how large the step is
// (what hemi-bake lightmap reports in its JSON); stitching them is the next step (not built yet).

#include <hemi/io/block_maps.h>
#include <hemi/io/mesh.h>

#include <glm/vec2.hpp>

#include <cstddef>
#include <span>
#include <vector>

namespace hemi::bake
{

// One seam edge: the lightmap UVs (TEXCOORD_1) of its two ends on side a and on side b; a0 and b0 are the
// same point in 3D, and so are a1 and b1.
struct LightmapSeam
{
    glm::vec2 a0, a1, b0, b1;
};

// Every edge two triangles share in 3D (the same positions at both ends, bit for bit, as exporters write the
// vertices they split at a UV seam) with lightmap UVs that differ on the two sides, where the surface is
// continuous: the vertex normals at each end agree within `crease_degrees` (a crease keeps its step). An edge
// of three or more triangles is no seam. Deterministic: in the order of the first triangle's edges.
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

} // namespace hemi::bake
