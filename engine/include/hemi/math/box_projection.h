#pragma once
// Box-projected (parallax-corrected) reflection probes (Lagarde & Zanuttini 2012, "Local Image-based
// Lighting With Parallax-corrected Cubemap"): a probe captured at point c sees the room from c; a reflection
// from another point p along r should see what r meets. Taking the room as the probe's influence box, the
// ray from p along r leaves the box at q, and the probe is looked up towards q - c. Exact for a point inside
// a box-shaped room whose walls are the box; an approximation elsewhere. The GLSL twin is
// hemi_box_projected_direction (hemi/lib/environment.glsl).

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace hemi::math
{

// The direction (unit) to look the probe captured at `centre` up in, for a reflection from `p` along `r`
// (unit), with the influence box [box_min, box_max] (p inside it); all in the probe's frame.
inline glm::vec3 box_projected_direction(const glm::vec3& p, const glm::vec3& r, const glm::vec3& box_min,
                                         const glm::vec3& box_max, const glm::vec3& centre)
{
    float t = 3.4e38f;
    for (int a = 0; a < 3; ++a)
        if (r[a] != 0.0f)
            t = glm::min(t, ((r[a] > 0.0f ? box_max[a] : box_min[a]) - p[a]) / r[a]);
    return glm::normalize(p + glm::max(t, 0.0f) * r - centre);
}

// How much a reflection probe whose influence box is [box_min, box_max] counts at p: 1 deeper than `fade`
// inside every face, falling linearly to 0 at the box's faces, 0 outside (with fade 0: 1 inside, 0
// outside). An engine blends the probes that overlap p by these weights (divided by their sum; the sky, or
// a wider probe, where they sum to 0), so that light changes continuously as p moves from one room into the
// next. The GLSL twin is hemi_box_influence.
inline float box_influence(const glm::vec3& p, const glm::vec3& box_min, const glm::vec3& box_max, float fade)
{
    const glm::vec3 inside = glm::min(p - box_min, box_max - p);
    const float depth = glm::min(inside.x, glm::min(inside.y, inside.z));
    if (!(fade > 0.0f))
        return depth >= 0.0f ? 1.0f : 0.0f;
    return glm::clamp(depth / fade, 0.0f, 1.0f);
}

} // namespace hemi::math
