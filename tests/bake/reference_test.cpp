// The reference tracer (hemi-bake reference) against analytic cases: the irradiance of a plane at a
// normal-map normal under uniform radiance (the visible part of the tilted hemisphere) and under one sun (the
// cosine, which also pins the tangent frame's handedness), and a closed emissive box whose bounces add a
// geometric series. Every expected value is computed here from the geometry, not by the tracer's code.
#include "quads.h"

#include <hemi/bake/reference.h>
#include <hemi/io/image.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <glm/exponential.hpp>
#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>

using namespace hemi::bake;
using hemi::io::Mesh;

namespace
{

// A material whose normal texture is one texel (r, g, b) everywhere.
struct FlatNormalMap
{
    std::vector<hemi::io::Material> materials;
    std::vector<hemi::io::EncodedImage> images;
    glm::vec3 tangent_normal; // decoded here: (2c / 255 - 1), normalised (scale 1)

    FlatNormalMap(uint8_t r, uint8_t g, uint8_t b, glm::vec3 albedo = glm::vec3(1.0f))
    {
        hemi::io::ImageRgba8 texel{4, 4, {}};
        for (int i = 0; i < 16; ++i)
            texel.pixels.insert(texel.pixels.end(), {r, g, b, 255});
        images.push_back({"flat normal", "image/png", hemi::io::encode_png(texel)});
        hemi::io::Material m;
        m.base_color_factor = glm::vec4(albedo, 1.0f);
        m.normal.image = 0;
        materials.push_back(m);
        tangent_normal = glm::normalize(
            glm::vec3(2.0f * r / 255.0f - 1.0f, 2.0f * g / 255.0f - 1.0f, 2.0f * b / 255.0f - 1.0f));
    }
};

// The plane z = 0 over [-1, 1]^2 (tangent +x, bitangent +y, normal +z) seen from straight above.
ReferenceOptions above(int rays)
{
    ReferenceOptions o;
    o.width = o.height = 24;
    o.auto_camera = false;
    o.camera.eye = glm::vec3(0.0f, 0.0f, 2.5f);
    o.camera.target = glm::vec3(0.0f);
    o.model = glm::mat4(1.0f);
    o.rays = rays;
    o.white = true;
    return o;
}

} // namespace

// Under uniform radiance 1 an open plane's irradiance at a normal tilted by theta from its own normal is
// pi (1 + cos theta) / 2: the tilted hemisphere loses the lune below the plane. White pixels show E / pi. The
// noise estimate agrees with the pixels' actual scatter about the analytic value (within a factor 1.5).
TEST(Reference, TiltedNormalUnderUniformRadianceSeesTheHemisphereAboveThePlane)
{
    const Mesh m = hemi::test::plane(2);
    const std::vector<hemi::io::Primitive> primitives = {{0, uint32_t(m.indices.size()), 0}};
    for (const uint8_t tilt : {170, 200, 240})
    {
        const FlatNormalMap map(tilt, 128, 200);
        const LightmapSurfaces surfaces(m, map.materials, map.images, primitives);
        LightmapLights lights; // uniform radiance 1
        const ReferenceImage r = render_reference(m, surfaces, lights, above(512));
        const double expected = (1.0 + double(map.tangent_normal.z)) / 2.0;
        double sum = 0.0, squared = 0.0, worst = 0.0;
        int covered = 0;
        for (uint32_t y = 0; y < 24; ++y)
            for (uint32_t x = 0; x < 24; ++x)
            {
                const float* p = r.image.at(x, y);
                if (p[3] < 1.0f)
                    continue;
                ++covered;
                for (int c = 0; c < 3; ++c)
                {
                    sum += p[c];
                    squared += (p[c] - expected) * (p[c] - expected);
                    worst = std::max(worst, std::abs(p[c] - expected));
                }
            }
        ASSERT_GT(covered, 200);
        // The mean over the pixels: unbiased to 0.1%; every pixel within 5 of the reported standard errors.
        EXPECT_NEAR(sum / (3.0 * covered), expected, 1e-3 * expected) << "tilt " << int(tilt);
        EXPECT_LT(worst, 5.0 * r.noise) << "tilt " << int(tilt);
        const double scatter = std::sqrt(squared / (3.0 * covered));
        EXPECT_GT(r.noise, scatter / 1.5) << "tilt " << int(tilt);
        EXPECT_LT(r.noise, scatter * 1.5) << "tilt " << int(tilt);
        EXPECT_LT(r.noise, 0.01) << "tilt " << int(tilt);
    }
}

// One sun of irradiance 1 and no sky: a pixel shows max(0, n'.d) / pi at the normal-map normal n'. A tilt
// towards +x in the map (the tangent) faces a sun on the +x side, one towards +y (up the image: the
// bitangent, glTF's convention) a sun on the +y side; the opposite tilt turns away from it.
TEST(Reference, SunLightsTheNormalMapNormalInTheTangentFrame)
{
    const Mesh m = hemi::test::plane(2);
    const std::vector<hemi::io::Primitive> primitives = {{0, uint32_t(m.indices.size()), 0}};
    struct Case
    {
        uint8_t r, g, b;
        glm::vec3 sun;
    };
    const Case cases[] = {
        {220, 128, 200, {0.8f, 0.0f, 0.6f}}, // towards the sun along the tangent
        {36, 128, 200, {0.8f, 0.0f, 0.6f}},  // away from it
        {128, 220, 200, {0.0f, 0.8f, 0.6f}}, // towards the sun along the bitangent
        {128, 36, 200, {0.0f, 0.8f, 0.6f}},  // away from it
    };
    for (const Case& k : cases)
    {
        const FlatNormalMap map(k.r, k.g, k.b);
        const LightmapSurfaces surfaces(m, map.materials, map.images, primitives);
        LightmapLights lights;
        lights.uniform = glm::vec3(0.0f);
        lights.sun = true;
        lights.sun_direction = k.sun;
        lights.sun_irradiance = glm::vec3(1.0f);
        lights.sun_diameter_degrees = 0.0f;
        const ReferenceImage r = render_reference(m, surfaces, lights, above(8));
        // The plane's tangent frame is the world's: n' is the decoded texel itself.
        const double expected = std::max(0.0f, glm::dot(map.tangent_normal, glm::normalize(k.sun))) / M_PI;
        int covered = 0;
        for (uint32_t y = 0; y < 24; ++y)
            for (uint32_t x = 0; x < 24; ++x)
                if (r.image.at(x, y)[3] == 1.0f)
                {
                    ++covered;
                    ASSERT_NEAR(r.image.at(x, y)[1], expected, 1e-5)
                        << int(k.r) << "," << int(k.g) << " (" << x << ", " << y << ")";
                }
        ASSERT_GT(covered, 200);
    }
}

// Inside a closed box whose every surface emits radiance 1 with albedo 0.5, a path of B bounces sees
// E / pi = sum_{k=0..B} 0.5^k, exactly (every path hits a wall). The camera looks in from outside: the near
// walls' backs are culled, as the rasteriser does, and the colour view shows emission + albedo E / pi.
TEST(Reference, ClosedBoxFurnaceAddsEachBounce)
{
    const Mesh m = hemi::test::unit_box(true); // facing into the box
    std::vector<hemi::io::Material> materials(1);
    materials[0].base_color_factor = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
    materials[0].emissive_factor = glm::vec3(1.0f);
    const std::vector<hemi::io::Primitive> primitives = {{0, uint32_t(m.indices.size()), 0}};
    const LightmapSurfaces surfaces(m, materials, {}, primitives);
    LightmapLights lights;
    lights.uniform = glm::vec3(0.0f);
    for (int bounces : {0, 1, 3})
        for (bool white : {true, false})
        {
            ReferenceOptions o;
            o.width = o.height = 16;
            o.model = glm::mat4(1.0f);
            o.rays = 16;
            o.bounces = bounces;
            o.white = white;
            const ReferenceImage r = render_reference(m, surfaces, lights, o);
            double e = 0.0;
            for (int k = 0; k <= bounces; ++k)
                e += std::pow(0.5, k);
            const double expected = white ? e : 1.0 + 0.5 * e;
            int covered = 0;
            for (uint32_t y = 0; y < 16; ++y)
                for (uint32_t x = 0; x < 16; ++x)
                    if (r.image.at(x, y)[3] == 1.0f)
                    {
                        ++covered;
                        ASSERT_NEAR(r.image.at(x, y)[0], expected, 1e-4 * expected) << bounces << " bounces";
                    }
            EXPECT_GT(covered, 100) << "the box fills the auto camera's view";
            EXPECT_LT(r.noise, 1e-4);
        }
}

// The closed box per channel, with colour and textures: walls that emit em and reflect albedo a give, along a
// path of B bounces, E / pi = em sum_{k=0..B} a^k (the white view) and em + a E / pi (the colour view), in
// each channel. A coloured albedo factor (0.8, 0.5, 0.2) under a coloured emissive factor; then a base colour
// texture of sRGB (128, 200, 32) under the factor (0.9, 0.8, 1) and an emissive texture of sRGB
// (255, 128, 64) under the factor (0.5, 1, 2), decoded here (128 is 0.2158; read as linear, 0.502).
TEST(Reference, ColouredAndTexturedClosedBoxPerChannel)
{
    const Mesh m = hemi::test::unit_box(true);
    const std::vector<hemi::io::Primitive> primitives = {{0, uint32_t(m.indices.size()), 0}};
    LightmapLights lights;
    lights.uniform = glm::vec3(0.0f);
    const uint8_t base[3] = {128, 200, 32}, emissive[3] = {255, 128, 64};
    const hemi::test::ColouredMaterial coloured({0.8f, 0.5f, 0.2f}, {1.0f, 2.0f, 0.5f});
    const hemi::test::ColouredMaterial textured({0.9f, 0.8f, 1.0f}, {0.5f, 1.0f, 2.0f}, base, emissive);
    for (const hemi::test::ColouredMaterial* mat : {&coloured, &textured})
    {
        const LightmapSurfaces surfaces(m, mat->materials, mat->images, primitives);
        for (int bounces : {0, 2})
            for (bool white : {true, false})
            {
                ReferenceOptions o;
                o.width = o.height = 12;
                o.model = glm::mat4(1.0f);
                o.rays = 8;
                o.bounces = bounces;
                o.white = white;
                const ReferenceImage r = render_reference(m, surfaces, lights, o);
                glm::dvec3 e(0.0);
                for (int k = 0; k <= bounces; ++k)
                    e += mat->emission * glm::pow(mat->albedo, glm::dvec3(k));
                const glm::dvec3 expected = white ? e : mat->emission + mat->albedo * e;
                int covered = 0;
                for (uint32_t y = 0; y < 12; ++y)
                    for (uint32_t x = 0; x < 12; ++x)
                        if (r.image.at(x, y)[3] == 1.0f)
                        {
                            ++covered;
                            for (int c = 0; c < 3; ++c)
                                ASSERT_NEAR(r.image.at(x, y)[c], expected[c], 1e-4 * expected[c])
                                    << (mat == &textured ? "textured" : "coloured") << " " << bounces
                                    << " bounces, white " << white << ", channel " << c;
                        }
                EXPECT_GT(covered, 50);
            }
    }
}

// The same seed gives the same bytes on one thread and on all of them; bad options are refused.
TEST(Reference, SameSeedSameBytesAndBadOptionsAreRefused)
{
    const Mesh m = hemi::test::plane(2);
    const FlatNormalMap map(200, 90, 200, glm::vec3(0.8f, 0.5f, 0.3f));
    const std::vector<hemi::io::Primitive> primitives = {{0, uint32_t(m.indices.size()), 0}};
    const LightmapSurfaces surfaces(m, map.materials, map.images, primitives);
    LightmapLights lights;
    lights.sun = true;
    lights.sun_direction = glm::vec3(0.3f, 0.2f, 1.0f);
    lights.sun_irradiance = glm::vec3(2.0f);
    ReferenceOptions o = above(32);
    o.white = false;
    const ReferenceImage all = render_reference(m, surfaces, lights, o);
    ReferenceImage one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = render_reference(m, surfaces, lights, o);
    }
    ASSERT_EQ(all.image.pixels.size(), one.image.pixels.size());
    EXPECT_EQ(std::memcmp(all.image.pixels.data(), one.image.pixels.data(),
                          all.image.pixels.size() * sizeof(float)),
              0);
    o.seed = 2;
    const ReferenceImage other = render_reference(m, surfaces, lights, o);
    EXPECT_NE(std::memcmp(all.image.pixels.data(), other.image.pixels.data(),
                          all.image.pixels.size() * sizeof(float)),
              0);

    ReferenceOptions bad = above(1);
    EXPECT_THROW(render_reference(m, surfaces, lights, bad), std::invalid_argument)
        << "one path gives no noise estimate";
    bad = above(8);
    bad.bounces = 17;
    EXPECT_THROW(render_reference(m, surfaces, lights, bad), std::invalid_argument);
    bad = above(8);
    bad.width = 0;
    EXPECT_THROW(render_reference(m, surfaces, lights, bad), std::invalid_argument);
    bad = above(8);
    bad.camera.eye = bad.camera.target;
    EXPECT_THROW(render_reference(m, surfaces, lights, bad), std::invalid_argument);
    LightmapLights nan = lights;
    nan.sun_irradiance.x = NAN;
    EXPECT_THROW(render_reference(m, surfaces, nan, above(8)), std::invalid_argument);
}

namespace
{
// GGX (Smith height-correlated, Schlick) times n.l, written out here from its definition (math/ggx.h).
double ggx_cos(const glm::dvec3& n, const glm::dvec3& l, const glm::dvec3& v, double roughness, double f0)
{
    const double nl = glm::dot(n, l), nv = glm::dot(n, v);
    if (nl <= 0.0 || nv <= 0.0)
        return 0.0;
    const glm::dvec3 h = glm::normalize(l + v);
    const double a2 = std::pow(roughness, 4.0), nh = glm::dot(n, h);
    const double d = a2 / (M_PI * std::pow(nh * nh * (a2 - 1.0) + 1.0, 2.0));
    const double g2 = 2.0 * nl * nv /
                      (nv * std::sqrt(a2 + (1.0 - a2) * nl * nl) + nl * std::sqrt(a2 + (1.0 - a2) * nv * nv));
    const double f = f0 + (1.0 - f0) * std::pow(1.0 - glm::dot(v, h), 5.0);
    return d * g2 * f / (4.0 * nl * nv) * nl;
}

// A 4 x 4 view of the plane from far away along `towards_eye` (2000 units away, 0.01 degrees across: one
// view direction to 1e-4).
ReferenceOptions far_view(const glm::dvec3& towards_eye, int rays, double roughness, double f0)
{
    ReferenceOptions o = above(rays);
    o.width = o.height = 4;
    o.camera.eye = glm::vec3(towards_eye * 2000.0);
    o.camera.fov_y_degrees = 0.01f;
    o.roughness = roughness;
    o.f0 = f0;
    return o;
}
} // namespace

// The GGX coat (hemi-bake reference --roughness) against its definition: under one point-like sun a pixel is
// max(0, n'.l) / pi plus E times GGX (n'.l) at the normal-map normal (5e-4: float directions from a camera
// 2000 units away; the sun is sampled as a light),
// and under uniform radiance 1 with roughness 1 and f0 1 (D = 1 / pi, V = 1 / (2 (n.l + n.v)), F = 1) the
// coat adds 1 - c ln((1 + c) / c) for c = n.v (the lobe sampled from GGX: the mean over 16 pixels within
// 0.2%). A Fresnel on n.v, an uncorrelated Smith term or a lobe drawn without its pdf fails.
TEST(Reference, GgxCoatAddsItsBrdfUnderOneSunAndItsAlbedoUnderAUniformSky)
{
    const Mesh m = hemi::test::plane(2);
    const std::vector<hemi::io::Primitive> primitives = {{0, uint32_t(m.indices.size()), 0}};
    const FlatNormalMap map(150, 120, 240);
    const LightmapSurfaces surfaces(m, map.materials, map.images, primitives);
    const glm::dvec3 n(map.tangent_normal);
    for (const glm::dvec3& eye : {glm::dvec3(0.6, -0.2, 0.77), glm::dvec3(-0.3, 0.5, 0.81)})
    {
        const glm::dvec3 v = glm::normalize(eye);
        LightmapLights sun;
        sun.uniform = glm::vec3(0.0f);
        sun.sun = true;
        sun.sun_direction = glm::vec3(-0.5f, 0.2f, 0.84f);
        sun.sun_irradiance = glm::vec3(2.0f);
        sun.sun_diameter_degrees = 0.0f;
        const glm::dvec3 l = glm::normalize(glm::dvec3(sun.sun_direction));
        const ReferenceImage lit = render_reference(m, surfaces, sun, far_view(v, 8, 0.45, 0.3));
        const double expected = 2.0 * (std::max(0.0, glm::dot(n, l)) / M_PI + ggx_cos(n, l, v, 0.45, 0.3));
        for (uint32_t i = 0; i < 16; ++i)
            ASSERT_NEAR(lit.image.pixels[i * 4 + 1], expected, 5e-4 * expected) << "pixel " << i;

        // The closed form integrates over the whole hemisphere of the normal: a flat normal map, so that the
        // plane clips none of it (a tilted one loses 0.4% of the coat below the plane).
        LightmapLights sky; // uniform radiance 1
        const FlatNormalMap flat(128, 128, 255);
        const LightmapSurfaces flat_surfaces(m, flat.materials, flat.images, primitives);
        const ReferenceImage white = render_reference(m, flat_surfaces, sky, far_view(v, 4096, 1.0, 1.0));
        const double c = glm::dot(glm::dvec3(flat.tangent_normal), v);
        const double coat = 1.0 - c * std::log((1.0 + c) / c);
        const double diffuse = (1.0 + double(flat.tangent_normal.z)) / 2.0;
        double mean = 0.0;
        for (uint32_t i = 0; i < 16; ++i)
            mean += white.image.pixels[i * 4 + 1] / 16.0;
        EXPECT_NEAR(mean, diffuse + coat, 2e-3 * (diffuse + coat)) << "view " << eye.x;
    }
}
