// Vehicle_test.cpp — the car mesh: a few hundred triangles, every part a closed surface (each edge
// shared by exactly two triangles, in opposite directions), normals outward (they agree with the
// winding, and the enclosed volume is positive and car-sized), wheels standing on y = 0, nothing
// ahead of the driver's eye that hides the road; and the car's pose under a replay's eye.
#include "world/Vehicle.h"

#include <cmath>
#include <map>
#include <tuple>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

namespace amb {
namespace {

glm::dvec3 position(const WorldMesh& m, std::uint32_t i) {
    return {m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
}

TEST(Vehicle, MeshIsAFewHundredTrianglesOfClosedOutwardSurfaces) {
    const WorldMesh m = makeVehicleMesh();
    EXPECT_GE(m.triangleCount(), 200u);
    EXPECT_LE(m.triangleCount(), 600u);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_EQ(m.albedo.size(), m.positions.size());
    for (std::uint32_t i : m.indices) ASSERT_LT(i, m.vertexCount());
    // Vertices welded by position (flat shading duplicates them): directed edges between welded
    // vertices. Closed and consistently wound: every directed edge once, and its reverse once.
    std::map<std::tuple<float, float, float>, int> weld;
    auto id = [&](std::uint32_t i) {
        const auto key =
            std::make_tuple(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
        return weld.emplace(key, int(weld.size())).first->second;
    };
    std::map<std::pair<int, int>, int> edges;
    double volume = 0.0;
    for (std::size_t t = 0; t < m.triangleCount(); ++t) {
        const std::uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1],
                            c = m.indices[3 * t + 2];
        const int ia = id(a), ib = id(b), ic = id(c);
        ++edges[{ia, ib}], ++edges[{ib, ic}], ++edges[{ic, ia}];
        const glm::dvec3 pa = position(m, a), pb = position(m, b), pc = position(m, c);
        const glm::dvec3 n = glm::cross(pb - pa, pc - pa);
        for (std::uint32_t v : {a, b, c}) {
            const glm::dvec3 vn(m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]);
            EXPECT_NEAR(glm::length(vn), 1.0, 1e-6);
            EXPECT_GT(glm::dot(n, vn), 0.0) << "triangle " << t;
        }
        volume += glm::dot(pa, glm::cross(pb, pc)) / 6.0;  // divergence theorem
    }
    for (const auto& [edge, count] : edges) {
        EXPECT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second;
        const auto reverse = edges.find({edge.second, edge.first});
        EXPECT_TRUE(reverse != edges.end() && reverse->second == 1)
            << "edge " << edge.first << "-" << edge.second << " has no opposite";
    }
    // Outward normals give a positive volume: a car of 4.4 x 1.76 x 1.44 m holds 5 to 11 m^3
    // (the wheels, partly inside the body, count twice there).
    EXPECT_GT(volume, 5.0);
    EXPECT_LT(volume, 11.0);
}

TEST(Vehicle, WheelsTouchTheGroundAndTheHoodViewStaysOpen) {
    const WorldMesh m = makeVehicleMesh();
    double lowest = 1e9;
    int onGround = 0;
    for (std::uint32_t v = 0; v < m.vertexCount(); ++v) {
        const glm::dvec3 p = position(m, v);
        lowest = std::min(lowest, p.y);
        if (p.y < 1e-5) {
            ++onGround;
            // Only tyres touch the ground, under an axle.
            const double axle = std::min(std::abs(p.z - VehicleShape::kRearAxleZ_m),
                                         std::abs(p.z - VehicleShape::kFrontAxleZ_m));
            EXPECT_LT(axle, 1e-5);
            EXPECT_GT(std::abs(p.x), 0.6);
        }
        // Ahead of the eye (1.5 m up at the origin) nothing rises above 1.1 m: the road shows.
        if (p.z > 0.35) {
            EXPECT_LE(p.y, 1.1) << "vertex " << v;
        }
        EXPECT_GE(p.z, VehicleShape::kRearZ_m - 0.05);
        EXPECT_LE(p.z, VehicleShape::kFrontZ_m + 0.05);
    }
    EXPECT_NEAR(lowest, 0.0, 1e-6);
    EXPECT_GE(onGround, 4);  // every wheel at least once
}

TEST(Vehicle, PoseFollowsTheEyeAndPitchesToTheGround) {
    CameraSample eye;
    eye.position_m = {100.0, 51.5, -20.0};
    const double heading = 0.7;
    eye.forward = glm::normalize(glm::dvec3(std::sin(heading), -0.05, std::cos(heading)));
    // Level without a ground; on a ground rising 12 % along the heading, atan(0.12).
    VehiclePose level = vehiclePoseFromEye(eye, 1.5);
    EXPECT_NEAR(level.heading_rad, heading, 1e-12);
    EXPECT_EQ(level.pitch_rad, 0.0);
    EXPECT_NEAR(level.position_m.y, 50.0, 1e-12);
    const auto ramp = [&](double x, double z) {
        return 50.0 + 0.12 * ((x - 100.0) * std::sin(heading) + (z + 20.0) * std::cos(heading));
    };
    const VehiclePose up = vehiclePoseFromEye(eye, 1.5, ramp);
    EXPECT_NEAR(up.pitch_rad, std::atan(0.12), 1e-9);
    EXPECT_NEAR(glm::dot(vehicleForward(up), glm::dvec3(0, 1, 0)), std::sin(std::atan(0.12)), 1e-9);
    // The pitched mesh: the front axle's ground point rises by its distance times sin(pitch).
    WorldMesh point;
    point.positions = {0.0f, 0.0f, float(VehicleShape::kFrontAxleZ_m)};
    point.normals = {0.0f, 1.0f, 0.0f};
    const WorldMesh pitched = pitchedMesh(point, up.pitch_rad);
    EXPECT_NEAR(pitched.positions[1], VehicleShape::kFrontAxleZ_m * std::sin(up.pitch_rad), 1e-6);
    EXPECT_NEAR(pitched.normals[2], -std::sin(up.pitch_rad), 1e-6);
}

}  // namespace
}  // namespace amb
