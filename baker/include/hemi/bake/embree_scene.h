#pragma once
// An Embree scene over one triangle mesh: the ray casting the bakes share (the PRT bake today; the lightmap,
// SSBump and reference tracers are to trace the same way).
//
// Units: origins, directions and distances are in the mesh's own units and object space (no transform).
// A direction need not be unit, but distances are measured in multiples of its length, so pass unit
// directions to get distances in mesh units.
//
// Triangles are io::Mesh's: counter-clockwise seen from the front (outside). Rays hit both sides (no
// culling): a bake that cares which side it hit compares the ray with geometric_normal().
//
// Degenerate triangles (zero area: a repeated vertex, or three collinear ones) are never hit: Embree's
// intersection test divides by the triangle's area. Their geometric_normal() is zero.
//
// Thread safety: construction builds the BVH (on Embree's TBB threads); after that the scene is read-only
// and every query may run from any number of threads at once (Embree's scenes are safe for concurrent
// queries once committed). intersect() and occluded() trace one ray (rtcIntersect1 / rtcOccluded1); their
// span overloads trace many in packets of 16 (rtcIntersect16 / rtcOccluded16), which is what the bakes use
// for the rays of one texel or one vertex: rays that share an origin (or a direction, towards the sun) walk
// the BVH's upper levels together, and Embree traces such a packet faster than its rays one by one.

#include <hemi/io/mesh.h>

#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>

namespace hemi::bake
{

// Where a ray first meets the mesh.
struct RayHit
{
    uint32_t primitive = 0;   // the triangle: mesh.indices[3 * primitive + 0..2]
    float u = 0.0f, v = 0.0f; // Embree's barycentrics: p = (1 - u - v) p0 + u p1 + v p2
    float distance = 0.0f;    // along the ray, in multiples of the direction's length
};

// One ray of a batch (EmbreeScene's span overloads).
struct Ray
{
    glm::vec3 origin{0.0f};
    float t_near = 0.0f;
    glm::vec3 direction{0.0f, 0.0f, 1.0f};
    float t_far = INFINITY;
};

class EmbreeScene
{
  public:
    // Copies the mesh's positions and triangles (the mesh may go away afterwards; normals, tangents and UVs
    // are not used). Throws std::invalid_argument for a mesh without vertices or triangles, an index count
    // that is not a multiple of 3, an index out of range or a non-finite position (Embree would silently drop
    // such triangles), and std::runtime_error, with Embree's message, when Embree fails.
    explicit EmbreeScene(const io::Mesh& mesh);
    ~EmbreeScene();
    // One Embree device and scene per object: not copied. Moving keeps them (Embree's error callback holds
    // the address of the part on the heap); a moved-from scene may only be destroyed.
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;
    EmbreeScene(EmbreeScene&&) noexcept;
    EmbreeScene& operator=(EmbreeScene&&) noexcept;

    // The closest hit with distance in [t_near, t_far], or none.
    std::optional<RayHit> intersect(const glm::vec3& origin, const glm::vec3& direction, float t_near = 0.0f,
                                    float t_far = INFINITY) const;
    // Whether anything lies along the ray within [t_near, t_far]: a shadow ray. Cheaper than intersect()
    // (it stops at the first hit found, not the closest), and the same answer as intersect().has_value().
    bool occluded(const glm::vec3& origin, const glm::vec3& direction, float t_near = 0.0f,
                  float t_far = INFINITY) const;
    // The same queries for every ray of `rays`, traced in packets of 16: hits[i] (blocked[i]: 1 or 0) is the
    // answer for rays[i]. A packet's answers may differ from the single-ray queries' in the last bits of u,
    // v and distance (Embree's packet and single-ray intersectors round differently), and are the same for
    // the same rays every time. Throws std::invalid_argument when the output's size is not the rays'.
    void intersect(std::span<const Ray> rays, std::span<std::optional<RayHit>> hits) const;
    void occluded(std::span<const Ray> rays, std::span<uint8_t> blocked) const;

    // cross(p1 - p0, p2 - p0) of a triangle: not normalised (its length is twice the area, zero for a
    // degenerate triangle), pointing to its front. Computed from the scene's copy of the positions rather
    // than taken from Embree's hit record: the bits are then those of the same expression anywhere else
    // (the PRT bake's front-face test must not flip with Embree's intersector). Computed once per triangle
    // when the scene is built (12 bytes a triangle).
    glm::vec3 geometric_normal(uint32_t primitive) const;

    uint32_t triangle_count() const { return triangle_count_; }
    // The length of the diagonal of the positions' axis-aligned bounding box, in mesh units.
    float diagonal() const { return diagonal_; }
    // How far a ray origin moves off the surface to escape its own triangle: `fraction` of the diagonal, so
    // that one option (PrtBakeOptions::ray_offset) suits models of any size.
    float ray_offset(float fraction) const { return fraction * diagonal_; }

    // RTC_VERSION of the Embree the scene is built with: its BVH and intersector decide which of two
    // nearly-equal triangles a ray hits, so bakes put it in their checkpoint keys.
    static int embree_version();

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    uint32_t triangle_count_ = 0;
    float diagonal_ = 0.0f;
};

// A ray origin `distance` off the surface point along its unit normal: the origin every bake ray starts
// from (EmbreeScene::ray_offset gives the distance), in one place so that all bakes compute it alike.
inline glm::vec3 offset_ray_origin(const glm::vec3& point, const glm::vec3& unit_normal, float distance)
{
    return point + distance * unit_normal;
}

} // namespace hemi::bake
