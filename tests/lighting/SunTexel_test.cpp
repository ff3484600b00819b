// SunTexel_test.cpp — the texel holding the sun direction (lighting/SunTexel.h) and that texel
// filled from its neighbours' sky.
#include "lighting/SunTexel.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Conventions.h"

namespace amb {
namespace {

// ---- Which texel -----------------------------------------------------------------------------

// Every texel centre maps back to its texel, at every face size from 1 up; a direction of any
// length gives the same texel.
TEST(SunTexel, EveryTexelCentreIsItsOwnTexel) {
    for (int n : {1, 2, 3, 4, 7, 8, 16, 64}) {
        for (int f = 0; f < kCubeFaces; ++f)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const CubeTexel want{f, i, j};
                    const glm::dvec3 d = cubeTexelDirection(f, i, j, n);
                    ASSERT_EQ(sunTexel(d, n), want) << n << " " << f << " " << i << " " << j;
                    ASSERT_EQ(sunTexel(1e-3 * d, n), want);
                    ASSERT_EQ(sunTexel(glm::normalize(d), n), want);
                }
    }
}

// The texel's square holds the direction: just inside each corner of a texel maps to it; a
// direction on an edge between faces goes to one face (the lower index), never to none.
TEST(SunTexel, TheTexelSquareHoldsTheDirection) {
    const int n = 16;
    for (int f = 0; f < kCubeFaces; ++f)
        for (int j = 0; j < n; j += 5)
            for (int i = 0; i < n; i += 3)
                for (double du : {0.01, 0.99})
                    for (double dv : {0.01, 0.99}) {
                        const double u = 2.0 * (i + du) / n - 1.0, v = 2.0 * (j + dv) / n - 1.0;
                        const CubeTexel want{f, i, j};
                        ASSERT_EQ(sunTexel(cubeFaceDirection(f, u, v), n), want);
                    }
    EXPECT_EQ(sunTexel(glm::dvec3(1.0, 1.0, 0.0), n).face, 0);   // +X and +Y: +X
    EXPECT_EQ(sunTexel(glm::dvec3(0.0, 1.0, -1.0), n).face, 2);  // +Y and -Z: +Y
    EXPECT_EQ(sunTexel(glm::dvec3(1.0, 1.0, 1.0), n).face, 0);
}

// ---- The fill --------------------------------------------------------------------------------

// The texel becomes the mean of the opposite pair of neighbours (row, column, diagonals) that
// differs least, both usable: a linear field is given back exactly, and along an edge (a sky over
// a darker ground) the pair along the edge is taken. Without a whole pair (a face's corner) the
// mean of the usable neighbours; NaN, infinite or negative neighbours are never used; a bad sun
// texel is left alone; a 1 x 1 face (no neighbours) is zeroed; a texel on another face changes
// nothing.
TEST(SunTexel, FillTakesThePairAlongTheEdge) {
    const int n = 4;
    const int f = int(CubeFace::PosZ);
    const auto centre = [&](int i, int j) { return cubeTexelDirection(f, i, j, n); };
    const auto at = [&](std::vector<float>& face, int i, int j) { return &face[3 * (j * n + i)]; };
    std::vector<float> linear(3 * n * n);
    for (int t = 0; t < n * n; ++t)
        for (int c = 0; c < 3; ++c) linear[3 * t + c] = float(t + 10 * c);
    {
        std::vector<float> a = linear;
        glm::vec3 removed, filled;
        at(a, 1, 2)[0] += 1e4f;  // the sun
        ASSERT_TRUE(fillSunTexel(a.data(), f, n, centre(1, 2), &removed, &filled));
        EXPECT_EQ(removed, glm::vec3(9.0f + 1e4f, 19.0f, 29.0f));
        EXPECT_EQ(filled, glm::vec3(9.0f, 19.0f, 29.0f));
        EXPECT_EQ(a, linear);
    }
    // Sky (1) over ground (0.1) below row 1, the sun in row 1: the row's pair.
    std::vector<float> edge(3 * n * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c) at(edge, i, j)[c] = j <= 1 ? 1.0f + 0.01f * i : 0.1f;
    {
        std::vector<float> a = edge;
        at(a, 1, 1)[1] = 3e4f;
        ASSERT_TRUE(fillSunTexel(a.data(), f, n, centre(1, 1)));
        EXPECT_FLOAT_EQ(at(a, 1, 1)[1], 1.01f);
        // A bad texel in that pair: the next best whole pair (here a diagonal: 1 and 0.1).
        a = edge;
        at(a, 2, 1)[2] = std::numeric_limits<float>::quiet_NaN();
        ASSERT_TRUE(fillSunTexel(a.data(), f, n, centre(1, 1)));
        EXPECT_FLOAT_EQ(at(a, 1, 1)[0], 0.5f * (1.0f + 0.1f));
    }
    {
        // A corner: no whole pair, the mean of the three neighbours.
        std::vector<float> a = linear;
        ASSERT_TRUE(fillSunTexel(a.data(), f, n, centre(0, 0)));
        EXPECT_FLOAT_EQ(a[0], (1 + 4 + 5) / 3.0f);
        // ... with one of them negative: the other two.
        a = linear;
        at(a, 1, 1)[2] = -1.0f;
        ASSERT_TRUE(fillSunTexel(a.data(), f, n, centre(0, 0)));
        EXPECT_FLOAT_EQ(a[0], (1 + 4) / 2.0f);
        // An edge texel: the column pair is its only whole one.
        a = linear;
        ASSERT_TRUE(fillSunTexel(a.data(), f, n, centre(3, 1)));
        EXPECT_FLOAT_EQ(at(a, 3, 1)[0], 7.0f);
    }
    {
        std::vector<float> a = linear;
        at(a, 1, 1)[0] = std::numeric_limits<float>::infinity();
        std::vector<float> b = a;
        EXPECT_FALSE(fillSunTexel(b.data(), f, n, centre(1, 1)));  // the sun texel itself is bad
        EXPECT_FALSE(fillSunTexel(b.data(), int(CubeFace::NegZ), n, centre(1, 2)));
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
    }
    std::vector<float> one{5.0f, 6.0f, 7.0f};
    ASSERT_TRUE(fillSunTexel(one.data(), 2, 1, glm::dvec3(0.1, 1.0, 0.2)));
    EXPECT_EQ(one, std::vector<float>(3, 0.0f));
}

}  // namespace
}  // namespace amb
