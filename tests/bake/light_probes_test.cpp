// Light probes that do not leak through walls (issue 44): each probe's depth map (io::LightProbes::depth)
// lets the lookup leave out the probes a point cannot see (Majercik et al. 2019). The scene is
// samples/light_probes' two rooms of 2 x 2 x 2 m side by side, sharing a wall 10 cm thick: the west room open
// to a sky and a sun that lights the shared wall, the east room closed. The references are the analytic
// darkness of the sealed room and probes baked exactly at the points looked up.
#include "two_rooms.h"

#include <hemi/io/light_probes.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <vector>

using glm::vec3;
using hemi::io::LightProbes;

using hemi::samples::received_light;
using hemi::samples::TwoRooms;
using hemi::samples::without_visibility;

// Issue 44, line 1: an object in the sealed dark room near the shared wall receives at most 1% of the light
// at the mirrored point of the sunlit room. The dark room's probes are exactly 0 (nothing reaches them), so
// everything the lookup gives there is leak; trilinear interpolation alone takes 11-45% of the lit side's
// light through the wall at these points (docs/probes.md).
TEST(LightProbes, NoLightLeaksThroughAWallIntoASealedRoom)
{
    const TwoRooms rooms(false, true);
    const glm::uvec3 count(8, 4, 4);
    const LightProbes probes = rooms.grid(count, 1024);
    ASSERT_EQ(probes.depth.size(), probes.size() * 64);
    for (size_t i = 0; i < probes.size(); ++i)
    {
        ASSERT_TRUE(probes.valid[i]) << "probe " << i;
        if (probes.position(i).x > 0.0f) // the sealed room is black
        {
            ASSERT_EQ(received_light(probes.irradiance[i]), 0.0) << "probe " << i;
        }
    }
    const LightProbes blind = without_visibility(probes);
    double worst = 0.0, worst_trilinear = 0.0;
    for (const float x : {0.1f, 0.2f, 0.3f})
        for (const float y : {0.3f, 1.0f, 1.7f})
            for (const float z : {0.3f, 1.0f, 1.7f})
            {
                const double lit = received_light(probes.at(vec3(-x, y, z)));
                ASSERT_GT(lit, 0.5) << "the sunlit room at " << -x << " " << y << " " << z;
                const double leak = received_light(probes.at(vec3(x, y, z))) / lit;
                const double leak_trilinear =
                    received_light(blind.at(vec3(x, y, z))) / received_light(blind.at(vec3(-x, y, z)));
                worst = std::max(worst, leak);
                worst_trilinear = std::max(worst_trilinear, leak_trilinear);
                EXPECT_LE(leak, 0.01)
                    << "at " << x << " " << y << " " << z << " (trilinear alone " << leak_trilinear << ")";
            }
    std::printf("dark room beside the sunlit one: at most %.2g of the lit side's light (trilinear alone: up "
                "to %.2f)\n",
                worst, worst_trilinear);
    EXPECT_GT(worst_trilinear, 0.1) << "the scene no longer shows the leak the lookup is there to stop";
}

// Issue 44, line 1: an object walking from the lit room through the door into the other changes light
// continuously, compared with probes baked exactly at the path's points 1 cm apart: no step of the lookup
// is larger than the reference's largest step between two points (measured 0.988 of it; trilinear alone,
// continuous by construction, 0.95). Visibility squared (not DDGI's cube, which steps 1.02 of it here)
// is what meets both this bound and the sealed room's 1% (docs/probes.md has the trade). A lookup that
// switches probes on and off where they stop seeing the point steps twice the reference's (0.040 against
// 0.019) and fails. With HEMI_PROBE_PATH set, writes the path (metres, reference, lookup, trilinear) there
// for docs/plots/probes_door.gp.
TEST(LightProbes, AnObjectWalkingThroughADoorChangesLightContinuously)
{
    const TwoRooms rooms(true, false);
    const glm::uvec3 count(8, 5, 4); // probes at y = 0.2, 0.6, 1.0, ...: behind the jambs and in the door
    const LightProbes probes = rooms.grid(count, 1024);
    const LightProbes blind = without_visibility(probes);
    // The path: diagonally through the door at 0.7 m, close past the jambs on either side (where the probes
    // behind them drop out of the blend), 2 m in 1 cm steps. The reference: a probe baked at each point
    // (4096 rays, the same directions at every point, so that its steps are the light's, not noise).
    constexpr int kPoints = 201;
    const vec3 from(-0.7071f, 0.2929f, 0.7f), to(0.7071f, 1.7071f, 0.7f);
    std::vector<double> reference(kPoints), lookup(kPoints), blended(kPoints);
    double reference_step = 0.0, lookup_step = 0.0, trilinear_step = 0.0, error = 0.0, trilinear_error = 0.0;
    for (int i = 0; i < kPoints; ++i)
    {
        const vec3 p = from + (to - from) * (float(i) / float(kPoints - 1));
        reference[size_t(i)] = received_light(rooms.probes(glm::uvec3(1), p, p, 4096, 0).irradiance[0]);
        lookup[size_t(i)] = received_light(probes.at(p));
        blended[size_t(i)] = received_light(blind.at(p));
        error += std::abs(lookup[size_t(i)] - reference[size_t(i)]) / kPoints;
        trilinear_error += std::abs(blended[size_t(i)] - reference[size_t(i)]) / kPoints;
        if (i > 0)
        {
            reference_step =
                std::max(reference_step, std::abs(reference[size_t(i)] - reference[size_t(i - 1)]));
            lookup_step = std::max(lookup_step, std::abs(lookup[size_t(i)] - lookup[size_t(i - 1)]));
            trilinear_step = std::max(trilinear_step, std::abs(blended[size_t(i)] - blended[size_t(i - 1)]));
        }
    }
    std::printf("through the door: largest step %.4f (reference's %.4f, trilinear alone %.4f), mean error "
                "%.4f (trilinear alone %.4f) of a lit side's %.3f\n",
                lookup_step, reference_step, trilinear_step, error, trilinear_error, reference.front());
    EXPECT_LE(lookup_step, reference_step);
    if (const char* out = std::getenv("HEMI_PROBE_PATH"))
    {
        std::ofstream f(out);
        f << "# metres along the path, reference, lookup, trilinear\n";
        for (int i = 0; i < kPoints; ++i)
            f << 0.01 * i << ' ' << reference[size_t(i)] << ' ' << lookup[size_t(i)] << ' '
              << blended[size_t(i)] << '\n';
    }
}
