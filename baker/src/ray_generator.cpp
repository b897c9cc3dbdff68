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

namespace
{

// uniform01's two halves: the hash of (seed, a), and the number drawn from it for b.
uint64_t item_hash(uint64_t seed, uint64_t a)
{
    return mix64(mix64(seed) ^ a);
}
float draw(uint64_t item, uint64_t b)
{
    // The top 24 bits: every value is a float, and 1.0 cannot come out.
    return float(mix64(item ^ (b * 0x632be59bd9b4e019ull)) >> 40) * (1.0f / 16777216.0f);
}

} // namespace

float uniform01(uint64_t seed, uint64_t a, uint64_t b)
{
    return draw(item_hash(seed, a), b);
}

namespace
{

// Direction at height z, in the golden-angle spiral whose rotation is `offset` (an item's uniform01(.., 0)).
glm::vec3 spiral(float offset, int ray, float z)
{
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
    return spiral(uniform01(seed, item, 0), ray, z);
}

glm::vec3 hemisphere_direction(uint64_t seed, uint64_t item, int ray, int rays)
{
    const float z = 1.0f - (float(ray) + uniform01(seed, item, uint64_t(ray) + 1)) / float(rays);
    return spiral(uniform01(seed, item, 0), ray, z);
}

void sphere_directions(uint64_t seed, uint64_t item, std::span<glm::vec3> out)
{
    const uint64_t h = item_hash(seed, item);
    const float offset = draw(h, 0), rays = float(out.size());
    for (size_t r = 0; r < out.size(); ++r)
        out[r] = spiral(offset, int(r), 1.0f - 2.0f * (float(int(r)) + draw(h, uint64_t(r) + 1)) / rays);
}

void hemisphere_directions(uint64_t seed, uint64_t item, std::span<glm::vec3> out)
{
    const uint64_t h = item_hash(seed, item);
    const float offset = draw(h, 0), rays = float(out.size());
    for (size_t r = 0; r < out.size(); ++r)
        out[r] = spiral(offset, int(r), 1.0f - (float(int(r)) + draw(h, uint64_t(r) + 1)) / rays);
}

} // namespace hemi::bake
