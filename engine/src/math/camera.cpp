// hemi's world and cameras (camera.h).
#include <hemi/math/camera.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace hemi::math
{

glm::mat4 gltf_to_world()
{
    // (x, y, z)_glTF -> (x, -z, y)_world: +90 degrees about x.
    return glm::rotate(glm::mat4(1.0f), float(M_PI) / 2.0f, glm::vec3(1.0f, 0.0f, 0.0f));
}

BoundingSphere bounding_sphere(const io::Mesh& mesh, const glm::mat4& model)
{
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : mesh.positions)
    {
        const glm::vec3 w = glm::vec3(model * glm::vec4(p, 1.0f));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
    }
    const glm::vec3 c = 0.5f * (lo + hi);
    float r = 0.0f;
    for (const glm::vec3& p : mesh.positions)
        r = std::max(r, glm::length(glm::vec3(model * glm::vec4(p, 1.0f)) - c));
    return {c, std::max(r, 1e-6f)};
}

Camera auto_camera(const io::Mesh& mesh, const glm::mat4& model, float aspect)
{
    const BoundingSphere s = bounding_sphere(mesh, model);
    Camera c;
    const float half = glm::radians(c.fov_y_degrees) * 0.5f;
    // The sphere fits the narrower of the two fields of view.
    const float fit = aspect < 1.0f ? std::atan(std::tan(half) * aspect) : half;
    const float distance = s.radius / std::sin(fit) * 1.02f;
    c.target = s.centre;
    c.eye = s.centre + distance * glm::normalize(glm::vec3(0.35f, -1.0f, 0.45f));
    return c;
}

glm::mat4 camera_matrix(const Camera& camera, const io::Mesh& mesh, const glm::mat4& model, float aspect)
{
    return camera_matrix(camera, bounding_sphere(mesh, model), aspect);
}

namespace
{
// The view-projection of `camera` with the given planes (Vulkan clip space, y down).
glm::mat4 view_projection(const Camera& camera, float aspect, float near_plane, float far_plane)
{
    const glm::vec3 forward = glm::normalize(camera.target - camera.eye);
    glm::vec3 up(0.0f, 0.0f, 1.0f);
    if (glm::length(glm::cross(forward, up)) < 1e-3f)
        up = glm::vec3(0.0f, 1.0f, 0.0f); // looking straight up or down
    const glm::mat4 view = glm::lookAt(camera.eye, camera.target, up);
    glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(camera.fov_y_degrees), aspect, near_plane, far_plane);
    proj[1][1] *= -1.0f; // Vulkan clip space: y down
    return proj * view;
}
} // namespace

glm::mat4 camera_ray_matrix(const Camera& camera, float aspect)
{
    camera_matrix(camera, BoundingSphere{camera.target, 1.0f}, aspect); // checks the camera
    return view_projection(camera, aspect, 1.0f, 2.0f);
}

glm::mat4 camera_matrix(const Camera& camera, const BoundingSphere& s, float aspect)
{
    const auto finite = [](const glm::vec3& v)
    { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    if (!finite(camera.eye) || !finite(camera.target))
        throw std::invalid_argument("hemi: the camera's eye or target is not finite");
    if (!(camera.fov_y_degrees > 0.0f && camera.fov_y_degrees < 180.0f))
        throw std::invalid_argument("hemi: the camera's field of view must be in (0, 180) degrees");
    if (!(glm::length(camera.target - camera.eye) > 0.0f))
        throw std::invalid_argument("hemi: the camera's eye and target coincide");
    // Depth is measured along the view axis, not toward the sphere's centre (the target may be off-centre).
    const glm::vec3 forward = glm::normalize(camera.target - camera.eye);
    const float depth = glm::dot(s.centre - camera.eye, forward);
    const float far_plane = std::max(depth + s.radius * 1.01f, 1e-3f);
    const float near_plane = std::max(far_plane * 1e-4f, depth - s.radius * 1.01f);
    return view_projection(camera, aspect, near_plane, far_plane);
}

glm::mat4 look_at_projection(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees, float aspect)
{
    glm::mat4 view = glm::lookAt(eye, target, glm::vec3(0.0f, 0.0f, 1.0f));
    glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(fov_y_degrees), aspect, 0.05f, 100.0f);
    proj[1][1] *= -1.0f; // Vulkan clip space: y down
    return proj * view;
}

std::optional<Camera> parse_camera(std::string_view text)
{
    if (text == "auto")
        return std::nullopt;
    const std::string s(text);
    const std::string form = "--camera expects auto or EYE,TARGET (6 comma-separated numbers, each within "
                             "+-1e6 world units, the eye apart from the target), got '" +
                             s + "'";
    float v[6] = {};
    size_t start = 0;
    for (int i = 0; i < 6; ++i)
    {
        const size_t comma = s.find(',', start);
        if ((i < 5) != (comma != std::string::npos))
            throw std::invalid_argument(form);
        const std::string item =
            s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        char* end = nullptr;
        const double d =
            item.empty() || std::isspace((unsigned char)item[0]) ? NAN : std::strtod(item.c_str(), &end);
        if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(d) || std::abs(d) > 1e6)
            throw std::invalid_argument(form);
        v[i] = float(d);
        start = comma + 1;
    }
    Camera c;
    c.eye = glm::vec3(v[0], v[1], v[2]);
    c.target = glm::vec3(v[3], v[4], v[5]);
    if (!(glm::length(c.target - c.eye) > 1e-6f))
        throw std::invalid_argument(form);
    return c;
}

} // namespace hemi::math
