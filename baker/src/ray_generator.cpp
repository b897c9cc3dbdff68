#include <hemi/bake/ray_generator.h>

#include <algorithm>
#include <cmath>

namespace hemi::bake
{

uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

float uniform01(uint64_t seed, uint64_t a, uint64_t b)
{
    // The top 24 bits: every value is a float, and 1.0 cannot come out.
    return float(mix64(mix64(mix64(seed) ^ a) ^ (b * 0x632be59bd9b4e019ull)) >> 40) * (1.0f / 16777216.0f);
}

namespace
{

// Direction at height z, in the golden-angle spiral of `item`'s set (its rotation: uniform01(.., 0)).
glm::vec3 spiral(uint64_t seed, uint64_t item, int ray, float z)
{
    const float offset = uniform01(seed, item, 0);
    float frac = float(ray) * 0.6180339887f + offset;
    frac -= std::floor(frac);
    const float phi = 2.0f * float(M_PI) * frac, s = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

} // namespace

glm::vec3 sphere_direction(uint64_t seed, uint64_t item, int ray, int rays)
{
    // z uniform in [-1, 1] (Archimedes: uniform in z is uniform in area), one ray per stratum of height 2/R.
    const float z = 1.0f - 2.0f * (float(ray) + uniform01(seed, item, uint64_t(ray) + 1)) / float(rays);
    return spiral(seed, item, ray, z);
}

glm::vec3 hemisphere_direction(uint64_t seed, uint64_t item, int ray, int rays)
{
    const float z = 1.0f - (float(ray) + uniform01(seed, item, uint64_t(ray) + 1)) / float(rays);
    return spiral(seed, item, ray, z);
}

} // namespace hemi::bake
