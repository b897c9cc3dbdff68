#include <hemi/bake/ray_generator.h>

#include <glm/vec2.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

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

// The golden-angle spiral's angle of ray r of an item is 2 pi (r g + offset), g the golden ratio's
// conjugate and `offset` the item's uniform01(.., 0). Its cosine and sine are the ray's own turn, 2 pi
// frac(r g) (the same for every item, in double), rotated by the item's 2 pi offset: one sine and cosine per
// item and a table per set size instead of one per ray (they were a tenth of a lightmap bake), and the same
// values for one ray as for the whole set.
constexpr double kGolden = 0.6180339887498949;
glm::vec2 ray_turn(int ray)
{
    double f = double(ray) * kGolden;
    f -= std::floor(f);
    return {float(std::cos(2.0 * M_PI * f)), float(std::sin(2.0 * M_PI * f))};
}
glm::vec2 item_turn(float offset)
{
    return {float(std::cos(2.0 * M_PI * double(offset))), float(std::sin(2.0 * M_PI * double(offset)))};
}
// The rays' turns of a set of `rays`, kept per thread for the last four sizes asked (a lightmap bake asks
// for its own ray count and for TexelOrigins' 128 and 64), the oldest replaced first.
const std::vector<glm::vec2>& ray_turns(size_t rays)
{
    thread_local std::array<std::vector<glm::vec2>, 4> tables;
    thread_local size_t next = 0;
    for (const std::vector<glm::vec2>& t : tables)
        if (t.size() == rays)
            return t;
    std::vector<glm::vec2>& turns = tables[next];
    next = (next + 1) % tables.size();
    turns.resize(rays);
    for (size_t r = 0; r < rays; ++r)
        turns[r] = ray_turn(int(r));
    return turns;
}

// Direction at height z, at the angle whose cosine and sine are `ray` turned by `item`.
glm::vec3 spiral(glm::vec2 item, glm::vec2 ray, float z)
{
    const float c = ray.x * item.x - ray.y * item.y, s = ray.y * item.x + ray.x * item.y;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return {r * c, r * s, z};
}

} // namespace

glm::vec3 sphere_direction(uint64_t seed, uint64_t item, int ray, int rays)
{
    // z uniform in [-1, 1] (Archimedes: uniform in z is uniform in area), one ray per stratum of height 2/R.
    const float z = 1.0f - 2.0f * (float(ray) + uniform01(seed, item, uint64_t(ray) + 1)) / float(rays);
    return spiral(item_turn(uniform01(seed, item, 0)), ray_turn(ray), z);
}

glm::vec3 hemisphere_direction(uint64_t seed, uint64_t item, int ray, int rays)
{
    const float z = 1.0f - (float(ray) + uniform01(seed, item, uint64_t(ray) + 1)) / float(rays);
    return spiral(item_turn(uniform01(seed, item, 0)), ray_turn(ray), z);
}

void sphere_directions(uint64_t seed, uint64_t item, std::span<glm::vec3> out)
{
    const uint64_t h = item_hash(seed, item);
    const glm::vec2 turn = item_turn(draw(h, 0));
    const std::vector<glm::vec2>& turns = ray_turns(out.size());
    const float rays = float(out.size());
    for (size_t r = 0; r < out.size(); ++r)
        out[r] = spiral(turn, turns[r], 1.0f - 2.0f * (float(int(r)) + draw(h, uint64_t(r) + 1)) / rays);
}

void hemisphere_directions(uint64_t seed, uint64_t item, std::span<glm::vec3> out)
{
    const uint64_t h = item_hash(seed, item);
    const glm::vec2 turn = item_turn(draw(h, 0));
    const std::vector<glm::vec2>& turns = ray_turns(out.size());
    const float rays = float(out.size());
    for (size_t r = 0; r < out.size(); ++r)
        out[r] = spiral(turn, turns[r], 1.0f - (float(int(r)) + draw(h, uint64_t(r) + 1)) / rays);
}

namespace
{
// Every other sample as a neighbour (too few samples for k of them): as if independent.
SampleNeighbours all_others(int count)
{
    SampleNeighbours n;
    n.count = count;
    n.k = std::max(count - 1, 0);
    n.independent = true;
    return n;
}
} // namespace

namespace
{
// The k nearest of each of `count` samples by `distance2(r, q)` (squared), searched outwards in index: two
// samples d apart in index (on a ring of indices with `ring`, else on a line) are at least d / count apart,
// so once that exceeds the k-th nearest found, none further can be nearer. About count^1.5 distances.
template <class Distance2> SampleNeighbours nearest(int count, int k, bool ring, Distance2&& distance2)
{
    SampleNeighbours n;
    n.count = count;
    n.k = k;
    n.index.resize(size_t(count) * size_t(k));
    const int reach = ring ? count / 2 : count - 1;
    // Each sample's on its own: the same table on any number of threads.
    tbb::parallel_for(
        tbb::blocked_range<int>(0, count, 256),
        [&](const tbb::blocked_range<int>& samples)
        {
            // The k nearest so far, nearest first (ties by index).
            std::vector<std::pair<double, uint32_t>> best;
            for (int r = samples.begin(); r != samples.end(); ++r)
            {
                best.clear();
                for (int d = 1; d <= reach; ++d)
                {
                    const double gap = double(d) / double(count) - 1e-9;
                    if (int(best.size()) == k && gap > 0.0 && gap * gap > best.back().first)
                        break;
                    for (const int sign : {-1, 1})
                    {
                        if (ring && 2 * d == count && sign < 0)
                            continue; // half way round the ring, r - d and r + d are one sample
                        int q = r + sign * d;
                        if (ring)
                            q = (q + count) % count;
                        else if (q < 0 || q >= count)
                            continue;
                        const std::pair<double, uint32_t> candidate(distance2(r, q), uint32_t(q));
                        if (int(best.size()) == k && !(candidate < best.back()))
                            continue;
                        if (int(best.size()) == k)
                            best.pop_back();
                        best.insert(std::upper_bound(best.begin(), best.end(), candidate), candidate);
                    }
                }
                for (int q = 0; q < k; ++q)
                    n.index[size_t(r) * size_t(k) + size_t(q)] = best[size_t(q)].second;
            }
        });
    return n;
}
} // namespace

SampleNeighbours hemisphere_neighbours(int rays, int k)
{
    if (rays <= k + 1)
        return all_others(rays);
    // The middles of the strata, turned by 0 (spiral's arithmetic in double).
    std::vector<glm::dvec3> middle(static_cast<size_t>(rays));
    for (int r = 0; r < rays; ++r)
    {
        const double z = 1.0 - (double(r) + 0.5) / double(rays), s = std::sqrt(1.0 - z * z);
        double frac = double(r) * 0.6180339887498949;
        frac -= std::floor(frac);
        middle[size_t(r)] = {s * std::cos(2.0 * M_PI * frac), s * std::sin(2.0 * M_PI * frac), z};
    }
    return nearest(rays, k, false,
                   [&](int r, int q)
                   {
                       const glm::dvec3 v = middle[size_t(q)] - middle[size_t(r)];
                       return v.x * v.x + v.y * v.y + v.z * v.z;
                   });
}

SampleNeighbours lattice_neighbours(int count, int k)
{
    if (count <= k + 1)
        return all_others(count);
    // Distance along one axis of the unit torus.
    const auto around = [](double a)
    {
        a = std::abs(a - std::floor(a));
        return std::min(a, 1.0 - a);
    };
    return nearest(count, k, true,
                   [&](int r, int q)
                   {
                       const double x = around(double(q - r) / double(count)),
                                    y = around(double(q) * 0.6180339887498949 -
                                               double(r) * 0.6180339887498949);
                       return x * x + y * y;
                   });
}

} // namespace hemi::bake
