#pragma once
// hemi's world, its placement of glTF scenes and its cameras: the math that a renderer and the offline
// reference tracer (hemi-bake reference) share, so that a ray-traced image is framed exactly like a
// rasterised one. hemi's world is z up; glTF scenes (and so baked assets) are y up and are placed in the
// world by gltf_to_world() (glTF +y becomes world +z). Clip space is Vulkan's: y down, depth 0 to 1.

#include <hemi/io/mesh.h>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <optional>
#include <string_view>

namespace hemi::math
{

// The rotation placing glTF's y-up space in hemi's z-up world: (x, y, z) -> (x, -z, y).
glm::mat4 gltf_to_world();

struct Camera
{
    glm::vec3 eye{0.0f, -3.0f, 1.0f};
    glm::vec3 target{0.0f};
    float fov_y_degrees = 35.0f; // vertical
};

// The model's bounding sphere in world space (under `model`): centred on the bounding box.
struct BoundingSphere
{
    glm::vec3 centre{0.0f};
    float radius = 1.0f;
};
BoundingSphere bounding_sphere(const io::Mesh& mesh, const glm::mat4& model);

// A camera that frames the whole model (its bounding sphere under `model`) from the front and slightly above.
Camera auto_camera(const io::Mesh& mesh, const glm::mat4& model, float aspect);
// View-projection for `camera` with near and far planes that enclose the model's bounding sphere. Pixel
// (x, y) of a W x H image (row 0 at the top) has its centre at clip ((x + 0.5) / W * 2 - 1, (y + 0.5) / H * 2
// - 1). Throws std::invalid_argument when the eye and the target coincide.
glm::mat4 camera_matrix(const Camera& camera, const io::Mesh& mesh, const glm::mat4& model, float aspect);
glm::mat4 camera_matrix(const Camera& camera, const BoundingSphere& bounds, float aspect);
// The same view and field of view with fixed planes (1 and 2): what a ray tracer inverts for each pixel's
// direction, which the planes do not change. camera_matrix's planes fit the model and collapse to a sliver
// when it lies behind the eye, where their inverse is not finite (hemi-bake reference's rays were NaN there).
glm::mat4 camera_ray_matrix(const Camera& camera, float aspect);
// A view-projection matrix (Vulkan clip space, near 0.05, far 100) looking from `eye` at `target`, z up.
glm::mat4 look_at_projection(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees,
                             float aspect);

// The tools' --camera value: "auto" (nullopt: auto_camera) or EYE,TARGET as six comma-separated numbers
// (world space, z up), each finite and within +-1e6, the eye apart from the target. Throws
// std::invalid_argument quoting the text otherwise.
std::optional<Camera> parse_camera(std::string_view text);

} // namespace hemi::math
