#pragma once
// The bakes' random numbers and ray directions, counter-based: every value is a pure function of
// (seed, item, ray), with no generator state to advance. Whichever thread traces an item, in whatever order,
// on however many threads, and whether the bake ran through or resumed from a checkpoint, the item gets the
// same rays; so the same seed gives the same bytes. An "item" is what a bake traces a set of rays from: a
// vertex for the PRT bake, a texel for a lightmap.
//
// Each item's set is a jittered spherical Fibonacci set (stratified in z, golden-angle spaced in phi) turned
// about z by a random angle of its own: stratified within the item, so R rays integrate smooth functions far
// better than R independent ones, while neighbouring items do not share the same directions (which would
// show as banding) and the set does not depend on anything but the seed, the item and R.
//
// Estimates: a sphere set integrates f over the sphere as (4 pi / R) sum_i f(d_i); a hemisphere set over the
// hemisphere z >= 0 as (2 pi / R) sum_i f(d_i). The sets are about +z in whatever frame the caller means:
// for a surface's hemisphere, d = x T + y B + z N with the tangent frame (T, B, N).

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hemi::bake
{

// SplitMix64's finaliser: a bijective 64-bit mix, the hash the counters go through.
uint64_t mix64(uint64_t z);

// A uniform number in [0, 1) with 24 random bits (exact in a float), determined by (seed, a, b) alone.
// The direction sets below use, for item a, b = 0 (the set's rotation) and b = 1..R (each ray's jitter in
// z); a bake that needs other random numbers for the same items draws them with another seed, e.g.
// mix64(seed ^ purpose), so that they are independent of its rays.
float uniform01(uint64_t seed, uint64_t a, uint64_t b);

// Ray `ray` (0 <= ray < rays) of the sphere set of `rays` directions of `item`: unit, uniform on the sphere,
// each standing for 4 pi / rays steradians. The PRT bake's rays (item = vertex index).
glm::vec3 sphere_direction(uint64_t seed, uint64_t item, int ray, int rays);

// Ray `ray` (0 <= ray < rays) of the hemisphere set of `rays` directions of `item`: unit, z >= 0, uniform on
// the hemisphere, each standing for 2 pi / rays steradians. Built like the sphere set, from the same random
// numbers of (seed, item): a bake uses one of the two sets per item, not both.
glm::vec3 hemisphere_direction(uint64_t seed, uint64_t item, int ray, int rays);

// The whole set of out.size() rays of `item` at once: out[r] is sphere_direction(seed, item, r, out.size())
// (hemisphere_direction(...)) bit for bit, with the item's part of the hashing done once, not per ray. What
// the bakes call for the rays of one texel or vertex.
void sphere_directions(uint64_t seed, uint64_t item, std::span<glm::vec3> out);
void hemisphere_directions(uint64_t seed, uint64_t item, std::span<glm::vec3> out);

// Which samples of a set lie next to which in the set's pattern, for estimating a set's noise from the set
// itself (the lightmap bake's LightmapSh::noise): for each of `count` samples, the indices of its k nearest
// (index[r * k .. r * k + k)), the same for every seed and item (a rotation, or an offset on a torus, moves
// every sample alike, and the jitter is left out). `independent` (index empty): every other sample is a
// neighbour, as for samples drawn independently of each other.
struct SampleNeighbours
{
    int count = 0, k = 0;
    bool independent = false;
    std::vector<uint32_t> index;
};
// The hemisphere set of `rays` directions: the k nearest on the sphere to each, taken at the middles of
// their strata (rays <= k + 1: independent). About rays^1.5 work, once per bake.
SampleNeighbours hemisphere_neighbours(int rays, int k);
// The points (r / count, frac(r * golden ratio)) on the unit torus, the pattern LightSampler's environment
// rays follow (its first coordinate turned by an offset of each item's own, and cut there: the caller leaves
// out pairs across the cut): the k nearest to each by their distance on the torus (count <= k + 1:
// independent). About count^1.5 work, once per bake.
SampleNeighbours lattice_neighbours(int count, int k);

} // namespace hemi::bake
