// The directional lightmap bake (lightmap_bake.h).
#include <hemi/bake/checkpoint.h>
#include <hemi/bake/embree_scene.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/math/basis.h>
#include <hemi/math/rnm_basis.h>
#include <hemi/math/sh.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace hemi::bake
{

glm::vec3 LightmapLights::environment_radiance(const glm::vec3& scene_d) const
{
    if (environment.pixels.empty())
        return uniform;
    const glm::vec3 d = scene_to_world * scene_d;
    const uint32_t w = environment.width, h = environment.height;
    const double phi = std::atan2(double(d.y), double(d.x));
    const double theta = std::acos(std::clamp(double(d.z), -1.0, 1.0));
    const double fx = (0.5 - phi / (2.0 * M_PI)) * w - 0.5, fy = theta / M_PI * h - 0.5;
    const double x0 = std::floor(fx), y0 = std::floor(fy);
    const float tx = float(fx - x0), ty = float(fy - y0);
    auto texel = [&](int64_t x, int64_t y) {
        x = ((x % int64_t(w)) + int64_t(w)) % int64_t(w); // the seam wraps
        y = std::clamp<int64_t>(y, 0, int64_t(h) - 1);   // the poles clamp
        const float* p = environment.at(uint32_t(x), uint32_t(y));
        return glm::vec3(p[0], p[1], p[2]);
    };
    const int64_t ix = int64_t(x0), iy = int64_t(y0);
    const glm::vec3 top = texel(ix, iy) * (1.0f - tx) + texel(ix + 1, iy) * tx;
    const glm::vec3 bottom = texel(ix, iy + 1) * (1.0f - tx) + texel(ix + 1, iy + 1) * tx;
    return (top * (1.0f - ty) + bottom * ty) * environment_scale;
}

namespace
{

constexpr uint64_t kLightmapCheckpointVersion = 1;

bool finite3(const glm::vec3& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check(const LightmapLights& l, const LightmapBakeOptions& o)
{
    if (o.rays < 1 || o.rays > (1 << 20))
        throw std::invalid_argument("rays per texel " + std::to_string(o.rays) + " is not in [1, 2^20]");
    if (o.sun_rays < 1 || o.sun_rays > (1 << 16))
        throw std::invalid_argument("sun rays per texel " + std::to_string(o.sun_rays) + " is not in [1, 65536]");
    if (!(o.ray_offset >= 0.0f) || !std::isfinite(o.ray_offset))
        throw std::invalid_argument("the ray offset must be >= 0");
    if (!finite3(l.uniform) || !std::isfinite(l.environment_scale))
        throw std::invalid_argument("the environment's radiance must be finite");
    if (l.sun)
    {
        if (!finite3(l.sun_direction) || glm::length(l.sun_direction) < 1e-6f)
            throw std::invalid_argument("the sun's direction must be a finite vector of non-zero length");
        if (!finite3(l.sun_irradiance))
            throw std::invalid_argument("the sun's irradiance must be finite");
        if (!(l.sun_diameter_degrees >= 0.0f) || !(l.sun_diameter_degrees < 90.0f))
            throw std::invalid_argument("the sun's diameter must be in [0, 90) degrees");
    }
}

uint64_t key_of(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapLights& l, const LightmapBakeOptions& o)
{
    CheckpointKey key(kLightmapCheckpointVersion);
    key.add_array(std::span<const glm::vec3>(mesh.positions)).add_array(std::span<const uint32_t>(mesh.indices));
    key.add_array(std::span<const glm::vec2>(mesh.uvs1)).add_array(std::span<const glm::vec3>(mesh.normals));
    key.add_array(std::span<const glm::vec4>(mesh.tangents));
    key.add_value(atlas.width).add_value(atlas.height);
    key.add_value(l.uniform).add_value(l.environment.width).add_value(l.environment.height);
    key.add_array(std::span<const float>(l.environment.pixels)).add_value(l.environment_scale);
    key.add_value(l.sun).add_value(l.sun_direction).add_value(l.sun_irradiance).add_value(l.sun_diameter_degrees);
    key.add_value(l.scene_to_world);
    key.add_value(o.rays).add_value(o.sun_rays).add_value(o.seed).add_value(o.ray_offset);
    key.add_value(EmbreeScene::embree_version());
    return key.digest();
}

} // namespace

LightmapSh bake_lightmap_sh(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapLights& lights,
                            const LightmapBakeOptions& o, const std::function<void(const LightmapProgress&)>& progress)
{
    check(lights, o);
    LightmapSh out;
    out.width = atlas.width;
    out.height = atlas.height;
    const uint32_t n = uint32_t(atlas.texels.size());
    out.irradiance.assign(n, {});
    if (n == 0)
        return out;
    const EmbreeScene scene(mesh);
    const float offset = scene.ray_offset(o.ray_offset);
    // The sun's direction in the mesh's space.
    const glm::vec3 sun_axis =
        lights.sun ? glm::normalize(glm::transpose(lights.scene_to_world) * lights.sun_direction) : glm::vec3(0, 0, 1);
    // The sun's disc: directions within half its angular diameter of the axis, uniform in solid angle.
    const double cos_half = std::cos(0.5 * double(lights.sun_diameter_degrees) * M_PI / 180.0);
    glm::vec3 sun_u = std::abs(sun_axis.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    sun_u = glm::normalize(sun_u - sun_axis * glm::dot(sun_axis, sun_u));
    const glm::vec3 sun_v = glm::cross(sun_axis, sun_u);
    const uint64_t sun_seed = mix64(o.seed ^ 0x53554e5f5241ull); // independent of the hemisphere rays
    const double weight = 2.0 * M_PI / double(o.rays);

    auto texel = [&](uint32_t i) {
        const LightmapTexel& t = atlas.texels[i];
        const uint64_t item = uint64_t(t.y) * atlas.width + t.x;
        const glm::vec3 origin = offset_ray_origin(t.position, t.geometric_normal, offset);
        std::array<glm::dvec3, 9> acc{};
        auto add = [&](const glm::vec3& world, const glm::dvec3& radiance) {
            const glm::vec3 local(glm::dot(world, t.tangent), glm::dot(world, t.bitangent), glm::dot(world, t.normal));
            const math::Sh9 y = math::sh9_eval(local);
            for (int j = 0; j < 9; ++j)
                acc[size_t(j)] += radiance * double(y[size_t(j)]);
        };
        for (int r = 0; r < o.rays; ++r)
        {
            const glm::vec3 h = hemisphere_direction(o.seed, item, r, o.rays);
            const glm::vec3 d = glm::normalize(h.x * t.tangent + h.y * t.bitangent + h.z * t.normal);
            if (glm::dot(d, t.geometric_normal) <= 0.0f || scene.occluded(origin, d))
                continue; // into its own triangle, or blocked by the scene
            add(d, glm::dvec3(lights.environment_radiance(d)) * weight);
        }
        if (lights.sun)
            for (int r = 0; r < o.sun_rays; ++r)
            {
                // A point of the disc, stratified in the ray index by the counter-based numbers.
                const double z = 1.0 - (1.0 - cos_half) * double(uniform01(sun_seed, item, uint64_t(2 * r)));
                const double phi = 2.0 * M_PI * double(uniform01(sun_seed, item, uint64_t(2 * r + 1)));
                const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
                const glm::vec3 d = glm::normalize(float(z) * sun_axis + float(s * std::cos(phi)) * sun_u +
                                                   float(s * std::sin(phi)) * sun_v);
                if (glm::dot(d, t.geometric_normal) <= 0.0f || scene.occluded(origin, d))
                    continue;
                // A directional light of irradiance E projects to E y(d): its delta radiance, per sample.
                add(d, glm::dvec3(lights.sun_irradiance) / double(o.sun_rays));
            }
        math::Sh9Rgb radiance;
        for (int j = 0; j < 9; ++j)
            radiance[size_t(j)] = glm::vec3(acc[size_t(j)]);
        out.irradiance[i] = math::convolve_cosine(radiance);
    };

    SliceCheckpoint checkpoint(o.checkpoint, key_of(mesh, atlas, lights, o), 1, n,
                               {{"irradiance", std::as_writable_bytes(std::span<std::array<glm::vec3, 9>>(out.irradiance))}},
                               o.checkpoint_seconds);
    uint32_t first = 0;
    if (const std::optional<SlicePosition> resumed = checkpoint.resume())
    {
        first = resumed->next_item;
        out.resumed = true;
    }
    const uint64_t rays_per_texel = uint64_t(o.rays) + (lights.sun ? uint64_t(o.sun_rays) : 0);
    const uint32_t slice = uint32_t(std::clamp<uint64_t>((uint64_t(1) << 21) / rays_per_texel, 256, n));
    if (progress)
        progress({first, n, checkpoint.error()});
    const auto t0 = std::chrono::steady_clock::now();
    while (first < n)
    {
        const uint32_t last = std::min(n, first + slice);
        tbb::parallel_for(tbb::blocked_range<uint32_t>(first, last, 64), [&](const tbb::blocked_range<uint32_t>& r) {
            for (uint32_t i = r.begin(); i != r.end(); ++i)
                texel(i);
        });
        out.rays += uint64_t(last - first) * rays_per_texel;
        first = last;
        checkpoint.slice_done(0, first);
        if (progress)
            progress({first, n, checkpoint.error()});
    }
    out.trace_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.checkpoint_error = checkpoint.error();
    return out;
}

int lightmap_output_size(std::string_view name)
{
    if (name == "plain")
        return 1;
    if (name == "rnm")
        return 3;
    return math::basis(name).size; // throws, listing the bases
}

std::vector<glm::vec3> lightmap_coefficients(std::string_view name, const std::array<glm::vec3, 9>& e)
{
    if (name == "plain")
        return {math::sh9_eval_rgb(e, glm::vec3(0.0f, 0.0f, 1.0f))};
    if (name == "rnm")
    {
        std::vector<glm::vec3> out;
        for (const glm::vec3& b : math::rnm_basis())
            out.push_back(math::sh9_eval_rgb(e, b));
        return out;
    }
    const math::BasisDesc& basis = math::basis(name);
    if (basis.id == HEMI_BASIS_SH9)
        return std::vector<glm::vec3>(e.begin(), e.end());
    // The projection matrix depends only on the basis: computed once per basis (quadrature).
    static std::mutex lock;
    static std::vector<std::pair<int, std::vector<double>>> cache;
    const std::vector<double>* p = nullptr;
    {
        std::lock_guard<std::mutex> guard(lock);
        for (const auto& [id, m] : cache)
            if (id == basis.id)
                p = &m;
        if (!p)
        {
            cache.emplace_back(basis.id, math::projection_from_sh9(basis));
            p = &cache.back().second;
        }
    }
    std::vector<glm::vec3> out(size_t(basis.size), glm::vec3(0.0f));
    for (int k = 0; k < basis.size; ++k)
    {
        glm::dvec3 sum(0.0);
        for (int j = 0; j < 9; ++j)
            sum += (*p)[size_t(k) * 9 + size_t(j)] * glm::dvec3(e[size_t(j)]);
        out[size_t(k)] = glm::vec3(sum);
    }
    return out;
}

std::vector<float> lightmap_maps(std::string_view name, const LightmapAtlas& atlas, const LightmapSh& sh, int dilate)
{
    const int k = lightmap_output_size(name);
    const uint32_t w = atlas.width, h = atlas.height;
    const size_t plane = size_t(w) * h;
    std::vector<float> maps(size_t(k) * plane * 3, 0.0f);
    std::vector<uint8_t> filled(plane, 0);
    for (size_t i = 0; i < atlas.texels.size(); ++i)
    {
        const LightmapTexel& t = atlas.texels[i];
        const std::vector<glm::vec3> c = lightmap_coefficients(name, sh.irradiance[i]);
        const size_t at = size_t(t.y) * w + t.x;
        filled[at] = 1;
        for (int j = 0; j < k; ++j)
            for (int ch = 0; ch < 3; ++ch)
                maps[(size_t(j) * plane + at) * 3 + size_t(ch)] = c[size_t(j)][ch];
    }
    // Dilation, one ring per pass: an empty texel takes the mean of its filled 8-neighbours.
    for (int pass = 0; pass < dilate; ++pass)
    {
        std::vector<uint8_t> next = filled;
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
            {
                const size_t at = size_t(y) * w + x;
                if (filled[at])
                    continue;
                int count = 0;
                std::vector<double> sum(size_t(k) * 3, 0.0);
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                    {
                        const int64_t sx = int64_t(x) + dx, sy = int64_t(y) + dy;
                        if (sx < 0 || sy < 0 || sx >= int64_t(w) || sy >= int64_t(h))
                            continue;
                        const size_t from = size_t(sy) * w + size_t(sx);
                        if (!filled[from])
                            continue;
                        ++count;
                        for (int j = 0; j < k; ++j)
                            for (int ch = 0; ch < 3; ++ch)
                                sum[size_t(j) * 3 + size_t(ch)] += maps[(size_t(j) * plane + from) * 3 + size_t(ch)];
                    }
                if (!count)
                    continue;
                for (int j = 0; j < k; ++j)
                    for (int ch = 0; ch < 3; ++ch)
                        maps[(size_t(j) * plane + at) * 3 + size_t(ch)] = float(sum[size_t(j) * 3 + size_t(ch)] / count);
                next[at] = 1;
            }
        filled.swap(next);
    }
    return maps;
}

} // namespace hemi::bake
