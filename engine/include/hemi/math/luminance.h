#pragma once
// Luminance of linear Rec. 709 / sRGB primaries (ITU-R BT.709): what the baker weighs light by where it needs
// one number for a colour (importance sampling, variance, the denoiser's edges).

#include <glm/vec3.hpp>

namespace hemi::math
{

inline double luminance(const glm::dvec3& c)
{
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}
inline float luminance(const glm::vec3& c)
{
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}

} // namespace hemi::math
