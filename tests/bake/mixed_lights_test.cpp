// Mixed lights (issue 43): a light whose indirect light is baked and whose direct light is given at run time
// through a shadowmask. The references are the same scene fully baked, the disc's visible share over an edge
// of known height, and each light's falloff computed here.
#include "quads.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/io/material.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

using namespace hemi::bake;
using hemi::io::LightMode;
using hemi::io::Mesh;
using hemi::io::PunctualLight;
using hemi::test::add_quad;
using hemi::test::plane;

namespace
{

// A 2 x 2 floor with a wall 0.5 high on it at x = -0.2 (both sides), albedo 0.5, under a dim sky and a sun
// from the +x side: the wall shadows the floor behind it and the lit floor lights the wall back.
struct FloorAndWall
{
    Mesh mesh;
    std::vector<hemi::io::Material> materials;
    std::vector<hemi::io::Primitive> primitives;
    LightmapSurfaces surfaces;
    LightmapAtlas atlas;
    LightmapLights lights;

    FloorAndWall()
        : mesh(make_mesh()), materials{grey()}, primitives{{0, uint32_t(mesh.indices.size()), 0}},
          surfaces(mesh, materials, {}, primitives)
    {
        LightmapUvReport report;
        atlas = rasterize_lightmap(mesh, 64, 64, report);
        lights.uniform = glm::vec3(0.2f);
        lights.sun = true;
        lights.sun_direction = glm::normalize(glm::vec3(0.8f, 0.3f, 0.6f));
        lights.sun_irradiance = glm::vec3(3.0f, 2.0f, 1.0f);
    }
    static Mesh make_mesh()
    {
        Mesh m;
        hemi::test::add_floor_and_wall(m);
        return m;
    }
    static hemi::io::Material grey()
    {
        hemi::io::Material m;
        m.base_color_factor = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
        return m;
    }
};

float largest(const glm::vec3& v)
{
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

// Done-when line 1, its second half and (for a sun of one direction) its first: the lightmap of a mixed sun
// holds none of its direct light (with no bounces it is the bake without the sun, to the byte) and all of its
// bounces (what the fully baked sun adds over the mixed one is exactly the sun's direct light of the bake
// without bounces); the mixed sun's direct light at run time, its irradiance times its shadowmask channel
// times the cosine, added to the lightmap, gives the fully baked lightmap texel by texel: lit, shadowed and,
// for a sun of 5 degrees, penumbra texels. Fails if the mixed sun's direct light is added to the lightmap, if
// the bounces start from the lightmap without it, or if the shadowmask counts the wrong rays.
TEST(MixedLights, TheMixedSunsLightmapHoldsItsBouncesAndTheShadowmaskGivesBackItsDirectLight)
{
    FloorAndWall s;
    ASSERT_GT(s.atlas.texels.size(), 1500u);
    LightmapBakeOptions o;
    o.rays = 64;
    o.sun_rays = 64;
    for (const float diameter : {0.0f, 5.0f})
    {
        s.lights.sun_diameter_degrees = diameter;
        auto bake = [&](LightMode mode, bool sun, int bounces)
        {
            LightmapLights l = s.lights;
            l.sun = sun;
            l.sun_mode = mode;
            LightmapBakeOptions b = o;
            b.bounces = bounces;
            return bake_lightmap_sh(s.mesh, s.atlas, l, b, &s.surfaces);
        };
        const LightmapSh baked0 = bake(LightMode::Baked, true, 0), none0 = bake(LightMode::Baked, false, 0);
        const LightmapSh mixed0 = bake(LightMode::Mixed, true, 0);
        const LightmapSh baked1 = bake(LightMode::Baked, true, 1), mixed1 = bake(LightMode::Mixed, true, 1);
        const LightmapSh none1 = bake(LightMode::Baked, false, 1);
        ASSERT_EQ(mixed0.shadowmask.size(), s.atlas.texels.size());
        ASSERT_TRUE(baked0.shadowmask.empty());
        EXPECT_EQ(0, std::memcmp(mixed0.direct.data(), none0.direct.data(), none0.direct.size() * 48))
            << "without bounces, a mixed sun adds nothing to the lightmap";
        EXPECT_EQ(
            0, std::memcmp(mixed0.irradiance.data(), none0.irradiance.data(), none0.irradiance.size() * 108));
        int lit = 0, shadowed = 0, penumbra = 0, bounced = 0;
        for (size_t i = 0; i < s.atlas.texels.size(); ++i)
        {
            const LightmapTexel& t = s.atlas.texels[i];
            const float mask = mixed1.shadowmask[i][0];
            ASSERT_GE(mask, 0.0f);
            ASSERT_LE(mask, 1.0f);
            EXPECT_EQ(mixed1.shadowmask[i][1], 1.0f) << "no light in channel 1";
            lit += mask == 1.0f;
            shadowed += mask == 0.0f;
            penumbra += mask > 0.0f && mask < 1.0f;
            // The run time's direct light: the sun's irradiance, its channel, the cosine at the normal.
            const glm::vec3 run_time =
                s.lights.sun_irradiance * mask * std::max(glm::dot(t.normal, s.lights.sun_direction), 0.0f);
            const glm::vec3 sum = mixed1.direct[i][0] + run_time;
            const glm::vec3 full = baked1.direct[i][0];
            // A sun of 5 degrees (radius R): the bake's 64 random samples of the disc each have their own
            // cosine, the run time the centre's. Their mean is off by sin(angle) R / (2 sqrt 64) of the sun's
            // irradiance in one standard deviation (0.2% of it here); five of them. In a penumbra the visible
            // part of the disc has its centroid off the centre (a shadowmask's own error: a share, not a
            // direction): mask times that offset is at most 4 R / (3 pi) / 2 = 0.21 R, times sin(angle) of
            // the sun's irradiance (0.2% of it for a real sun of 0.53 degrees).
            const float cos_angle = std::max(glm::dot(t.normal, s.lights.sun_direction), 0.0f);
            const float sin_angle = std::sqrt(1.0f - cos_angle * cos_angle);
            const float r = 0.5f * diameter * float(M_PI) / 180.0f;
            const float tolerance = 2e-5f * std::max(1.0f, largest(full)) +
                                    (5.0f * sin_angle * r / (2.0f * std::sqrt(float(o.sun_rays))) +
                                     (mask > 0.0f && mask < 1.0f ? 0.22f * r * sin_angle : 0.0f)) *
                                        largest(s.lights.sun_irradiance);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(sum[c], full[c], tolerance)
                    << "diameter " << diameter << " texel " << i << " at " << t.position.x << ","
                    << t.position.y << "," << t.position.z << " mask " << mask << " channel " << c;
            // The bounces: what baking the sun adds over mixing it is its direct light alone.
            const glm::vec3 sun_direct = baked0.direct[i][0] - none0.direct[i][0];
            const glm::vec3 extra = baked1.direct[i][0] - mixed1.direct[i][0];
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(extra[c], sun_direct[c], 2e-5f * std::max(1.0f, largest(baked1.direct[i][0])))
                    << "texel " << i << " channel " << c;
            // And the mixed lightmap does hold the sun's bounce: above the bake without the sun.
            bounced += mixed1.direct[i][0].x > none1.direct[i][0].x + 0.01f;
        }
        std::printf("sun of %.0f deg: %d lit, %d shadowed, %d penumbra texels; %d texels lit by its bounce\n",
                    double(diameter), lit, shadowed, penumbra, bounced);
        EXPECT_GT(lit, 500);
        EXPECT_GT(shadowed, 100);
        EXPECT_GT(bounced, 400);
        if (diameter > 0.0f)
        {
            EXPECT_GT(penumbra, 20);
        }
    }
}

// Done-when line 1, its third half: the shadowmask's penumbra follows the sun's angular size over an edge of
// known height. A roof at z = 1 over x < 0 and a sun straight above: a floor point at x sees the fraction of
// the disc (angular radius R) beyond the roof's edge at the angle atan(x) from its centre, 1 - s(atan(x) / R)
// with s(t) = (acos t - t sqrt(1 - t^2)) / pi. The floor is a strip across the edge, 256 texels wide over
// 3 tan R either side, for a sun of 0.5 and of 5 degrees: its 10%-90% width is 6 mm and 60 mm. Each column
// of 16 texels (4096 rays each) within 0.02 of the share (ten standard deviations of the column's mean; the
// worst is 0.01), and the 10%-90% width within 3 texels. Fails for a mask that ignores the disc or takes its
// diameter for its radius.
TEST(MixedLights, TheShadowmasksPenumbraFollowsTheSunsAngularSize)
{
    for (const double diameter : {0.5, 5.0})
    {
        const double radius = 0.5 * diameter * M_PI / 180.0;
        const float half = float(3.0 * std::tan(radius));
        Mesh m;
        add_quad(m, {-half, -half / 8, 0}, {half, -half / 8, 0}, {half, half / 8, 0}, {-half, half / 8, 0},
                 {0.0f, 1.0f, 1.0f, 0.0f});
        add_quad(m, {-3, -3, 1}, {-3, 3, 1}, {0, 3, 1}, {0, -3, 1}, {0.0f, 0.0f, 0.1f, 0.0f}); // the roof
        LightmapUvReport report;
        const LightmapAtlas a = rasterize_lightmap(m, 256, 16, report);
        ASSERT_EQ(a.texels.size(), 256u * 16u);
        LightmapLights lights;
        lights.uniform = glm::vec3(0.0f);
        lights.sun = true;
        lights.sun_mode = LightMode::Mixed;
        lights.sun_direction = glm::vec3(0.0f, 0.0f, 1.0f);
        lights.sun_irradiance = glm::vec3(1.0f);
        lights.sun_diameter_degrees = float(diameter);
        LightmapBakeOptions o;
        o.rays = 1;
        o.sun_rays = 4096;
        const LightmapSh sh = bake_lightmap_sh(m, a, lights, o);
        std::vector<double> column(256, 0.0), x(256, 0.0);
        for (size_t i = 0; i < a.texels.size(); ++i)
        {
            column[a.texels[i].x] += double(sh.shadowmask[i][0]) / 16.0;
            x[a.texels[i].x] = double(a.texels[i].position.x);
        }
        double worst = 0.0, x10 = 0.0, x90 = 0.0;
        for (uint32_t c = 0; c < 256; ++c)
        {
            const double t = std::clamp(std::atan(x[c]) / radius, -1.0, 1.0);
            const double expected = 1.0 - (std::acos(t) - t * std::sqrt(1.0 - t * t)) / M_PI;
            worst = std::max(worst, std::abs(column[c] - expected));
            EXPECT_NEAR(column[c], expected, 0.02) << "sun of " << diameter << " deg, x = " << x[c];
            if (c > 0 && column[c - 1] < 0.1 && column[c] >= 0.1)
                x10 = x[c];
            if (c > 0 && column[c - 1] < 0.9 && column[c] >= 0.9)
                x90 = x[c];
        }
        // The analytic 10%-90% width: s(t) = 0.9 at t = -0.687, so 2 tan(0.687 R).
        const double width = 2.0 * std::tan(0.6870 * radius);
        std::printf(
            "sun of %.1f deg: penumbra 10%%-90%% %.3f mm (analytic %.3f mm), worst column off by %.4f\n",
            diameter, (x90 - x10) * 1e3, width * 1e3, worst);
        EXPECT_NEAR(x90 - x10, width, 3.0 * 2.0 * half / 256.0);
    }
}

// Done-when line 2: four mixed point lights that all reach the floor take the four channels; each channel
// holds its light's visibility past an occluder, so the four lights given at run time (their falloff computed
// here, times their channel and the cosine) plus the lightmap give the fully baked lightmap; a fifth light
// that reaches them is refused naming it, and lights whose ranges do not meet share a channel.
TEST(MixedLights, FourOverlappingLightsTakeFourChannelsAndAFifthIsRefusedByName)
{
    Mesh m = plane(4);
    // A small roof over the floor's middle, facing down, geometry only.
    add_quad(m, {-0.3f, -0.3f, 0.4f}, {-0.3f, 0.3f, 0.4f}, {0.3f, 0.3f, 0.4f}, {0.3f, -0.3f, 0.4f},
             {0.0f, 0.0f, 0.1f, 0.0f});
    LightmapUvReport report;
    const LightmapAtlas a = rasterize_lightmap(m, 32, 32, report);
    LightmapLights lights;
    lights.uniform = glm::vec3(0.0f);
    const glm::vec3 colours[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}};
    for (int l = 0; l < 4; ++l)
    {
        PunctualLight p;
        p.type = PunctualLight::Type::Point;
        p.name = "lamp" + std::to_string(l);
        p.color = colours[l];
        p.intensity = 2.0f;
        p.position = glm::vec3(l & 1 ? 0.5f : -0.5f, l & 2 ? 0.5f : -0.5f, 1.0f);
        p.mode = LightMode::Mixed;
        lights.punctual.push_back(p);
    }
    const std::vector<ShadowmaskChannel> channels = shadowmask_channels(lights);
    ASSERT_EQ(channels.size(), 4u);
    for (int l = 0; l < 4; ++l)
    {
        EXPECT_EQ(channels[size_t(l)].light, l);
        EXPECT_EQ(channels[size_t(l)].channel, l);
    }
    LightmapBakeOptions o;
    o.rays = 4;
    const LightmapSh mixed = bake_lightmap_sh(m, a, lights, o);
    LightmapLights all_baked = lights;
    for (PunctualLight& p : all_baked.punctual)
        p.mode = LightMode::Baked;
    const LightmapSh baked = bake_lightmap_sh(m, a, all_baked, o);
    int shadowed[4] = {};
    for (size_t i = 0; i < a.texels.size(); ++i)
    {
        const glm::dvec3 p(a.texels[i].position);
        glm::dvec3 run_time(0.0);
        for (int l = 0; l < 4; ++l)
        {
            const glm::dvec3 to = glm::dvec3(lights.punctual[size_t(l)].position) - p;
            const double d = glm::length(to);
            const double e = 2.0 / (d * d) * std::max(to.z / d, 0.0);
            const float mask = mixed.shadowmask[i][size_t(l)];
            ASSERT_TRUE(mask == 0.0f || mask == 1.0f) << "a point light's shadow is hard";
            shadowed[l] += mask == 0.0f;
            run_time += glm::dvec3(colours[l]) * e * double(mask);
        }
        const glm::dvec3 sum = glm::dvec3(mixed.direct[i][0]) + run_time;
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(sum[c], double(baked.direct[i][0][c]), 1e-4 * std::max(1.0, sum[c]))
                << "texel " << i << " channel " << c;
        EXPECT_EQ(glm::length(mixed.direct[i][0]), 0.0f) << "the lightmap holds no direct light";
    }
    for (int l = 0; l < 4; ++l)
        EXPECT_GT(shadowed[l], 20) << "light " << l << " casts the roof's shadow in its own channel";

    PunctualLight fifth = lights.punctual[0];
    fifth.name = "the fifth lamp";
    fifth.position = glm::vec3(0.0f, 0.0f, 2.0f);
    LightmapLights five = lights;
    five.punctual.push_back(fifth);
    try
    {
        shadowmask_channels(five);
        FAIL() << "a fifth overlapping mixed light was accepted";
    }
    catch (const std::invalid_argument& e)
    {
        const std::string what = e.what();
        EXPECT_NE(what.find("light 4 'the fifth lamp'"), std::string::npos) << what;
        EXPECT_NE(what.find("lamp3"), std::string::npos) << what;
    }
    EXPECT_THROW(bake_lightmap_sh(m, a, five, o), std::invalid_argument);
    // Ranges that do not meet: every light takes channel 0, and the fifth too.
    for (size_t l = 0; l < five.punctual.size(); ++l)
    {
        five.punctual[l].range = 1.0f;
        five.punctual[l].position = glm::vec3(3.0f * float(l), 0.0f, 1.0f);
    }
    for (const ShadowmaskChannel& c : shadowmask_channels(five))
        EXPECT_EQ(c.channel, 0);
    // A mixed sun reaches everywhere: it takes channel 0, and the lights channel 1.
    five.sun = true;
    five.sun_mode = LightMode::Mixed;
    const std::vector<ShadowmaskChannel> with_sun = shadowmask_channels(five);
    ASSERT_EQ(with_sun.size(), 6u);
    EXPECT_EQ(with_sun[0].light, -1);
    EXPECT_EQ(with_sun[0].channel, 0);
    for (size_t l = 1; l < with_sun.size(); ++l)
        EXPECT_EQ(with_sun[l].channel, 1);
}

// The light probes follow the modes: a mixed sun's direct light is the run time's, its bounce is the probes'.
// Baked with one bounce and a sun of one direction, the probes of the baked sun minus those of the mixed sun
// are, at every probe, either 0 (the sun hidden) or the SH9 of the sun's direct light alone, the same at
// every probe that sees it, whose constant coefficient is pi Y00 E (E / 4 at every normal). Fails if the
// probes add the mixed sun's direct light, or if they leave its direct light out of what their rays pick up
// from the surfaces (the difference would then hold the sun's bounce, which changes from probe to probe).
// Each probe's occlusion of the mixed sun (its channel R) is 1 where the difference is the sun's light and 0
// where it is none; the baked sun leaves the probes without occlusion.
TEST(MixedLights, LightProbesTakeAMixedSunsBounceButNotItsDirectLight)
{
    FloorAndWall s;
    s.lights.sun_diameter_degrees = 0.0f;
    LightmapBakeOptions o;
    o.rays = 32;
    o.sun_rays = 4;
    o.bounces = 1;
    LightmapLights mixed_lights = s.lights;
    mixed_lights.sun_mode = LightMode::Mixed;
    const LightmapSh baked = bake_lightmap_sh(s.mesh, s.atlas, s.lights, o, &s.surfaces);
    const LightmapSh mixed = bake_lightmap_sh(s.mesh, s.atlas, mixed_lights, o, &s.surfaces);
    hemi::io::LightProbes pb = probe_grid(s.mesh, glm::uvec3(4, 4, 2)), pm = pb;
    LightmapBakeOptions po = o;
    po.rays = 256;
    bake_light_probes(pb, s.mesh, s.atlas, baked, s.lights, po, &s.surfaces);
    bake_light_probes(pm, s.mesh, s.atlas, mixed, mixed_lights, po, &s.surfaces);
    const glm::vec3 constant = s.lights.sun_irradiance * float(M_PI * 0.28209479177387814);
    std::array<glm::vec3, 9> direct{};
    int hidden = 0, seen = 0;
    for (size_t j = 0; j < pb.irradiance.size(); ++j)
    {
        if (!pb.valid[j])
            continue;
        std::array<glm::vec3, 9> d;
        float size = 0.0f;
        for (size_t c = 0; c < 9; ++c)
        {
            d[c] = pb.irradiance[j][c] - pm.irradiance[j][c];
            size = std::max(size, largest(d[c]));
        }
        ASSERT_EQ(pm.occlusion.size(), pm.irradiance.size());
        EXPECT_EQ(pm.occlusion[j][0], size < 1e-4f ? 0.0f : 1.0f) << "probe " << j;
        EXPECT_EQ(pm.occlusion[j][1], 1.0f) << "no light in channel G";
        if (size < 1e-4f)
        {
            ++hidden;
            continue;
        }
        if (seen++ == 0)
        {
            direct = d;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(direct[0][c], constant[c], 1e-4f) << "the sun's constant term";
        }
        for (size_t c = 0; c < 9; ++c)
            for (int ch = 0; ch < 3; ++ch)
                ASSERT_NEAR(d[c][ch], direct[c][ch], 1e-4f) << "probe " << j << " coefficient " << c;
    }
    std::printf("%d probes see the sun, %d do not\n", seen, hidden);
    EXPECT_TRUE(pb.occlusion.empty());
    EXPECT_GT(seen, 4);
    EXPECT_GT(hidden, 0);
    EXPECT_THROW(
        {
            LightmapSh cut = mixed;
            cut.mixed_direct.pop_back();
            bake_light_probes(pm, s.mesh, s.atlas, cut, mixed_lights, po, &s.surfaces);
        },
        std::invalid_argument);
    // A shadowmask that does not match the texels is refused too, not read past its end.
    EXPECT_THROW(
        {
            LightmapSh cut = mixed;
            cut.shadowmask.pop_back();
            lightmap_maps("shadowmask", s.atlas, cut, 2);
        },
        std::invalid_argument);
}

// A bake in tiles (its sums on disk) keeps the mixed light's shadowmask and direct light in its tile file
// too, not in memory, each tile's in its place: the same bytes as the bake in memory, bounces included.
TEST(MixedLights, ABakeInTilesGivesTheSameShadowmaskAndLightmap)
{
    FloorAndWall s;
    s.lights.sun_mode = LightMode::Mixed;
    LightmapBakeOptions o;
    o.rays = 16;
    o.sun_rays = 8;
    o.bounces = 1;
    const LightmapSh whole = bake_lightmap_sh(s.mesh, s.atlas, s.lights, o, &s.surfaces);
    LightmapBakeOptions tiled = o;
    tiled.tile_texels = 300; // several tiles, the last one short
    tiled.tile_file = std::filesystem::temp_directory_path() / "hemi_mixed_tiles.bin";
    LightmapSh parts = bake_lightmap_sh(s.mesh, s.atlas, s.lights, tiled, &s.surfaces);
    ASSERT_GT(parts.tiles_count, 2u);
    EXPECT_TRUE(parts.shadowmask.empty());
    EXPECT_TRUE(parts.mixed_direct.empty());
    ASSERT_TRUE(parts.has_mixed());
    ASSERT_EQ(parts.texels(), whole.shadowmask.size());
    std::vector<std::array<float, 4>> mask(whole.shadowmask.size());
    std::vector<glm::vec3> direct(whole.mixed_direct.size());
    parts.read_mixed(0, uint32_t(mask.size()), mask.data(), direct.data());
    EXPECT_EQ(0, std::memcmp(mask.data(), whole.shadowmask.data(), whole.shadowmask.size() * 16));
    EXPECT_EQ(0, std::memcmp(direct.data(), whole.mixed_direct.data(), whole.mixed_direct.size() * 12));
    parts.load();
    EXPECT_EQ(0, std::memcmp(parts.shadowmask.data(), whole.shadowmask.data(), whole.shadowmask.size() * 16));
    EXPECT_EQ(0, std::memcmp(parts.direct.data(), whole.direct.data(), whole.direct.size() * 48));
    EXPECT_EQ(0,
              std::memcmp(parts.irradiance.data(), whole.irradiance.data(), whole.irradiance.size() * 108));
}

// A realtime light is not baked at all: neither its direct light nor its bounces, nor a shadowmask.
TEST(MixedLights, ARealtimeLightIsNotBaked)
{
    FloorAndWall s;
    LightmapBakeOptions o;
    o.rays = 16;
    o.sun_rays = 4;
    o.bounces = 1;
    LightmapLights realtime = s.lights, none = s.lights;
    realtime.sun_mode = LightMode::Realtime;
    none.sun = false;
    const LightmapSh a = bake_lightmap_sh(s.mesh, s.atlas, realtime, o, &s.surfaces);
    const LightmapSh b = bake_lightmap_sh(s.mesh, s.atlas, none, o, &s.surfaces);
    EXPECT_TRUE(a.shadowmask.empty());
    EXPECT_EQ(0, std::memcmp(a.direct.data(), b.direct.data(), b.direct.size() * 48));
    EXPECT_EQ(0, std::memcmp(a.irradiance.data(), b.irradiance.data(), b.irradiance.size() * 108));
}

} // namespace
