// Reflection probes (issue 44; bake/reflection_probe.h): Heidrich & Seidel's parabolic maps of what a point
// of a lit level sees, from its finished lightmap. The reference is hemi's path tracer (bake/reference.h),
// which computes each surface's light itself, without the lightmap: a camera at the probe's centre sees, per
// pixel, the radiance the mirror map should hold in that direction. The scene: samples/light_probes' box
// room (box_room.h), 4 x 3 x 2.5 m, lit only by an emissive panel in its ceiling, walls of three colours so
// that a direction mapped wrongly shows.
#include "box_room.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/reference.h>
#include <hemi/bake/reflection_probe.h>
#include <hemi/io/gltf.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/box_projection.h>
#include <hemi/math/camera.h>
#include <hemi/math/luminance.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vector_relational.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

using namespace hemi;

namespace
{

using samples::BoxRoom;
constexpr glm::vec3 kBoxMin = samples::kBoxRoomMin, kBoxMax = samples::kBoxRoomMax;

// What the path tracer sees from `eye` towards `target` over a `size`^2 image of `fov` degrees: per pixel its
// direction and radiance (alpha 1: every path hit the room).
struct View
{
    std::vector<glm::vec3> directions, radiance;
    double noise = 0.0;
};
View trace(const BoxRoom& room, glm::vec3 eye, glm::vec3 target, uint32_t size, float fov, int rays)
{
    bake::ReferenceOptions o;
    o.width = o.height = size;
    o.auto_camera = false;
    o.camera = {eye, target, fov};
    o.model = glm::mat4(1.0f);
    o.rays = rays;
    o.bounces = 2;
    const bake::ReferenceImage image = bake::render_reference(room.mesh, room.surfaces, room.lights, o);
    const glm::mat4 inverse = glm::inverse(math::camera_ray_matrix(o.camera, 1.0f));
    View v;
    v.noise = image.noise;
    for (uint32_t y = 0; y < size; ++y)
        for (uint32_t x = 0; x < size; ++x)
        {
            const glm::vec2 ndc((x + 0.5f) / size * 2.0f - 1.0f, (y + 0.5f) / size * 2.0f - 1.0f);
            const glm::vec4 n = inverse * glm::vec4(ndc, 0.0f, 1.0f),
                            f = inverse * glm::vec4(ndc, 1.0f, 1.0f);
            v.directions.push_back(glm::normalize(glm::vec3(f) / f.w - glm::vec3(n) / n.w));
            const float* p = image.image.at(x, y);
            EXPECT_EQ(p[3], 1.0f) << "a path escaped the closed room";
            v.radiance.emplace_back(p[0], p[1], p[2]);
        }
    return v;
}

} // namespace

// Issue 44, line 3: the mirror map at the probe's centre equals the path-traced radiance seen from that
// point, direction by direction, over six views that cover most of the sphere.
TEST(ReflectionProbe, TheMirrorMapIsWhatThePathTracerSeesFromItsCentre)
{
    const BoxRoom room;
    const glm::vec3 centre(0.3f, -0.2f, 1.2f);
    bake::ReflectionProbeOptions o;
    o.size = 64;
    o.exponents = {10};
    const io::EnvmapAsset probe =
        bake::bake_reflection_probe(room.mesh, room.atlas, room.sh, room.lights, &room.surfaces, centre, o);
    // Away from the light's panel and a 25 cm band around it (where a pixel or a texel straddles the panel's
    // 4 and the ceiling's 0.3, and the map's texels, resampled and bilinear, and the tracer's box-filtered
    // pixels differ by whatever share each gives the panel), every channel's difference against the tracer's
    // own noise; and the panel's radiance well inside its edges.
    double squared = 0.0, noise = 0.0, bias = 0.0, level = 0.0, panel = 0.0, panel_reference = 0.0;
    size_t n = 0, panel_n = 0;
    for (const glm::vec3 towards :
         {glm::vec3(1, 0, 0.1f), glm::vec3(-1, 0, 0.1f), glm::vec3(0, 1, 0.1f), glm::vec3(0, -1, 0.1f),
          glm::vec3(0.3f, 0.2f, 1.0f), glm::vec3(-0.2f, 0.3f, -1.0f)})
    {
        const View v = trace(room, centre, centre + towards, 24, 80.0f, 1024);
        noise += v.noise * v.noise / 6.0;
        for (size_t i = 0; i < v.directions.size(); ++i)
        {
            const glm::vec3 d = v.directions[i], mirror(probe.mirror[0].sample(glm::dvec3(d)));
            // Where the direction meets the room (the box projection's exit point, seen from the centre).
            float t = 1e30f;
            for (int a = 0; a < 3; ++a)
                if (d[a] != 0.0f)
                    t = std::min(t, ((d[a] > 0.0f ? kBoxMax[a] : kBoxMin[a]) - centre[a]) / d[a]);
            const glm::vec3 q = centre + t * d;
            const bool ceiling = q.z > kBoxMax.z - 1e-3f;
            if (ceiling && std::abs(q.x) < 0.4f && std::abs(q.y) < 1.4f) // well inside the panel
            {
                panel += math::luminance(mirror);
                panel_reference += math::luminance(v.radiance[i]);
                ++panel_n;
            }
            if (ceiling && std::abs(q.x) < 0.75f) // the panel and a band around its edges
                continue;
            for (int c = 0; c < 3; ++c)
                squared += std::pow(mirror[c] - v.radiance[i][c], 2.0) / 3.0;
            bias += math::luminance(mirror - v.radiance[i]);
            level += math::luminance(v.radiance[i]);
            ++n;
        }
    }
    const double rms = std::sqrt(squared / n);
    std::printf(
        "mirror map against the path tracer over %zu directions: RMS difference %.4f, the tracer's noise "
        "%.4f; mean %.4f against %.4f; the light's panel %.3f against %.3f (%zu directions)\n",
        n, rms, std::sqrt(noise), (level + bias) / n, level / n, panel / panel_n, panel_reference / panel_n,
        panel_n);
    ASSERT_GT(n, 3000u);
    ASSERT_GT(panel_n, 20u);
    // The tracer's noise and little else (measured 1.03 of it); the mean within the lightmap's own agreement
    // with the tracer (2.7% brighter walls, the panel 2% darker: the lightmap's irradiance, not the probe).
    EXPECT_LT(rms, 1.25 * std::sqrt(noise));
    EXPECT_LT(std::abs(bias) / level, 0.04);
    EXPECT_NEAR(panel / panel_reference, 1.0, 0.03);
}

// Issue 44, line 3: a box-projected lookup (math::box_projected_direction) at an off-centre point of the box
// room matches the path-traced reflection there: for 40 directions spread over the sphere (the panel's edges
// left out, as above), the radiance along the direction from the point (the tracer's 4 x 4 pixels over 2
// degrees around it, 1024 paths each) against the probe's mirror map looked up towards where the direction
// leaves the room. Without the projection the same lookup sees the room from the probe's centre, 1.6 m away.
TEST(ReflectionProbe, ABoxProjectedLookupOffCentreSeesWhatThePointSees)
{
    const BoxRoom room;
    const glm::vec3 centre(0.3f, -0.2f, 1.2f), p(-1.2f, 0.7f, 0.6f);
    bake::ReflectionProbeOptions o;
    o.size = 64;
    o.exponents = {10};
    const io::EnvmapAsset probe =
        bake::bake_reflection_probe(room.mesh, room.atlas, room.sh, room.lights, &room.surfaces, centre, o);
    double projected = 0.0, plain = 0.0, level = 0.0;
    int n = 0;
    for (int i = 0; i < 40; ++i)
    {
        const double z = 1.0 - (i + 0.5) / 20.0, phi = i * 2.39996;
        const glm::vec3 r(float(std::sqrt(1 - z * z) * std::cos(phi)),
                          float(std::sqrt(1 - z * z) * std::sin(phi)), float(z));
        float t = 1e30f;
        for (int a = 0; a < 3; ++a)
            if (r[a] != 0.0f)
                t = std::min(t, ((r[a] > 0.0f ? kBoxMax[a] : kBoxMin[a]) - p[a]) / r[a]);
        const glm::vec3 q = p + t * r;
        if (q.z > kBoxMax.z - 1e-3f && std::abs(q.x) < 0.75f)
            continue; // the panel and its edges
        const View v = trace(room, p, p + r, 4, 2.0f, 1024);
        glm::vec3 seen(0.0f);
        for (const glm::vec3& c : v.radiance)
            seen += c / float(v.radiance.size());
        const glm::vec3 corrected(probe.mirror[0].sample(
            glm::dvec3(math::box_projected_direction(p, r, kBoxMin, kBoxMax, centre))));
        const glm::vec3 uncorrected(probe.mirror[0].sample(glm::dvec3(r)));
        projected += std::pow(math::luminance(corrected - seen), 2.0);
        plain += std::pow(math::luminance(uncorrected - seen), 2.0);
        level += math::luminance(seen);
        ++n;
    }
    const double mean = level / n, rms = std::sqrt(projected / n), rms_plain = std::sqrt(plain / n);
    std::printf(
        "box-projected reflection at %d directions: RMS difference %.4f (%.1f%% of the mean %.3f), without "
        "the projection %.4f (%.1f%%)\n",
        n, rms, 100.0 * rms / mean, mean, rms_plain, 100.0 * rms_plain / mean);
    ASSERT_GE(n, 25);
    EXPECT_LT(rms, 0.1 * mean);
    EXPECT_GT(rms_plain, 2.0 * rms);
}

// hemi-bake lightmap's job (bake_lightmap_file, --reflection-probe) bakes reflection probes into the asset:
// one over the scene's bounds (no box given), one with its own box; each probe's mirror map sees the
// ceiling's panel's middle (emission 4 and its bounce) and the floor below (about 0.2).
TEST(ReflectionProbe, TheLightmapJobBakesThemIntoTheAsset)
{
    const BoxRoom room;
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "hemi_reflection_probe_test";
    std::filesystem::create_directories(dir);
    io::GltfScene scene;
    scene.mesh = room.mesh;
    scene.materials = room.materials;
    scene.primitives = room.primitives;
    io::write_gltf(dir / "room.glb", scene);
    bake::LightmapFileOptions o;
    o.width = o.height = 128;
    o.outputs = {"plain"};
    o.bake.rays = 64;
    o.bake.bounces = 1;
    o.lights.uniform = glm::vec3(0.0f);
    const glm::vec3 centre(0.3f, -0.2f, 1.2f);
    const glm::vec3 corner(1.5f, 1.0f, 0.5f); // a second probe elsewhere, with its own box
    o.reflection_probes = {{centre}, {corner, glm::vec3(-1.0f, -1.0f, 0.0f), glm::vec3(1.8f, 1.4f, 2.5f)}};
    o.reflection.size = 32;
    o.reflection.rays = 4;
    o.reflection.exponents = {10};
    const bake::LightmapBakeSummary summary =
        bake::bake_lightmap_file(dir / "room.glb", dir / "room.hemi", o);
    EXPECT_EQ(summary.reflection_probes, 2u);
    const io::LightmapAsset a = io::read_lightmap_asset(dir / "room.hemi");
    ASSERT_EQ(a.reflections.size(), 2u);
    EXPECT_EQ(a.reflections[0].centre, centre);
    // The scene's bounds, padded by 0.1% of their diagonal.
    EXPECT_NEAR(glm::distance(a.reflections[0].box_min, kBoxMin), 0.0f, 0.02f);
    EXPECT_NEAR(glm::distance(a.reflections[0].box_max, kBoxMax), 0.0f, 0.02f);
    EXPECT_TRUE(glm::all(glm::lessThan(a.reflections[0].box_min, kBoxMin)));
    EXPECT_EQ(a.reflections[1].centre, corner);
    EXPECT_EQ(a.reflections[1].box_min, glm::vec3(-1.0f, -1.0f, 0.0f));
    EXPECT_EQ(a.reflections[1].box_max, glm::vec3(1.8f, 1.4f, 2.5f));
    // Each probe sees the panel's middle from its own centre; from the other's, that direction meets the
    // grey ceiling (or a wall) instead.
    for (size_t i = 0; i < 2; ++i)
    {
        const io::ReflectionProbe& p = a.reflections[i];
        EXPECT_EQ(p.maps.mirror[0].size, 32u);
        const glm::vec3 panel(0.0f, 0.0f, 2.5f);
        const glm::dvec3 own = glm::normalize(glm::dvec3(panel - p.centre)),
                         other = glm::normalize(glm::dvec3(panel - a.reflections[1 - i].centre));
        EXPECT_GT(math::luminance(glm::vec3(p.maps.mirror[0].sample(own))), 3.8f) << i;
        EXPECT_LT(math::luminance(glm::vec3(p.maps.mirror[0].sample(other))), 1.0f) << i;
        EXPECT_LT(math::luminance(glm::vec3(p.maps.mirror[0].sample(glm::dvec3(0, 0, -1)))), 0.5f) << i;
    }
    std::filesystem::remove_all(dir);
}

// The influence that blends overlapping probes (math::box_influence), worked out here: 1 deeper than the fade
// inside every face, a third of it 0.1 inside one face with a fade of 0.3, 0 on and beyond a face; with no
// fade, 1 inside and 0 outside. Two boxes overlapping by 0.6 along x, each fading over 0.3, cross over
// continuously.
TEST(ReflectionProbe, OverlappingProbesBlendByTheirBoxesInfluence)
{
    const glm::vec3 lo(0.0f), hi(2.0f, 1.0f, 1.0f);
    EXPECT_FLOAT_EQ(math::box_influence(glm::vec3(1.0f, 0.5f, 0.5f), lo, hi, 0.3f), 1.0f);
    EXPECT_NEAR(math::box_influence(glm::vec3(1.9f, 0.5f, 0.5f), lo, hi, 0.3f), 1.0f / 3.0f, 1e-6f);
    EXPECT_NEAR(math::box_influence(glm::vec3(1.0f, 0.5f, 0.95f), lo, hi, 0.3f), 0.05f / 0.3f, 1e-6f);
    EXPECT_EQ(math::box_influence(glm::vec3(2.0f, 0.5f, 0.5f), lo, hi, 0.3f), 0.0f);
    EXPECT_EQ(math::box_influence(glm::vec3(2.5f, 0.5f, 0.5f), lo, hi, 0.3f), 0.0f);
    EXPECT_EQ(math::box_influence(glm::vec3(1.99f, 0.5f, 0.5f), lo, hi, 0.0f), 1.0f);
    EXPECT_EQ(math::box_influence(glm::vec3(2.01f, 0.5f, 0.5f), lo, hi, 0.0f), 0.0f);
    // Box a [0, 2] and box b [1.4, 3.4] along x: b's share of the blend rises from 0 to 1 over the overlap.
    float previous = 0.0f;
    for (int i = 0; i <= 300; ++i)
    {
        const glm::vec3 p(1.0f + 0.005f * i, 0.5f, 0.5f);
        const float a = math::box_influence(p, lo, hi, 0.3f),
                    b = math::box_influence(p, glm::vec3(1.4f, 0.0f, 0.0f), glm::vec3(3.4f, 1.0f, 1.0f),
                                            0.3f);
        ASSERT_GT(a + b, 0.0f) << p.x;
        const float share = b / (a + b);
        EXPECT_LE(std::abs(share - previous), 0.02f) << p.x;
        previous = share;
    }
    EXPECT_FLOAT_EQ(previous, 1.0f);
}
