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

} // namespace hemi::math
