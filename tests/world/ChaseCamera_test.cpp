// ChaseCamera_test.cpp — the chase eye: the spring step against its closed form; along a real
// mountain drive the eye stays behind and above the car, above the terrain, and looks at the car;
// a cut puts it at rest behind the car.
#include "world/ChaseCamera.h"

#include <cmath>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/CameraPath.h"
#include "world/World.h"

namespace amb {
namespace {

TEST(ChaseCamera, SpringStepsFollowTheClosedForm) {
    // x(t) = target + (d0 + (v0 + w d0) t) exp(-w t), stepped at 1/30 s and at 1/7 s.
    const glm::dvec3 target(3.0, -1.0, 2.0), x0(10.0, 4.0, -6.0), v0(-2.0, 5.0, 1.0);
    const double w = 3.0;
    for (double dt : {1.0 / 30.0, 1.0 / 7.0}) {
        glm::dvec3 x = x0, v = v0;
        for (int i = 1; i <= int(std::round(4.0 / dt)); ++i) {
            criticalSpringStep(x, v, target, w, dt);
            const double t = i * dt;
            const glm::dvec3 d0 = x0 - target;
            const glm::dvec3 exact = target + (d0 + (v0 + w * d0) * t) * std::exp(-w * t);
            ASSERT_LT(glm::length(x - exact), 1e-9) << "dt " << dt << " t " << t;
        }
        // Critically damped: after 4 s (12 time constants) within 1e-3 of the target.
        EXPECT_LT(glm::length(x - target), 1e-3);
    }
}

TEST(ChaseCamera, StaysBehindAndAboveTheCarAndAboveTheTerrain) {
    const World world(WorldSettings{});
    DriveSettings drive;
    drive.road = "mountain";
    drive.speed_mps = 18.0;
    drive.duration_s = 40.0;
    drive.step_s = 1.0 / 30.0;
    const std::vector<CameraSample> path = makeDrivePath(world, drive);
    const auto ground = [&](double x, double z) { return world.height(x, z); };
    const ChaseSettings settings;
    ChaseCamera chase(settings, ground);
    double minClearance = 1e9, minBehind = 1e9;
    for (std::size_t i = 0; i < path.size(); ++i) {
        const VehiclePose car = vehiclePoseFromEye(path[i], drive.eyeHeight_m, ground);
        const CameraSample eye = chase.update(car, drive.step_s, i == 0, path[i]);
        const glm::dvec3 fromCar = eye.position_m - car.position_m;
        const glm::dvec3 ahead(std::sin(car.heading_rad), 0.0, std::cos(car.heading_rad));
        // Behind: at least 3 m behind the car's middle along its heading (the target is 6.5 m).
        minBehind = std::min(minBehind, -glm::dot(fromCar, ahead) + VehicleShape::centreZ_m());
        EXPECT_GT(fromCar.y, 1.5) << "sample " << i;  // above the car's ground point
        minClearance = std::min(
            minClearance, eye.position_m.y - world.height(eye.position_m.x, eye.position_m.z));
        // It looks at the car: the middle of the car lies straight ahead.
        const glm::dvec3 look = glm::normalize(ChaseCamera::lookAt(car, settings) - eye.position_m);
        EXPECT_GT(glm::dot(look, eye.forward), 1.0 - 1e-9);
        EXPECT_NEAR(glm::dot(eye.forward, eye.up), 0.0, 1e-9);
        EXPECT_GT(eye.up.y, 0.0);
    }
    EXPECT_GT(minBehind, 3.0);
    EXPECT_GE(minClearance, settings.clearance_m - 1e-9);
}

TEST(ChaseCamera, ACutPutsTheEyeAtRestBehindTheCar) {
    ChaseCamera chase(ChaseSettings{}, {});
    VehiclePose car;
    car.position_m = {0.0, 10.0, 0.0};
    car.heading_rad = 0.0;
    CameraSample sample;
    chase.update(car, 0.0, true, sample);
    // Jump 5 km and turn round: with the cut the offset is the target at once, without it not.
    car.position_m = {5000.0, 10.0, 0.0};
    car.heading_rad = 3.0;
    const glm::dvec3 target = ChaseCamera::targetOffset(car, ChaseSettings{});
    ChaseCamera smooth = chase;
    smooth.update(car, 1.0 / 30.0, false, sample);
    EXPECT_GT(glm::length(smooth.offset() - target), 1.0);
    const CameraSample eye = chase.update(car, 1.0 / 30.0, true, sample);
    EXPECT_LT(glm::length(chase.offset() - target), 1e-12);
    EXPECT_NEAR(glm::length(eye.position_m - (car.position_m + target)), 0.0, 1e-9);
}

}  // namespace
}  // namespace amb
