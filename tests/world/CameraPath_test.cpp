// CameraPath_test.cpp — drive, fly and static paths: exact speed, on the road, above the
// terrain, cuts flagged, orientation orthonormal, bad settings rejected.
#include "world/CameraPath.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Error.h"
#include "world/World.h"

namespace amb {
namespace {

const World& defaultWorld() {
    static const World world{WorldSettings{}};
    return world;
}

void expectOrthonormal(const CameraSample& s) {
    ASSERT_NEAR(glm::length(s.forward), 1.0, 1e-9);
    ASSERT_NEAR(glm::length(s.up), 1.0, 1e-9);
    ASSERT_NEAR(glm::dot(s.forward, s.up), 0.0, 1e-9);
    ASSERT_GT(s.up.y, 0.0);
}

// Horizontal distance from (x, z) to a road's centreline polyline.
double distanceToRoad(const Road& road, const glm::dvec3& p) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i + 1 < road.centreline.size(); ++i) {
        const glm::dvec2 a(road.centreline[i].x, road.centreline[i].z);
        const glm::dvec2 b(road.centreline[i + 1].x, road.centreline[i + 1].z);
        const glm::dvec2 q(p.x, p.z);
        const double t = std::clamp(glm::dot(q - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
        best = std::min(best, glm::length(q - (a + t * (b - a))));
    }
    return best;
}

TEST(CameraPath, DriveHasExactSpeedAndStaysOnTheRoad) {
    const World& world = defaultWorld();
    DriveSettings d;
    d.road = "highway";
    d.speed_mps = 30.0;
    d.duration_s = 60.0;
    d.step_s = 1.0 / 60.0;
    d.laneOffset_m = 2.0;
    d.startDistance_m = 500.0;
    const std::vector<CameraSample> path = makeDrivePath(world, d);
    ASSERT_EQ(path.size(), 3601u);
    const Road& road = *world.roads().find("highway");
    for (std::size_t k = 0; k < path.size(); ++k) {
        const CameraSample& s = path[k];
        EXPECT_NEAR(s.time_s, double(k) * d.step_s, 1e-12);
        EXPECT_FALSE(s.cut);
        expectOrthonormal(s);
        if (k > 0) {
            const double chord = glm::length(s.position_m - path[k - 1].position_m);
            ASSERT_NEAR(chord, d.speed_mps * d.step_s, 1e-6 * d.speed_mps * d.step_s) << k;
        }
        if (k % 10 == 0) {
            // On the road, in the lane, at eye height above the road surface and the terrain.
            const double off = distanceToRoad(road, s.position_m);
            EXPECT_LT(off, road.halfWidth_m) << k;
            EXPECT_NEAR(off, d.laneOffset_m, 0.1) << k;
            const auto q = world.roads().nearest(s.position_m.x, s.position_m.z, road.halfWidth_m);
            ASSERT_TRUE(q.has_value());
            EXPECT_NEAR(s.position_m.y - q->surfaceHeight_m, d.eyeHeight_m, 0.1) << k;
            EXPECT_NEAR(s.position_m.y - world.height(s.position_m.x, s.position_m.z),
                        d.eyeHeight_m, 0.25)
                << k;
            // Looking along the road, in the direction of travel.
            const glm::dvec3 t = road.tangentAt(q->along_m);
            EXPECT_GT(glm::dot(s.forward, t), 0.9) << k;
        }
    }
    // The drive started where asked: startDistance_m along the road, offset into the lane.
    EXPECT_NEAR(glm::length(glm::dvec2(path[0].position_m.x, path[0].position_m.z) -
                            glm::dvec2(road.pointAt(500.0).x, road.pointAt(500.0).z)),
                d.laneOffset_m, 0.1);
}

TEST(CameraPath, DriveSlowsInCurvesWithinTheAccelerationBound) {
    const World& world = defaultWorld();
    DriveSettings d;
    d.road = "mountain";
    d.speed_mps = 20.0;
    d.maxLateralAccel_mps2 = 1.0;  // 16 m/s in curves of radius 256 m
    d.maxSpeedChange_mps2 = 2.0;
    d.reverse = true;  // downhill from the top
    d.duration_s = 120.0;
    const std::vector<CameraSample> path = makeDrivePath(world, d);
    double slowest = 1e9, fastest = 0.0, previous = -1.0, biggestChange = 0.0;
    for (std::size_t k = 1; k < path.size(); ++k) {
        const double v = glm::length(path[k].position_m - path[k - 1].position_m) / d.step_s;
        slowest = std::min(slowest, v);
        fastest = std::max(fastest, v);
        if (previous >= 0.0)
            biggestChange = std::max(biggestChange, std::abs(v - previous) / d.step_s);
        previous = v;
    }
    EXPECT_LE(fastest, d.speed_mps * (1.0 + 1e-9));
    EXPECT_LT(slowest, 0.8 * d.speed_mps);  // the mountain road has tighter curves
    EXPECT_GE(slowest, 1.0);
    EXPECT_LE(biggestChange, 2.0 * d.maxSpeedChange_mps2);
    // Reversed: it starts at the road's far end.
    const Road& road = *world.roads().find("mountain");
    EXPECT_NEAR(path[0].position_m.x, road.centreline.back().x, 1e-6);
    EXPECT_NEAR(path[0].position_m.z, road.centreline.back().z, 1e-6);
}

TEST(CameraPath, DriveRejectsBadSettings) {
    const World& world = defaultWorld();
    DriveSettings d;
    d.road = "nowhere";
    EXPECT_THROW(makeDrivePath(world, d), InputError);
    d.road = "highway";
    d.speed_mps = 0.0;
    EXPECT_THROW(makeDrivePath(world, d), InputError);
    d.speed_mps = std::nan("");
    EXPECT_THROW(makeDrivePath(world, d), InputError);
    d.speed_mps = 30.0;
    d.laneOffset_m = 50.0;
    EXPECT_THROW(makeDrivePath(world, d), InputError);
    d.laneOffset_m = 0.0;
    d.step_s = 0.0;
    EXPECT_THROW(makeDrivePath(world, d), InputError);
    d.step_s = 1.0 / 60.0;
    d.duration_s = 3600.0;  // 108 km: longer than the road
    EXPECT_THROW(makeDrivePath(world, d), InputError);
}

TEST(CameraPath, FlightPlansAreDeterministic) {
    ProceduralFlight p;
    p.seed = 4;
    p.length_m = 20000.0;
    p.cuts = 2;
    const FlightPlan a = makeFlightPlan(p), b = makeFlightPlan(p);
    ASSERT_EQ(a.legs.size(), 3u);
    ASSERT_EQ(a.legs, b.legs);
    EXPECT_NEAR(a.length_m(), p.length_m, p.segmentMax_m);
    p.seed = 5;
    EXPECT_NE(makeFlightPlan(p).legs, a.legs);
}

TEST(CameraPath, FlyHasExactSpeedClearsTheTerrainAndFlagsTheCut) {
    const World& world = defaultWorld();
    FlySettings f;
    f.speed_mps = 250.0;
    f.altitude_m = 150.0;
    f.clearance_m = 60.0;
    f.duration_s = 40.0;  // 10 km
    ProceduralFlight p;
    p.seed = 11;
    p.length_m = 1.3 * f.speed_mps * f.duration_s;
    p.cuts = 1;
    p.cutJump_m = 2500.0;
    f.plan = makeFlightPlan(p);
    const std::vector<CameraSample> path = makeFlyPath(world, f);
    ASSERT_EQ(path.size(), 2401u);
    int cuts = 0;
    double meanAbove = 0.0;
    for (std::size_t k = 0; k < path.size(); ++k) {
        const CameraSample& s = path[k];
        expectOrthonormal(s);
        const double above = s.position_m.y - world.height(s.position_m.x, s.position_m.z);
        ASSERT_GE(above, f.clearance_m) << k;
        meanAbove += above / double(path.size());
        if (k == 0) continue;
        const glm::dvec3 step = s.position_m - path[k - 1].position_m;
        if (s.cut) {
            ++cuts;
            EXPECT_GT(glm::length(step), 100.0);  // a real teleport
            continue;
        }
        ASSERT_NEAR(glm::length(step), f.speed_mps * f.step_s, 1e-6 * f.speed_mps * f.step_s) << k;
        // Bounded climb: the flight level does not follow every bump.
        EXPECT_LE(std::abs(step.y) / std::hypot(step.x, step.z), f.maxClimb * 1.01) << k;
    }
    EXPECT_EQ(cuts, 1);
    EXPECT_FALSE(path[0].cut);
    EXPECT_GE(meanAbove, f.altitude_m);
    EXPECT_LT(meanAbove, f.altitude_m + 400.0);
}

TEST(CameraPath, FlyFollowsWaypointsWithTurnsFarFromTheOrigin) {
    // A square circuit 10^6 m from the origin: positions stay exact in double precision.
    const World& world = defaultWorld();
    const glm::dvec2 o(1.0e6, -1.0e6);
    FlySettings f;
    f.plan.legs = {
        {o, o + glm::dvec2(2000, 0), o + glm::dvec2(2000, 2000), o + glm::dvec2(0, 2000)}};
    f.speed_mps = 80.0;
    f.turnRadius_m = 300.0;
    f.duration_s = 60.0;  // 4.8 km of 6 km
    const std::vector<CameraSample> path = makeFlyPath(world, f);
    for (std::size_t k = 1; k < path.size(); ++k) {
        const double chord = glm::length(path[k].position_m - path[k - 1].position_m);
        ASSERT_NEAR(chord, f.speed_mps * f.step_s, 1e-6 * f.speed_mps * f.step_s) << k;
        ASSERT_GE(path[k].position_m.y - world.height(path[k].position_m.x, path[k].position_m.z),
                  f.clearance_m);
    }
    // The 90 degree turn at the first corner is an arc of radius r tangent to both legs: it
    // passes the corner at r (sqrt 2 - 1) = 124 m.
    double closest = 1e9;
    for (const CameraSample& s : path)
        closest = std::min(closest, glm::length(glm::dvec2(s.position_m.x, s.position_m.z) -
                                                (o + glm::dvec2(2000, 0))));
    EXPECT_GT(closest, 50.0);
    EXPECT_LT(closest, 130.0);
    // Too short a plan for the duration: an input error, not a truncated path.
    f.duration_s = 600.0;
    EXPECT_THROW(makeFlyPath(world, f), InputError);
    f.duration_s = 60.0;
    f.clearance_m = 500.0;  // above the altitude
    EXPECT_THROW(makeFlyPath(world, f), InputError);
}

TEST(CameraPath, StaticStandsStill) {
    const World& world = defaultWorld();
    StaticSettings s;
    s.position_m = {100.0, -200.0};
    s.heightAboveTerrain_m = 3.0;
    s.heading_rad = 0.5 * 3.14159265358979323846;  // east
    s.duration_s = 10.0;
    s.step_s = 0.5;
    const std::vector<CameraSample> path = makeStaticPath(world, s);
    ASSERT_EQ(path.size(), 21u);
    for (const CameraSample& c : path) {
        EXPECT_EQ(c.position_m, path[0].position_m);
        expectOrthonormal(c);
        EXPECT_NEAR(c.forward.x, 1.0, 1e-12);
    }
    EXPECT_NEAR(path[0].position_m.y, world.height(100.0, -200.0) + 3.0, 1e-9);
    EXPECT_NEAR(path.back().time_s, 10.0, 1e-12);
}

}  // namespace
}  // namespace amb
