// Road_test.cpp — routed roads: length, grade bound, smoothness, water, determinism, queries,
// the ribbon mesh drawn.
#include "world/Road.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "world/Heightfield.h"

namespace amb {
namespace {

struct Routed {
    WorldSettings settings;
    Heightfield heightfield;
    RoadNetwork network;
    explicit Routed(const WorldSettings& s)
        : settings(s), heightfield(s), network(s, heightfield) {}
};

const Routed& defaultWorld() {
    static const Routed routed{WorldSettings{}};
    return routed;
}

double horizontal(const glm::dvec3& a, const glm::dvec3& b) {
    return std::hypot(b.x - a.x, b.z - a.z);
}

TEST(Road, HighwayAndMountainRoadAreSeveralKilometresLong) {
    const RoadNetwork& net = defaultWorld().network;
    const Road* highway = net.find("highway");
    const Road* mountain = net.find("mountain");
    ASSERT_NE(highway, nullptr);
    ASSERT_NE(mountain, nullptr);
    EXPECT_GE(highway->length_m, 8000.0);
    EXPECT_GE(mountain->length_m, 3000.0);
    EXPECT_EQ(net.find("no such road"), nullptr);
    // length_m is the arc length: the sum of the chords is at most that and close to it.
    for (const Road& road : net.roads()) {
        double chords = 0.0;
        for (std::size_t i = 1; i < road.centreline.size(); ++i)
            chords += horizontal(road.centreline[i - 1], road.centreline[i]);
        EXPECT_LE(chords, road.length_m * (1.0 + 1e-9)) << road.name;
        EXPECT_GE(chords, road.length_m * 0.999) << road.name;
    }
}

TEST(Road, StaysInsideTheRoadRegionAndIsEvenlyResampled) {
    const Routed& w = defaultWorld();
    for (const Road& road : w.network.roads()) {
        for (const glm::dvec3& p : road.centreline) {
            EXPECT_LE(std::abs(p.x), w.settings.roadRegion_m) << road.name;
            EXPECT_LE(std::abs(p.z), w.settings.roadRegion_m) << road.name;
        }
        const double spacing = road.length_m / double(road.centreline.size() - 1);
        EXPECT_GE(spacing, 2.0);
        EXPECT_LE(spacing, 4.0);
        for (std::size_t i = 1; i < road.centreline.size(); ++i) {
            const double d = horizontal(road.centreline[i - 1], road.centreline[i]);
            ASSERT_LE(d, spacing * (1.0 + 1e-9)) << road.name << " segment " << i;
            ASSERT_GE(d, 0.9 * spacing) << road.name << " segment " << i;  // no cusps
        }
    }
}

TEST(Road, GradeIsBounded) {
    const RoadNetwork& net = defaultWorld().network;
    EXPECT_LE(net.find("highway")->maxGrade, 0.08);
    EXPECT_LE(net.find("mountain")->maxGrade, 0.12);
    for (const Road& road : net.roads()) {
        double steepest = 0.0;
        for (std::size_t i = 1; i < road.centreline.size(); ++i) {
            const glm::dvec3 &a = road.centreline[i - 1], &b = road.centreline[i];
            steepest = std::max(steepest, std::abs(b.y - a.y) / horizontal(a, b));
        }
        EXPECT_LE(steepest, road.maxGrade) << road.name;
    }
}

TEST(Road, MountainRoadClimbs) {
    const Road* mountain = defaultWorld().network.find("mountain");
    double lo = 1e9, hi = -1e9;
    for (const glm::dvec3& p : mountain->centreline) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
    EXPECT_GE(hi - lo, 100.0);
}

TEST(Road, CurvatureIsBounded) {
    // Turning angle between consecutive segments over their mean length: the radius of curvature.
    for (const Road& road : defaultWorld().network.roads()) {
        const double minRadius_m = road.name == "highway" ? 120.0 : 25.0;
        double smallest = std::numeric_limits<double>::infinity();
        for (std::size_t i = 1; i + 1 < road.centreline.size(); ++i) {
            const glm::dvec3 &a = road.centreline[i - 1], &b = road.centreline[i],
                             &c = road.centreline[i + 1];
            const glm::dvec2 u(b.x - a.x, b.z - a.z), v(c.x - b.x, c.z - b.z);
            const double angle = std::atan2(std::abs(u.x * v.y - u.y * v.x), glm::dot(u, v));
            const double length = 0.5 * (glm::length(u) + glm::length(v));
            if (angle > 0.0) smallest = std::min(smallest, length / angle);
        }
        EXPECT_GE(smallest, minRadius_m) << road.name;
    }
}

TEST(Road, AvoidsWaterAndFollowsTheTerrain) {
    for (std::uint64_t seed : {1ull, 7ull}) {
        WorldSettings settings;
        settings.seed = seed;
        const Routed w(settings);
        for (const Road& road : w.network.roads()) {
            std::size_t wet = 0;
            double deepestCut = 0.0;
            for (const glm::dvec3& p : road.centreline) {
                EXPECT_GT(p.y, settings.waterLevel_m);  // the surface is always dry
                const double h = w.heightfield.height(p.x, p.z);
                if (h < settings.waterLevel_m) ++wet;
                deepestCut = std::max(deepestCut, std::abs(h - p.y));
            }
            // Less than 1 % of the road over natural water, cuts and fills at most 25 m.
            EXPECT_LE(double(wet), 0.01 * double(road.centreline.size())) << road.name << seed;
            EXPECT_LE(deepestCut, 25.0) << road.name << " seed " << seed;
        }
    }
}

TEST(Road, RoutingIsDeterministicAndDependsOnTheSeed) {
    const Routed& w = defaultWorld();
    const std::vector<Road> again = RoadNetwork::route(w.settings, w.heightfield);
    ASSERT_EQ(again.size(), w.network.roads().size());
    for (std::size_t r = 0; r < again.size(); ++r) {
        const Road& a = again[r];
        const Road& b = w.network.roads()[r];
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.length_m, b.length_m);
        ASSERT_EQ(a.centreline.size(), b.centreline.size());
        for (std::size_t i = 0; i < a.centreline.size(); ++i)
            ASSERT_EQ(a.centreline[i], b.centreline[i]) << a.name << " vertex " << i;
    }
    WorldSettings other = w.settings;
    other.seed = 99;
    const Heightfield otherField(other);
    const std::vector<Road> different = RoadNetwork::route(other, otherField);
    EXPECT_NE(different[0].centreline.front(), w.network.roads()[0].centreline.front());
}

TEST(Road, PointAtAndTangentAt) {
    const Road& road = *defaultWorld().network.find("mountain");
    EXPECT_EQ(road.pointAt(-5.0), road.centreline.front());
    EXPECT_EQ(road.pointAt(road.length_m + 5.0), road.centreline.back());
    EXPECT_NEAR(glm::length(road.pointAt(road.vertexDistance_m(10)) - road.centreline[10]), 0.0,
                1e-9);
    for (double s = 1.0; s < road.length_m - 1.0; s += road.length_m / 97.0) {
        const glm::dvec3 t = road.tangentAt(s);
        EXPECT_NEAR(glm::length(t), 1.0, 1e-12);
        // Against a central difference of pointAt over +-1 m.
        const glm::dvec3 fd = glm::normalize(road.pointAt(s + 1.0) - road.pointAt(s - 1.0));
        EXPECT_GT(glm::dot(t, fd), 0.995) << "s = " << s;
    }
}

TEST(Road, NearestMatchesBruteForce) {
    const RoadNetwork& net = defaultWorld().network;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> offset(-60.0, 60.0);
    std::uniform_int_distribution<std::size_t> pick(0, 1000000);
    const double maxDistance = 40.0;
    int found = 0;
    for (int k = 0; k < 3000; ++k) {
        const Road& road = net.roads()[std::size_t(k) % net.roads().size()];
        const glm::dvec3 base = road.centreline[pick(rng) % road.centreline.size()];
        const double x = base.x + offset(rng), z = base.z + offset(rng);
        double best = std::numeric_limits<double>::infinity();
        double bestHeight = 0.0;
        for (const Road& r : net.roads()) {
            for (std::size_t i = 0; i + 1 < r.centreline.size(); ++i) {
                const glm::dvec2 a(r.centreline[i].x, r.centreline[i].z);
                const glm::dvec2 b(r.centreline[i + 1].x, r.centreline[i + 1].z);
                const glm::dvec2 p(x, z);
                const double t =
                    std::clamp(glm::dot(p - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
                const double d = glm::length(p - (a + t * (b - a)));
                if (d < best) {
                    best = d;
                    bestHeight = glm::mix(r.centreline[i].y, r.centreline[i + 1].y, t);
                }
            }
        }
        const auto q = net.nearest(x, z, maxDistance);
        ASSERT_EQ(q.has_value(), best <= maxDistance) << x << ", " << z;
        if (q) {
            ++found;
            EXPECT_NEAR(q->distance_m, best, 1e-9);
            EXPECT_NEAR(q->surfaceHeight_m, bestHeight, 0.01);  // ties between two roads
            EXPECT_EQ(q->halfWidth_m, net.roads()[std::size_t(q->roadIndex)].halfWidth_m);
        }
    }
    EXPECT_GT(found, 1000);
    // Far away, non-finite or negative ranges: nothing.
    EXPECT_FALSE(net.nearest(1.0e6, 1.0e6, 100.0).has_value());
    EXPECT_FALSE(net.nearest(std::nan(""), 0.0, 100.0).has_value());
    EXPECT_FALSE(net.nearest(0.0, 0.0, -1.0).has_value());
    // On a vertex: distance 0, the vertex's height, its arc length.
    const Road& hw = *net.find("highway");
    const auto on = net.nearest(hw.centreline[100].x, hw.centreline[100].z, 1.0);
    ASSERT_TRUE(on.has_value());
    EXPECT_NEAR(on->distance_m, 0.0, 1e-9);
    EXPECT_NEAR(on->surfaceHeight_m, hw.centreline[100].y, 1e-9);
    // An unbounded range finds the nearest road from anywhere.
    const auto far = net.nearest(2.0e4, 0.0, std::numeric_limits<double>::infinity());
    ASSERT_TRUE(far.has_value());
    EXPECT_GT(far->distance_m, 1.0e4);
}

TEST(Road, SmallRegionStillRoutesInsideIt) {
    WorldSettings settings;
    settings.seed = 3;
    settings.roadRegion_m = 1500.0;
    const Routed w(settings);
    ASSERT_GE(w.network.roads().size(), 2u);
    for (const Road& road : w.network.roads()) {
        EXPECT_GE(road.length_m, 500.0) << road.name;
        for (const glm::dvec3& p : road.centreline) {
            ASSERT_LE(std::abs(p.x), settings.roadRegion_m);
            ASSERT_LE(std::abs(p.z), settings.roadRegion_m);
        }
    }
}

// The ribbon the renderer draws: two vertices per centreline vertex at the half width, lifted,
// facing up; on a grade its normals tilt along the road, perpendicular to the centreline's
// tangent and to the level across direction.
TEST(Road, RibbonFollowsTheGradeWithItsNormals) {
    const Road& mountain = *defaultWorld().network.find("mountain");
    const auto& c = mountain.centreline;
    // The steepest stretch of 48 segments.
    std::size_t first = 1;
    double steepest = 0.0;
    for (std::size_t i = 1; i + 49 < c.size(); i += 16) {
        const double grade = std::abs(c[i + 48].y - c[i].y) / (48.0 * RoadNetwork::kRoadSpacing_m);
        if (grade > steepest) steepest = grade, first = i;
    }
    ASSERT_GT(steepest, 0.03);
    const std::size_t last = first + 48;
    const double lift = 0.12;
    const WorldMesh m = roadRibbon(mountain, first, last, lift, glm::vec3(0.1f));
    ASSERT_EQ(m.vertexCount(), 2 * (last - first + 1));
    EXPECT_EQ(m.triangleCount(), 2 * (last - first));
    double largestTilt = 0.0;
    for (std::size_t i = first; i <= last; ++i) {
        const glm::dvec3 along = c[std::min(i + 1, c.size() - 1)] - c[i - 1];
        for (int s = 0; s < 2; ++s) {
            const std::size_t v = 2 * (i - first) + s;
            const glm::dvec3 p = c[first] + glm::dvec3(m.positions[3 * v], m.positions[3 * v + 1],
                                                       m.positions[3 * v + 2]);
            const glm::dvec3 n(m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]);
            EXPECT_NEAR(horizontal(p, c[i]), mountain.halfWidth_m, 1e-3);
            EXPECT_NEAR(p.y, c[i].y + lift, 1e-3);
            EXPECT_NEAR(glm::length(n), 1.0, 1e-6);
            EXPECT_GT(n.y, 0.0);
            EXPECT_NEAR(glm::dot(n, glm::normalize(along)), 0.0, 1e-6);  // follows the grade
            const glm::dvec3 across = p - glm::dvec3(c[i].x, c[i].y + lift, c[i].z);
            EXPECT_NEAR(glm::dot(n, across), 0.0, 1e-3);  // level across
            largestTilt = std::max(largestTilt, std::sqrt(1.0 - n.y * n.y));
        }
    }
    // sin of the tilt is about the grade.
    EXPECT_GT(largestTilt, 0.5 * steepest);
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
        const auto P = [&](int k) {
            const std::uint32_t v = m.indices[t + k];
            return glm::dvec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
        };
        ASSERT_GT(glm::cross(P(1) - P(0), P(2) - P(0)).y, 0.0);
    }
}

}  // namespace
}  // namespace amb
