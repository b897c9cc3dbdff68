// The reference tracer (reference.h).
#include "light_sampler.h"

#include <hemi/bake/embree_scene.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/bake/reference.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/math/ggx.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace hemi::bake
{
namespace
{

constexpr int kMaxBounces = 16;

// A surface point as a path sees it, in the mesh's space.
struct SurfacePoint
{
    glm::vec3 origin; // offset off the surface along g, where its rays start
    glm::vec3 g;      // unit geometric normal of the side seen
    glm::vec3 n;      // unit interpolated (shading) normal of that side: the hemisphere that is lit
};

// A unit frame about `n`.
void frame_about(const glm::vec3& n, glm::vec3& t, glm::vec3& b)
{
    const glm::vec3 a = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    t = glm::normalize(a - n * glm::dot(n, a));
    b = glm::cross(n, t);
}

class Tracer
{
  public:
    Tracer(const io::Mesh& mesh, const LightmapSurfaces& surfaces, const LightmapLights& lights,
           const ReferenceOptions& o)
        : mesh_(mesh), surfaces_(surfaces), lights_(lights), o_(o), scene_(mesh), light_(lights, o.seed),
          offset_(scene_.ray_offset(o.ray_offset))
    {
        for (int level = 0; level <= kMaxBounces; ++level)
            seeds_[level] = mix64(o.seed + uint64_t(level + 1) * 0x9E3779B97F4A7C15ull);
        specular_seed_ = mix64(o.seed ^ 0x5350454355ull);
    }

    float offset() const { return offset_; }
    const EmbreeScene& scene() const { return scene_; }

    // Whether light leaves the hit towards the ray (the front of a surface, or either side of a double-sided
    // one).
    bool seen(const RayHit& hit, const glm::vec3& d) const
    {
        return !(glm::dot(scene_.geometric_normal(hit.primitive), d) > 0.0f) ||
               surfaces_.double_sided(hit.primitive);
    }

    // The surface point of a hit seen along `d`: both normals turned to the side the ray sees.
    SurfacePoint point(const glm::vec3& from, const glm::vec3& d, const RayHit& hit,
                       glm::vec3* tangent_normal_world) const
    {
        const uint32_t* idx = &mesh_.indices[size_t(hit.primitive) * 3];
        const float w0 = 1.0f - hit.u - hit.v;
        glm::vec3 g = glm::normalize(scene_.geometric_normal(hit.primitive));
        glm::vec3 n =
            w0 * mesh_.normals[idx[0]] + hit.u * mesh_.normals[idx[1]] + hit.v * mesh_.normals[idx[2]];
        n = glm::length(n) > 0.0f ? glm::normalize(n) : g;
        if (glm::dot(g, d) > 0.0f) // a double-sided surface seen from behind: lit as the other side
        {
            g = -g;
            n = -n;
        }
        if (tangent_normal_world)
        {
            // The material system's frame: T orthogonalised against N, B = cross(N, T) w.
            const glm::vec4 t4 =
                w0 * mesh_.tangents[idx[0]] + hit.u * mesh_.tangents[idx[1]] + hit.v * mesh_.tangents[idx[2]];
            glm::vec3 t = glm::vec3(t4) - n * glm::dot(n, glm::vec3(t4));
            glm::vec3 b;
            if (glm::length(t) > 1e-8f)
            {
                t = glm::normalize(t);
                b = glm::cross(n, t) * (mesh_.tangents[idx[0]].w < 0.0f ? -1.0f : 1.0f);
            }
            else
                frame_about(n, t, b);
            const glm::vec3 nt = surfaces_.tangent_normal(hit.primitive, hit.u, hit.v);
            *tangent_normal_world = glm::normalize(t * nt.x + b * nt.y + n * nt.z);
        }
        const glm::vec3 p = from + d * hit.distance;
        return {offset_ray_origin(p, g, offset_), g, n};
    }

    // One path's estimate of the irradiance at `s` towards the unit normal `m` (E(m) over the hemisphere of
    // s.n, dark below s.g's plane): path `r` of `count` of `item` at bounce `level`.
    glm::dvec3 irradiance(const SurfacePoint& s, const glm::vec3& m, uint64_t item, int r, int count,
                          int level, uint64_t& rays) const
    {
        const uint64_t key = item * uint64_t(kMaxBounces + 1) + uint64_t(level);
        auto lit = [&](const glm::vec3& d) { return glm::dot(d, s.g) > 0.0f && glm::dot(d, s.n) > 0.0f; };
        glm::dvec3 e(0.0);
        // Cosine-weighted about m, from the stratified hemisphere set (z uniform -> z = sqrt(z)).
        {
            const glm::vec3 h = hemisphere_direction(seeds_[level], key, r, count);
            const float z = std::sqrt(std::max(0.0f, h.z)), rho = std::sqrt(std::max(0.0f, 1.0f - z * z));
            const float phi = std::atan2(h.y, h.x);
            glm::vec3 t, b;
            frame_about(m, t, b);
            const glm::vec3 d = glm::normalize(rho * std::cos(phi) * t + rho * std::sin(phi) * b + z * m);
            if (lit(d))
            {
                ++rays;
                const std::optional<RayHit> hit = scene_.intersect(s.origin, d);
                glm::dvec3 radiance(0.0);
                if (!hit)
                {
                    if (!light_.image_environment())
                        radiance = glm::dvec3(lights_.environment_radiance(d));
                }
                else if (seen(*hit, d))
                {
                    radiance = glm::dvec3(surfaces_.emission(hit->primitive, hit->u, hit->v));
                    if (level < o_.bounces)
                    {
                        const SurfacePoint next = point(s.origin, d, *hit, nullptr);
                        radiance += glm::dvec3(surfaces_.albedo(hit->primitive, hit->u, hit->v)) / M_PI *
                                    irradiance(next, next.n, item, r, count, level + 1, rays);
                    }
                }
                e += radiance * M_PI; // cosine-weighted: E = pi * mean L
            }
        }
        glm::vec3 d;
        double w = 0.0;
        if (light_.environment_ray(key, r, count, d, w) && lit(d))
        {
            const float c = glm::dot(d, m);
            ++rays;
            if (c > 0.0f && !scene_.occluded(s.origin, d))
                e += glm::dvec3(lights_.environment_radiance(d)) * (double(c) * w * double(count));
        }
        if (lights_.sun)
        {
            d = light_.sun_ray(key, r);
            const float c = glm::dot(d, m);
            if (c > 0.0f && lit(d))
            {
                ++rays;
                if (!scene_.occluded(s.origin, d))
                    e += glm::dvec3(lights_.sun_irradiance) * double(c);
            }
        }
        for (const io::PunctualLight& p : lights_.punctual)
        {
            float distance = INFINITY;
            const glm::vec3 irr = light_.punctual(p, s.origin, d, distance);
            const float c = glm::dot(d, m);
            if (irr == glm::vec3(0.0f) || !(c > 0.0f) || !lit(d))
                continue;
            ++rays;
            if (!scene_.occluded(s.origin, d, 0.0f,
                                 std::isfinite(distance) ? distance * (1.0f - 1e-4f) : INFINITY))
                e += glm::dvec3(irr) * double(c);
        }
        return e;
    }

    // One path's estimate of the GGX coat's specular radiance at `s` towards the unit view direction v, at
    // the normal-map normal m (lit from the hemisphere of s.n, dark below s.g's plane): path `r` of `count`
    // of `item`.
    glm::dvec3 specular(const SurfacePoint& s, const glm::vec3& m, const glm::vec3& v, uint64_t item, int r,
                        int count, uint64_t& rays) const
    {
        auto lit = [&](const glm::vec3& d) { return glm::dot(d, s.g) > 0.0f && glm::dot(d, s.n) > 0.0f; };
        const glm::dvec3 f0(o_.f0), md(m), vd(v);
        const uint64_t key = mix64(item ^ specular_seed_);
        glm::dvec3 l(0.0);
        if (lights_.sun)
        {
            const glm::vec3 d = light_.sun_ray(key, r);
            if (lit(d) && glm::dot(d, m) > 0.0f)
            {
                ++rays;
                if (!scene_.occluded(s.origin, d))
                    l += glm::dvec3(lights_.sun_irradiance) *
                         math::ggx_eval_cos(md, glm::dvec3(d), vd, o_.roughness, f0);
            }
        }
        for (const io::PunctualLight& p : lights_.punctual)
        {
            glm::vec3 d;
            float distance = INFINITY;
            const glm::vec3 irr = light_.punctual(p, s.origin, d, distance);
            if (irr == glm::vec3(0.0f) || !(glm::dot(d, m) > 0.0f) || !lit(d))
                continue;
            ++rays;
            if (!scene_.occluded(s.origin, d, 0.0f,
                                 std::isfinite(distance) ? distance * (1.0f - 1e-4f) : INFINITY))
                l += glm::dvec3(irr) * math::ggx_eval_cos(md, glm::dvec3(d), vd, o_.roughness, f0);
        }
        // The lobe: a stratified pair of uniforms from the hemisphere set (z and the azimuth are uniform).
        const glm::vec3 h = hemisphere_direction(specular_seed_, item, r, count);
        double azimuth = std::atan2(double(h.y), double(h.x)) / (2.0 * M_PI);
        if (azimuth < 0.0)
            azimuth += 1.0;
        double pdf = 0.0;
        const glm::dvec3 dd =
            math::ggx_sample(md, vd, o_.roughness, std::clamp(double(h.z), 0.0, 1.0 - 1e-12),
                             std::clamp(azimuth, 0.0, 1.0 - 1e-12), pdf);
        const glm::vec3 d = glm::normalize(glm::vec3(dd));
        if (pdf > 0.0 && lit(d))
        {
            ++rays;
            const std::optional<RayHit> hit = scene_.intersect(s.origin, d);
            glm::dvec3 radiance(0.0);
            if (!hit)
                radiance = glm::dvec3(lights_.environment_radiance(d));
            else if (seen(*hit, d))
            {
                radiance = glm::dvec3(surfaces_.emission(hit->primitive, hit->u, hit->v));
                if (o_.bounces > 0)
                {
                    const SurfacePoint next = point(s.origin, d, *hit, nullptr);
                    radiance += glm::dvec3(surfaces_.albedo(hit->primitive, hit->u, hit->v)) / M_PI *
                                irradiance(next, next.n, item ^ (1ull << 62), r, count, 1, rays);
                }
            }
            l += radiance * math::ggx_eval_cos(md, dd, vd, o_.roughness, f0) / pdf;
        }
        return l;
    }

  private:
    const io::Mesh& mesh_;
    const LightmapSurfaces& surfaces_;
    const LightmapLights& lights_;
    const ReferenceOptions& o_;
    EmbreeScene scene_;
    detail::LightSampler light_;
    float offset_;
    uint64_t seeds_[kMaxBounces + 1];
    uint64_t specular_seed_ = 0;
};

} // namespace

ReferenceImage render_reference(const io::Mesh& mesh, const LightmapSurfaces& surfaces,
                                const LightmapLights& lights, const ReferenceOptions& o,
                                const std::function<void(uint32_t rows_done, uint32_t rows)>& progress)
{
    if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
        throw std::invalid_argument("the reference image's size " + std::to_string(o.width) + "x" +
                                    std::to_string(o.height) + " is not within 1 to 16384 a side");
    if (o.rays < 2 || o.rays > (1 << 20))
        throw std::invalid_argument("paths per pixel " + std::to_string(o.rays) + " is not in [2, 2^20]");
    if (o.bounces < 0 || o.bounces > kMaxBounces)
        throw std::invalid_argument("bounces " + std::to_string(o.bounces) + " is not in [0, 16]");
    if (!(o.ray_offset >= 0.0f) || !std::isfinite(o.ray_offset))
        throw std::invalid_argument("the ray offset must be >= 0");
    if (!(o.roughness == 0.0 || (o.roughness >= math::kGgxMinRoughness && o.roughness <= 1.0)))
        throw std::invalid_argument("the GGX coat's roughness must be 0 (none) or in [0.03, 1], got " +
                                    std::to_string(o.roughness));
    if (!(o.f0 >= 0.0 && o.f0 <= 1.0))
        throw std::invalid_argument("the GGX coat's f0 must be in [0, 1], got " + std::to_string(o.f0));
    detail::check_lights(lights);
    if (const std::string problem = io::mesh_problem(mesh, io::MeshNeeds::Frames); !problem.empty())
        throw std::invalid_argument("the reference needs normals, tangents and UVs: " + problem);

    ReferenceImage out;
    const float aspect = float(o.width) / float(o.height);
    out.camera = o.auto_camera ? math::auto_camera(mesh, o.model, aspect) : o.camera;
    const glm::mat4 inverse = glm::inverse(math::camera_ray_matrix(out.camera, aspect));
    const glm::mat4 to_mesh = glm::inverse(o.model);
    const glm::vec3 eye = glm::vec3(to_mesh * glm::vec4(out.camera.eye, 1.0f));
    const Tracer tracer(mesh, surfaces, lights, o);
    const uint64_t pixel_seed = mix64(o.seed ^ 0x5049584c5f5241ull);

    out.image = io::ImageRgba{o.width, o.height, std::vector<float>(size_t(o.width) * o.height * 4, 0.0f)};
    std::vector<double> error(size_t(o.width) * o.height, -1.0); // per pixel: squared standard error, or -1
    std::atomic<uint64_t> rays{0};
    const auto t0 = std::chrono::steady_clock::now();
    const uint32_t chunk = std::max<uint32_t>(1, std::min<uint32_t>(16, o.height / 16));
    for (uint32_t first = 0; first < o.height; first += chunk)
    {
        const uint32_t last = std::min(o.height, first + chunk);
        tbb::parallel_for(
            tbb::blocked_range<uint32_t>(first * o.width, last * o.width, 16),
            [&](const tbb::blocked_range<uint32_t>& range)
            {
                uint64_t traced = 0;
                for (uint32_t pixel = range.begin(); pixel != range.end(); ++pixel)
                {
                    const uint32_t px = pixel % o.width, py = pixel / o.width;
                    glm::dvec3 sum[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
                    int hits[2] = {0, 0};
                    for (int r = 0; r < o.rays; ++r)
                    {
                        // A uniformly random point of the pixel's square.
                        const float jx = uniform01(pixel_seed, pixel, uint64_t(2 * r));
                        const float jy = uniform01(pixel_seed, pixel, uint64_t(2 * r + 1));
                        const glm::vec2 ndc((float(px) + jx) / float(o.width) * 2.0f - 1.0f,
                                            (float(py) + jy) / float(o.height) * 2.0f - 1.0f);
                        glm::vec4 far = inverse * glm::vec4(ndc, 1.0f, 1.0f);
                        const glm::vec3 target = glm::vec3(to_mesh * glm::vec4(glm::vec3(far) / far.w, 1.0f));
                        const glm::vec3 d = glm::normalize(target - eye);
                        // The nearest surface whose side towards the eye is drawn (culled back faces let it
                        // through).
                        float t_near = 0.0f;
                        std::optional<RayHit> hit;
                        for (int layer = 0; layer < 256; ++layer)
                        {
                            ++traced;
                            hit = tracer.scene().intersect(eye, d, t_near);
                            if (!hit || tracer.seen(*hit, d))
                                break;
                            t_near = hit->distance + tracer.offset();
                            hit.reset();
                        }
                        if (!hit)
                            continue;
                        glm::vec3 m;
                        const SurfacePoint s = tracer.point(eye, d, *hit, &m);
                        // The even and the odd paths are two independent stratified sets (the noise estimate
                        // compares them), each over its half of the paths.
                        const int half = r & 1, halves[2] = {(o.rays + 1) / 2, o.rays / 2};
                        const glm::dvec3 e = tracer.irradiance(s, m, uint64_t(pixel) * 2 + uint64_t(half),
                                                               r >> 1, halves[half], 0, traced);
                        glm::dvec3 colour = e / M_PI;
                        if (!o.white)
                            colour = glm::dvec3(surfaces.albedo(hit->primitive, hit->u, hit->v)) * colour +
                                     glm::dvec3(surfaces.emission(hit->primitive, hit->u, hit->v));
                        if (o.roughness > 0.0)
                            colour += tracer.specular(s, m, -d, uint64_t(pixel) * 2 + uint64_t(half), r >> 1,
                                                      halves[half], traced);
                        sum[r & 1] += colour;
                        ++hits[r & 1];
                    }
                    float* p = out.image.pixels.data() + size_t(pixel) * 4;
                    const int n = hits[0] + hits[1];
                    if (n > 0)
                    {
                        const glm::dvec3 mean = (sum[0] + sum[1]) / double(n);
                        p[0] = float(mean.x), p[1] = float(mean.y), p[2] = float(mean.z);
                    }
                    p[3] = float(n) / float(o.rays);
                    if (n == o.rays)
                    {
                        // Two independent estimates a, b of n_a and n_b paths: Var(a - b) = s^2 (1/n_a +
                        // 1/n_b) and the whole mean's variance s^2 / n, so (a - b)^2 n_a n_b / n^2 estimates
                        // the latter.
                        const glm::dvec3 diff = sum[0] / double(hits[0]) - sum[1] / double(hits[1]);
                        const double share = double(hits[0]) * double(hits[1]) / (double(n) * double(n));
                        error[pixel] = glm::dot(diff, diff) * share / 3.0; // over three channels
                    }
                }
                rays += traced;
            });
        if (progress)
            progress(last, o.height);
    }
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.rays = rays;
    double total = 0.0;
    size_t counted = 0;
    for (const double e : error)
        if (e >= 0.0)
        {
            total += e;
            ++counted;
        }
    out.noise = counted ? std::sqrt(total / double(counted)) : 0.0;
    return out;
}

ReferenceImage render_reference_file(const std::filesystem::path& scene_path,
                                     const std::filesystem::path& exr, LightmapLights lights,
                                     const ReferenceOptions& options,
                                     const std::function<void(uint32_t rows_done, uint32_t rows)>& progress)
{
    io::check_writable(exr);
    const io::GltfScene scene = io::read_gltf(scene_path);
    lights.scene_to_world = glm::mat3(math::gltf_to_world());
    lights.punctual.insert(lights.punctual.end(), scene.lights.begin(), scene.lights.end());
    const LightmapSurfaces surfaces(scene.mesh, scene.materials, scene.images, scene.primitives);
    ReferenceOptions o = options;
    o.model = math::gltf_to_world();
    ReferenceImage image = render_reference(scene.mesh, surfaces, lights, o, progress);
    io::write_exr(exr, image.image);
    return image;
}

} // namespace hemi::bake
