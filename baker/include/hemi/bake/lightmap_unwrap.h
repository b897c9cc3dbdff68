#pragma once
// Lightmap UVs for scenes that have none (hemi-bake lightmap --unwrap): planar charts, packed at one texel
// density. Triangles that share an edge (vertices welded by position, so seams of the other UV sets do not
// cut charts) join the chart of a seed triangle while their normal stays within `max_chart_angle` of the
// seed's and their projection onto the seed's plane overlaps none of the chart's (two faces of one plane
// modelled over each other, as shipped levels have them, or a surface folding back, go to charts of their
// own, so no two triangles share a texel); each chart is projected onto the seed's plane, turned so that its
// longest edge runs along u, and the charts' rectangles are packed on a skyline (bottom-left best fit,
// tallest first) with `padding` texels between them, so that conservative rasterisation never gives two
// charts one texel. A level of flat walls gets one chart per wall; a curved surface gets bands of at most
// `max_chart_angle` of curvature.
//
// What this is not: an optimising unwrapper (xatlas, UVAtlas: not packaged in Debian). Curved meshes get
// many small charts and so many seams; an artist's second UV map (Blender's Lightmap Pack, or a hand-made
// one) is better, and hemi-bake uses TEXCOORD_1 whenever the scene has it, unless --unwrap is given.

#include <hemi/io/mesh.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hemi::bake
{

struct UnwrapOptions
{
    float texel_size = 0.0f;        // world units per texel; 0: the largest that fits the atlas below
    uint32_t width = 0, height = 0; // the atlas; 0 x 0: from texel_size (about square, no wasted rows);
                                    // 0 x 0 and texel size 0: 512 x 512
    float max_chart_angle_degrees = 10.0f;
    uint32_t padding = 2; // texels between charts (and around the atlas's border)
};

struct UnwrapResult
{
    uint32_t width = 0, height = 0; // the atlas the charts are packed into
    float texel_size = 0.0f;        // world units per texel, the same for every chart
    size_t charts = 0;
    size_t vertices_added = 0;      // vertices split where charts meet
    std::vector<uint32_t> chart_of; // per triangle, its chart (~0u for a triangle of zero area)
};

// Rewrites mesh.uvs1 (and splits vertices shared by several charts, copying their other attributes; the
// triangle order, and so the primitives' index ranges, stay as they are). Throws std::invalid_argument for an
// inconsistent mesh (io::mesh_problem), bad options, or charts that do not fit the atlas at the given
// texel size (naming both).
UnwrapResult unwrap_lightmap(io::Mesh& mesh, const UnwrapOptions& options);

} // namespace hemi::bake
