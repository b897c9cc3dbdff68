#pragma once
// SH projection of environment maps stored as images, with exact per-texel solid angles.
//
// Conventions (z up, like hemi's world and tangent space):
//  - equirectangular (latitude-longitude), Blender's world mapping for z-up scenes (Cycles'
//    direction_to_equirectangular: u = 0.5 - atan2(y, x) / 2pi, v = 1 - acos(z) / pi with v up the image):
//    the image centre looks along +x, the left quarter along +y, the right quarter along -y; column x
//    (u = (x + 0.5) / W) is azimuth phi = pi - 2pi u, measured from +x toward +y; row y from the top covers
//    theta in [pi y / H, pi (y+1) / H) from +z (row 0 is the zenith); texel solid angle =
//    (2pi / W) (cos theta0 - cos theta1). An environment Blender renders behind a scene lights it the same.
//  - cube map: six square faces in the order +X, -X, +Y, -Y, +Z, -Z with the Vulkan/OpenGL face
//    orientation (e.g. +X: direction (1, -t, -s) for face coordinates s, t in [-1, 1], t down the rows);
//    texel solid angle from the exact area integral A(x, y) = atan2(xy, sqrt(x^2 + y^2 + 1)).

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hemi::math
{

// `rgba` holds width*height RGBA floats, row-major from the top row. Throws std::invalid_argument on
// inconsistent sizes or non-finite texels.
std::vector<glm::vec3> project_equirect(int order, uint32_t width, uint32_t height,
                                        std::span<const float> rgba);

// The pixel (x, y) of a width x height equirectangular image that the unit direction d falls in,
// by the convention above (every direction falls in exactly one pixel).
void equirect_pixel(const glm::dvec3& d, uint32_t width, uint32_t height, uint32_t& x, uint32_t& y);

// `faces` holds 6 faces of size x size RGBA floats, one after another in the order above.
std::vector<glm::vec3> project_cubemap(int order, uint32_t size, std::span<const float> faces);

// The unit direction through face coordinates (s, t) in [-1, 1] of cube face `face` (0..5, order above).
glm::vec3 cubemap_direction(int face, float s, float t);
// Exact solid angle of the face region [s0, s1] x [t0, t1] (any face).
double cubemap_solid_angle(double s0, double t0, double s1, double t1);

} // namespace hemi::math
