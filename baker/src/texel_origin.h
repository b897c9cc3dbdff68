#pragma once
// Where a lightmap texel's rays start, and whether it lies inside geometry: shared by the lightmap bake
// (each texel's origin and LightmapSh::valid) and the atlas's overlap rule (a texel that several triangles
// claim goes to one a viewer can reach), so that both judge a texel alike. Internal to hemi_baker.

#include <hemi/bake/embree_scene.h>
#include <hemi/io/mesh.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>

namespace hemi::bake::detail
{

class TexelOrigins
{
  public:
    // `offset`: the ray offset (EmbreeScene::ray_offset); `double_sided(triangle)`: a surface whose back
    // sends light as its front does (its back is no sign of being inside geometry); empty: none is.
    TexelOrigins(const EmbreeScene& scene, const io::Mesh& mesh, uint32_t width, uint32_t height,
                 float offset, std::function<bool(uint32_t)> double_sided = {});

    // Whether the ray meets the back of a single-sided surface.
    bool back_face(uint32_t triangle, const glm::vec3& direction) const;

    struct Origin
    {
        glm::vec3 origin{0.0f}; // where the texel's rays start, off the surface
        bool moved = false;  // not from the sample point itself: moved out of a wall, or within the footprint
        bool inside = false; // inside geometry wherever its footprint was tried
    };
    // Texel (x, y) of `triangle`, sampled at `barycentric` (the texel centre's, or a grazed texel's point):
    //   - the point, kept inside the triangle, moved through the nearest back face that eight rays in the
    //     triangle's plane, as long as half the texel's diagonal, reach (a sample under a wall or inside it
    //     comes out on the wall's visible side);
    //   - if that origin lies inside geometry (inside() below), the point itself not moved; then 8 points
    //     of the texel's footprint 0.4 texels out along each axis (the edges' middles first, then the
    //     corners) on the triangle, each moved out of walls as above or else not; then those beyond its
    //     edges, in its plane (where its chart goes on onto the next triangle; one under a wall or past a
    //     corner into another surface is inside geometry and not taken). The first not inside geometry is the
    //     origin: a texel that straddles a wall, its centre inside the wall and an edge of it in the room,
    //     keeps the light of the part that a viewer sees.
    // `tangent`: the texel's, which the push's eight directions start from (else one of the plane's).
    Origin find(uint32_t triangle, uint32_t x, uint32_t y, const glm::vec3& barycentric,
                const glm::vec3* tangent = nullptr) const;

    // Whether a ray origin of `triangle` at texel item `item` (y * width + x) lies inside geometry: more than
    // half of the hemisphere rays about the triangle's normal meet the back of a single-sided surface first;
    // 16 to kInsideRays rays, until the count is clear. Its rays do not depend on a bake's ray count.
    static constexpr int kInsideRays = 128;
    bool inside(const glm::vec3& origin, uint32_t triangle, uint64_t item) const;

    // Whether a texel judged inside geometry is seen from outside it all the same: of kSeenRays hemisphere
    // rays from `origin` about the triangle's normal (others than inside()'s), at least kSeenHits meet the
    // front of a surface (or either side of a double-sided one) at a point that is not inside geometry by
    // inside()'s test about the side met. Lines of sight go both ways: such a point sees the texel. A wall
    // facing the backs of single-sided walls (an outer wall behind an arena's, whose backs q3map2 drops)
    // meets backs over most of its hemisphere, and yet a viewer in the arena sees it over their tops; a face
    // inside a wall or a pillar meets only that geometry's insides, and the points it meets there are inside
    // geometry too. Two points, not one, so that a ray through a crack between two brushes does not count.
    // `may_be_outside(hit)`: false where the point met is known to be inside geometry (a texel judged inside
    // wherever its footprint was tried), which saves its test.
    static constexpr int kSeenRays = 64, kSeenHits = 2;
    bool seen(const glm::vec3& origin, uint32_t triangle, uint64_t item,
              const std::function<bool(const RayHit&)>& may_be_outside = {}) const;

  private:
    // inside() about the unit normal `g`.
    bool inside_about(const glm::vec3& origin, const glm::vec3& g, uint64_t item) const;

    const EmbreeScene& scene_;
    const io::Mesh& mesh_;
    uint32_t width_, height_;
    float offset_;
    std::function<bool(uint32_t)> double_sided_;
};

} // namespace hemi::bake::detail
