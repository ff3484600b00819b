// Vehicle_test.cpp — the car mesh: well formed, outward normals, and nothing ahead of the
// driver's eye (1.5 m up, at the origin) rises above 1.1 m, so the road stays in view.
#include "world/Vehicle.h"

#include <cmath>

#include <gtest/gtest.h>

namespace amb {
namespace {

TEST(Vehicle, MeshIsWellFormedAndLeavesTheViewOpen) {
    const WorldMesh m = makeVehicleMesh();
    ASSERT_GT(m.triangleCount(), 0u);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_EQ(m.albedo.size(), m.positions.size());
    for (std::uint32_t i : m.indices) ASSERT_LT(i, m.vertexCount());
    for (std::size_t v = 0; v < m.vertexCount(); ++v) {
        const float nx = m.normals[3 * v], ny = m.normals[3 * v + 1], nz = m.normals[3 * v + 2];
        EXPECT_NEAR(std::sqrt(nx * nx + ny * ny + nz * nz), 1.0, 1e-6);
        const float y = m.positions[3 * v + 1], z = m.positions[3 * v + 2];
        if (z > 0.35f) {
            EXPECT_LE(y, 1.1f) << "vertex " << v;
        }
        EXPECT_GE(y, 0.0f);
    }
    // Each triangle's winding agrees with its vertices' normals (counter-clockwise outside).
    for (std::size_t t = 0; t < m.triangleCount(); ++t) {
        const std::uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        auto p = [&](std::uint32_t i, int k) { return double(m.positions[3 * i + k]); };
        const double e1[3] = {p(b, 0) - p(a, 0), p(b, 1) - p(a, 1), p(b, 2) - p(a, 2)};
        const double e2[3] = {p(c, 0) - p(a, 0), p(c, 1) - p(a, 1), p(c, 2) - p(a, 2)};
        const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                             e1[0] * e2[1] - e1[1] * e2[0]};
        const double dot = n[0] * m.normals[3 * a] + n[1] * m.normals[3 * a + 1] +
                           n[2] * m.normals[3 * a + 2];
        EXPECT_GT(dot, 0.0) << "triangle " << t;
    }
}

}  // namespace
}  // namespace amb
