// BenchStats_test.cpp — the paired bootstrap interval of a ratio of mean errors: exact when the
// runs differ by a constant factor, centred on the ratio, about 95 % coverage on synthetic
// series with a known ratio, narrower with more frames, and frames paired by their number; the
// run folder's files read as errors per frame (terrain rows, the drawn column, the screen).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "app/bench/BenchStats.h"

namespace amb {
namespace {

// `frames` measured frames of `witnesses` errors each: a slowly varying level (consecutive
// frames correlated, as along a replay) times `scale`, plus independent noise.
FrameErrors series(int frames, int witnesses, double scale, std::mt19937_64& random,
                   double noise = 0.05) {
    std::normal_distribution<double> n(0.0, 1.0);
    FrameErrors out;
    double level = 0.3;
    for (int f = 0; f < frames; ++f) {
        level = 0.3 + 0.8 * (level - 0.3) + 0.02 * n(random);
        for (int w = 0; w < witnesses; ++w)
            out.add(10 * f, std::max(0.0, scale * level + noise * n(random)));
    }
    return out;
}

TEST(BenchStats, AConstantFactorIsExact) {
    std::mt19937_64 random(1);
    const FrameErrors other = series(60, 4, 1.0, random);
    FrameErrors ours;
    for (const auto& [frame, f] : other.byFrame) {
        ours.byFrame[frame] = {0.5 * f.first, f.second};
    }
    const RatioInterval r = pairedBootstrapRatio(ours, other);
    EXPECT_NEAR(r.ratio, 0.5, 1e-12);
    EXPECT_NEAR(r.lo, 0.5, 1e-12);
    EXPECT_NEAR(r.hi, 0.5, 1e-12);
    EXPECT_EQ(r.frames, 60);
    EXPECT_TRUE(r.excludesOne());
    // The same run against itself: 1, and the interval holds 1.
    const RatioInterval same = pairedBootstrapRatio(other, other);
    EXPECT_NEAR(same.ratio, 1.0, 1e-12);
    EXPECT_FALSE(same.excludesOne());
}

TEST(BenchStats, FramesArePairedByNumber) {
    FrameErrors a, b;
    a.add(0, 1.0);
    a.add(10, 3.0);
    a.add(20, 100.0);  // b did not measure frame 20: left out of both
    b.add(0, 2.0);
    b.add(10, 2.0);
    b.add(30, 100.0);
    const RatioInterval r = pairedBootstrapRatio(a, b);
    EXPECT_EQ(r.frames, 2);
    EXPECT_NEAR(r.ratio, 1.0, 1e-12);  // (1 + 3) / (2 + 2)
    EXPECT_EQ(pairedBootstrapRatio(a, FrameErrors{}).frames, 0);
    EXPECT_EQ(formatRatio(pairedBootstrapRatio(a, FrameErrors{})), "—");
}

// The interval holds the true ratio in about 95 % of replays (tolerance: 200 synthetic replays
// give a binomial standard deviation of 1.5 %; the block bootstrap is a little optimistic on
// short series, so 85 % to 99.5 % is accepted), and shrinks about as 1/sqrt(frames).
TEST(BenchStats, CoverageIsAboutNinetyFivePercent) {
    std::mt19937_64 random(7);
    const double trueRatio = 0.7;
    int covered = 0;
    const int replays = 200;
    for (int t = 0; t < replays; ++t) {
        const FrameErrors other = series(90, 4, 1.0, random);
        FrameErrors ours;
        // Ours: the same scene (the same level per frame), its own noise, 0.7 times the error.
        std::normal_distribution<double> n(0.0, 1.0);
        for (const auto& [frame, f] : other.byFrame)
            for (int w = 0; w < f.second; ++w)
                ours.add(frame, trueRatio * f.first / f.second + 0.03 * n(random));
        const RatioInterval r = pairedBootstrapRatio(ours, other, 1000, 100 + t);
        EXPECT_LE(r.lo, r.ratio);
        EXPECT_GE(r.hi, r.ratio);
        covered += r.lo <= trueRatio && trueRatio <= r.hi;
    }
    const double coverage = double(covered) / replays;
    EXPECT_GT(coverage, 0.85) << coverage;
    EXPECT_LT(coverage, 0.995) << coverage;

    std::mt19937_64 r2(3);
    const FrameErrors shortOther = series(40, 4, 1.0, r2), shortOurs = series(40, 4, 0.7, r2);
    const FrameErrors longOther = series(640, 4, 1.0, r2), longOurs = series(640, 4, 0.7, r2);
    const RatioInterval shortR = pairedBootstrapRatio(shortOurs, shortOther);
    const RatioInterval longR = pairedBootstrapRatio(longOurs, longOther);
    const double ratioOfWidths = (shortR.hi - shortR.lo) / (longR.hi - longR.lo);
    EXPECT_GT(ratioOfWidths, 2.0) << ratioOfWidths;  // sqrt(16) = 4, loosely
    EXPECT_LT(ratioOfWidths, 8.0) << ratioOfWidths;
}

TEST(BenchStats, TheSameSeedGivesTheSameInterval) {
    std::mt19937_64 random(5);
    const FrameErrors a = series(50, 3, 0.8, random), b = series(50, 3, 1.0, random);
    const RatioInterval x = pairedBootstrapRatio(a, b), y = pairedBootstrapRatio(a, b);
    EXPECT_EQ(x.lo, y.lo);
    EXPECT_EQ(x.hi, y.hi);
}

// A run folder's measurement files read back as errors per frame: reference.csv's terrain rows
// only (objects are not headline), its "total" or "drawn" column found by position or name;
// screen.csv's "error" by name, every kind; rows that do not parse are skipped, a missing file
// gives no frames.
TEST(BenchStats, RunFilesAreReadAsErrorsPerFrame) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / "ambience-bench-stats-files";
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "reference.csv") << "frame,witness,x,y,z,total,drawn\n"
                                            "0,ring_0,0,0,0,0.2,0.1\n"
                                            "0,ring_1,0,0,0,0.4,0.3\n"
                                            "0,car,0,0,0,9.0,9.0\n"
                                            "6,ring_0,0,0,0,0.6,nan\n"
                                            "x,ring_0,0,0,0,5.0,5.0\n";
    std::ofstream(dir / "screen.csv") << "frame,kind,error,bias,x,y,z,nx,ny,nz\n"
                                         "0,terrain,0.5,0,0,0,0,0,1,0\n"
                                         "0,object,0.1,0,0,0,0,0,1,0\n"
                                         "6,road,0.3,0,0,0,0,0,1,0\n";
    const FrameErrors sphere = readFrameErrors(dir.string(), true);
    ASSERT_EQ(sphere.byFrame.size(), 2u);
    EXPECT_NEAR(sphere.byFrame.at(0).first, 0.6, 1e-12);
    EXPECT_EQ(sphere.byFrame.at(0).second, 2);
    EXPECT_NEAR(sphere.mean(), 0.4, 1e-12);  // (0.2 + 0.4 + 0.6) / 3
    const FrameErrors drawn = readFrameErrors(dir.string(), true, true);
    ASSERT_EQ(drawn.byFrame.size(), 1u);  // frame 6's drawn is not a number
    EXPECT_NEAR(drawn.mean(), 0.2, 1e-12);
    const FrameErrors screen = readScreenErrors(dir.string());
    ASSERT_EQ(screen.byFrame.size(), 2u);
    EXPECT_NEAR(screen.byFrame.at(0).first, 0.6, 1e-12);
    EXPECT_NEAR(screen.mean(), 0.3, 1e-12);
    EXPECT_TRUE(readScreenErrors((dir / "nowhere").string()).byFrame.empty());
    std::ofstream(dir / "screen.csv") << "frame,kind,bias\n0,terrain,0.5\n";  // no error column
    EXPECT_TRUE(readScreenErrors(dir.string()).byFrame.empty());
    fs::remove_all(dir);
}

}  // namespace
}  // namespace amb
