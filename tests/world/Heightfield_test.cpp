// Heightfield_test.cpp — the noise equals GLM's bit for bit, determinism, normals against
// difference quotients, smoothness and statistics far from the origin, moisture range.
#include "world/Heightfield.h"

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/gtc/noise.hpp>

namespace amb {
namespace {

WorldSettings seeded(std::uint64_t seed) {
    WorldSettings s;
    s.seed = seed;
    return s;
}

bool bitEqual(double a, double b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// The table-driven noise is GLM's classic Perlin noise bit for bit over the period [0, 289]:
// a million random points, every lattice line and the cells' edges from both sides, and the
// period's end (289 wraps to 0).
TEST(Heightfield, ClassicNoiseIsGlmsBitForBit) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.0, 289.0);
    std::vector<double> coords;
    for (int i = 0; i <= 289; ++i)
        for (double d : {0.0, 1e-12, 0.5, 1.0 - 1e-12})
            if (i + d <= 289.0) coords.push_back(i + d);
    coords.push_back(std::nextafter(289.0, 0.0));
    int mismatches = 0, count = 0;
    const auto check = [&](double a, double b) {
        ++count;
        const double want = glm::perlin(glm::dvec2(a, b));
        if (!bitEqual(Heightfield::classicNoise(a, b), want) && ++mismatches <= 5)
            ADD_FAILURE() << "at (" << a << ", " << b << "): " << Heightfield::classicNoise(a, b)
                          << " against " << want;
    };
    for (int n = 0; n < 1000000; ++n) check(u(rng), u(rng));
    for (double a : coords) {
        check(a, u(rng));
        check(u(rng), a);
    }
    for (std::size_t i = 0; i < coords.size(); i += 7)
        for (std::size_t j = 0; j < coords.size(); j += 5) check(coords[i], coords[j]);
    EXPECT_EQ(mismatches, 0) << "of " << count;
}

TEST(Heightfield, SameSeedGivesBitIdenticalHeights) {
    const Heightfield a(seeded(7)), b(seeded(7));
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-2e4, 2e4);
    for (int n = 0; n < 2000; ++n) {
        const double x = u(rng), z = u(rng);
        ASSERT_TRUE(bitEqual(a.height(x, z), b.height(x, z))) << x << ", " << z;
        ASSERT_TRUE(bitEqual(a.moisture(x, z), b.moisture(x, z)));
    }
}

TEST(Heightfield, DifferentSeedGivesDifferentTerrain) {
    const Heightfield a(seeded(1)), b(seeded(2));
    int differ = 0;
    double sumSq = 0.0;
    for (int n = 0; n < 400; ++n) {
        const double x = 97.0 * n - 20000.0, z = 53.0 * n - 9000.0;
        const double d = a.height(x, z) - b.height(x, z);
        differ += std::abs(d) > 1e-3;
        sumSq += d * d;
    }
    EXPECT_GT(differ, 390);
    EXPECT_GT(std::sqrt(sumSq / 400.0), 10.0);  // metres: unrelated terrain, not a small shift
}

TEST(Heightfield, NormalMatchesFineDifferenceQuotient) {
    const Heightfield hf(seeded(3));
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(-8000.0, 8000.0);
    for (double offset : {0.0, 1e6}) {
        for (int n = 0; n < 300; ++n) {
            const double x = offset + u(rng), z = offset + u(rng);
            const double e = 0.02;  // metres; independent of the implementation's step
            const double dhdx = (hf.height(x + e, z) - hf.height(x - e, z)) / (2 * e);
            const double dhdz = (hf.height(x, z + e) - hf.height(x, z - e)) / (2 * e);
            const glm::dvec3 ref = glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
            const glm::dvec3 n3 = hf.normal(x, z);
            EXPECT_NEAR(glm::length(n3), 1.0, 1e-12);
            EXPECT_GT(n3.y, 0.0);
            // Angle between the normals below 0.01 rad where features are tens of metres wide;
            // a gully's wall curves over metres, and there the 0.5 m step errs by up to 0.1 rad.
            const double bound = hf.ravineMask(x, z) > 0.0 ? 0.1 : 0.01;
            EXPECT_GT(glm::dot(n3, ref), std::cos(bound)) << x << ", " << z;
        }
    }
}

// Smoothness at centimetre scale: second differences of a C1 noise sum stay tiny. A float
// evaluation at 10^6 m would quantise positions to ~6 cm and show steps here.
// A gully's wall curves at up to about 1 / m: there the bound is 4 / m x (1.2 cm)^2, still a
// hundred times below what a step or a kink of its slope would show.
void expectSmoothAtCentimetres(const Heightfield& hf, double x0, double z0, double bound = 1e-5) {
    std::vector<double> h;
    for (int i = 0; i <= 200; ++i) h.push_back(hf.height(x0 + 0.01 * i, z0 + 0.007 * i));
    for (int i = 1; i < 200; ++i) {
        ASSERT_LT(std::abs(h[i + 1] - 2.0 * h[i] + h[i - 1]), bound) << "at " << x0 << " step " << i;
    }
}

TEST(Heightfield, SmoothAtCentimetresNearAndFarFromOrigin) {
    const Heightfield hf(seeded(4));
    for (double offset : {0.0, 1e6, -1e6, 3.7e6}) {
        for (int n = 0; n < 10; ++n)
            expectSmoothAtCentimetres(hf, offset + 731.0 * n, offset - 377.0 * n);
    }
}

// Gullies: nowhere deeper than kGullyDepth_m, none outside ravine country (there the height is
// the broad terrain's bit for bit), in ravine country some as deep as 5 m, and smooth (C1: the
// cross-section meets the land with zero slope) at centimetres like the rest of the terrain.
TEST(Heightfield, GulliesCutOnlyRavineCountryAndStaySmooth) {
    const Heightfield hf(seeded(1));
    int outside = 0, inside = 0, deep = 0;
    double deepX = 0.0, deepZ = 0.0;
    for (double x = -6000.0; x <= 6000.0; x += 37.0) {
        for (double z = -6000.0; z <= 6000.0; z += 41.0) {
            const double d = hf.gullyDepth(x, z);
            ASSERT_GE(d, 0.0);
            ASSERT_LE(d, Heightfield::kGullyDepth_m);
            ASSERT_TRUE(bitEqual(hf.height(x, z), hf.broadHeight(x, z) - d));
            if (hf.ravineMask(x, z) == 0.0) {
                ++outside;
                ASSERT_EQ(d, 0.0) << x << ", " << z;
            } else {
                ++inside;
                if (d > 5.0) ++deep, deepX = x, deepZ = z;
            }
        }
    }
    // About a tenth of the land is ravine country.
    const double share = double(inside) / double(inside + outside);
    EXPECT_GT(share, 0.05);
    EXPECT_LT(share, 0.3);
    ASSERT_GT(deep, 0);
    // Across the deep gully, at centimetres: smooth.
    for (int n = 0; n < 10; ++n)
        expectSmoothAtCentimetres(hf, deepX - 1.0 + 0.2 * n, deepZ - 0.7 * n, 4.0 * 1.5e-4);
    // It is a gully, not a pit or a step: within 20 m the land rises back to the broad terrain.
    double rim = 0.0;
    for (int a = 0; a < 16; ++a) {
        const double phi = 2.0 * 3.14159265358979 * a / 16.0;
        double least = 1e9;
        for (double r = 1.0; r <= 20.0; r += 1.0)
            least = std::min(least, hf.gullyDepth(deepX + r * std::cos(phi), deepZ + r * std::sin(phi)));
        rim = std::max(rim, 5.0 - least);
    }
    EXPECT_GT(rim, 4.0) << "some direction leaves the gully within 20 m";
}

// The noise's slope stays under the bound mayHaveGullies relies on: a million random
// points, difference quotients over 1e-4 lattice units (the quintic fade keeps the slope's
// own variation small at that step).
TEST(Heightfield, NoiseSlopeStaysUnderItsBound) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> at(0.0, 289.0);
    const double e = 1e-4;
    double steepest = 0.0;
    for (int n = 0; n < 1000000; ++n) {
        const double u = at(rng), v = at(rng);
        const double f = Heightfield::classicNoise(u, v);
        const double du = (Heightfield::classicNoise(u + e, v) - f) / e;
        const double dv = (Heightfield::classicNoise(u, v + e) - f) / e;
        steepest = std::max(steepest, std::hypot(du, dv));
    }
    EXPECT_LT(steepest, Heightfield::kNoiseSlopeBound);
    EXPECT_GT(steepest, 0.6 * Heightfield::kNoiseSlopeBound);  // the bound is not loose
}

// mayHaveGullies never says no where a gully could cut: discs of three radii on a grid across
// ravine country's edges, each checked on a 4 m grid inside it. It says no over most of the
// land, and yes in ravine country.
TEST(Heightfield, MayHaveGulliesNeverMissesRavineCountry) {
    const Heightfield hf(seeded(1));
    int no = 0, yes = 0;
    for (double cx = -6000.0; cx <= -3000.0; cx += 97.0) {
        for (double cz = 3000.0; cz <= 6000.0; cz += 89.0) {
            for (double r : {20.0, 46.0, 120.0}) {
                if (hf.mayHaveGullies(cx, cz, r)) {
                    ++yes;
                    continue;
                }
                ++no;
                for (double dx = -r; dx <= r; dx += 4.0) {
                    for (double dz = -r; dz <= r; dz += 4.0) {
                        if (std::hypot(dx, dz) > r) continue;
                        ASSERT_EQ(hf.ravineMask(cx + dx, cz + dz), 0.0)
                            << "disc " << cx << ", " << cz << " r " << r;
                    }
                }
            }
            if (hf.ravineMask(cx, cz) > 0.0) {
                ASSERT_TRUE(hf.mayHaveGullies(cx, cz, 0.0));
            }
        }
    }
    EXPECT_GT(no, yes);
    EXPECT_GT(yes, 0);
}

struct Stats {
    double mean = 0, sd = 0, meanSlope = 0;
};

Stats statistics(const Heightfield& hf, double x0, double z0) {
    // 60 x 60 km sampled every 300 m: several continent wavelengths.
    Stats s;
    double sum = 0, sum2 = 0, slope = 0;
    int n = 0;
    for (int j = 0; j < 200; ++j) {
        for (int i = 0; i < 200; ++i) {
            const double x = x0 + 300.0 * i, z = z0 + 300.0 * j;
            const double h = hf.height(x, z);
            sum += h;
            sum2 += h * h;
            if ((i + j) % 8 == 0) slope += 1.0 - hf.normal(x, z).y;
            ++n;
        }
    }
    s.mean = sum / n;
    s.sd = std::sqrt(sum2 / n - s.mean * s.mean);
    s.meanSlope = slope / (n / 8.0);
    return s;
}

TEST(Heightfield, FarFromOriginHasTheSameStatistics) {
    const Heightfield hf(seeded(5));
    const Stats near = statistics(hf, -30000.0, -30000.0);
    const Stats far = statistics(hf, 1e6 - 30000.0, 1e6 - 30000.0);
    // Same process, different region: means within 60 m, spreads and slopes within 35 %.
    EXPECT_NEAR(near.mean, far.mean, 60.0);
    EXPECT_NEAR(far.sd / near.sd, 1.0, 0.35);
    EXPECT_NEAR(far.meanSlope / near.meanSlope, 1.0, 0.35);
    EXPECT_GT(near.sd, 50.0);  // real relief, metres
}

TEST(Heightfield, PlausibleRangeAndMoistureInUnitInterval) {
    const Heightfield hf(seeded(6));
    for (int n = 0; n < 5000; ++n) {
        const double x = -25000.0 + 10.3 * n, z = 13000.0 - 7.9 * n;
        const double h = hf.height(x, z);
        ASSERT_TRUE(std::isfinite(h));
        ASSERT_GT(h, -400.0);
        ASSERT_LT(h, 2000.0);
        const double m = hf.moisture(x, z);
        ASSERT_GE(m, 0.0);
        ASSERT_LE(m, 1.0);
    }
}

}  // namespace
}  // namespace amb
