// CaptureCore_test.cpp — the rules every capturing method shares (lighting/CaptureCore.h): the
// clock and the rate of the time of day across the 24 h wrap, jumps, the teleport rule and the
// probe it drops, the face budget (a probe over six frames at one face per frame, six probes in
// one frame at 36 faces), poisoned probes counted and never handed on, the fallback refreshed by
// the time of day and never NaN; and that the volume and a baseline, given the same captures,
// count the same faces, probes, rejections and teleports.
#include "lighting/CaptureCore.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "FakeCubeCapture.h"
#include "ShChecks.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"
#include "lighting/CubeMapProjector.h"
#include "world/Replay.h"

namespace amb {
namespace {

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;
using testing_support::Poison;

constexpr double kDt = 1.0 / 30.0;

// A request for the probe over (x, 0) with key (0, i, 0), i counting up.
struct Counter {
    std::int64_t next = 0;
    std::optional<ProbeRequest> operator()(const std::vector<ProbeKey>&) {
        ProbeRequest r;
        r.key = ProbeKey{0, next, 0};
        r.x_m = 10.0 * double(next++);
        return r;
    }
};

// An environment whose fallback scene is absurd (a broken sky model: 1e30 everywhere, finite
// texels whose SH leaves the range the store accepts; NaN texels the projection already zeroes).
class NanEnvironment final : public testing_support::FlatProbeEnvironment {
  public:
    bool broken = false;
    void fallbackCubeMap(double timeOfDay_h, int n, std::vector<float>& rgb) const override {
        FlatProbeEnvironment::fallbackCubeMap(timeOfDay_h, n, rgb);
        if (broken) std::fill(rgb.begin(), rgb.end(), 1e30f);
    }
};

TEST(CaptureCore, ClockRateWrapsAtMidnightAndJumpsAreSeen) {
    FakeCubeCapture capture(4);
    FlatProbeEnvironment environment;
    CaptureCore core(capture, environment, CaptureSettings{});
    EXPECT_DOUBLE_EQ(core.timeRate_hPerS(), CaptureSettings{}.defaultTimeRate_hPerS);
    // 23.9 h -> 0.1 h over 2 s: 0.2 h forward across midnight, 0.1 h per second.
    EXPECT_FALSE(core.beginFrame({0, 2, 0}, {0, 0, 0}, 23.9, 0.0).timeJump);
    EXPECT_FALSE(core.beginFrame({0, 2, 0}, {0, 0, 0}, 24.1, 2.0).timeJump);
    EXPECT_NEAR(core.timeRate_hPerS(), 0.1, 1e-12);
    EXPECT_NEAR(core.timeOfDay_h(), 0.1, 1e-12);
    EXPECT_DOUBLE_EQ(core.time_s(), 2.0);
    EXPECT_DOUBLE_EQ(core.lastJump_s(), -1.0);
    // Six hours in one frame is a jump: the rate keeps its value, the jump is dated.
    EXPECT_TRUE(core.beginFrame({0, 2, 0}, {0, 0, 0}, 6.1, 1.0).timeJump);
    EXPECT_NEAR(core.timeRate_hPerS(), 0.1, 1e-12);
    EXPECT_DOUBLE_EQ(core.lastJump_s(), 3.0);
    // A bad dt adds no time; a bad time of day keeps the last one.
    core.beginFrame({0, 2, 0}, {0, 0, 0}, std::nan(""), std::nan(""));
    EXPECT_DOUBLE_EQ(core.time_s(), 3.0);
    EXPECT_NEAR(core.timeOfDay_h(), 6.1, 1e-12);
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 6.1, -1.0);
    EXPECT_DOUBLE_EQ(core.time_s(), 3.0);
}

TEST(CaptureCore, TeleportIsAStepTheSpeedCannotExplainAndDropsTheProbe) {
    FakeCubeCapture capture(4);
    FlatProbeEnvironment environment;
    CaptureCore core(capture, environment, CaptureSettings{});
    Counter next;
    glm::dvec3 p(0.0);
    const glm::dvec3 v(30.0, 0.0, 0.0);
    for (int f = 0; f < 3; ++f, p += v * kDt) {
        EXPECT_FALSE(core.beginFrame(p, v, 12.0, kDt).teleport);
        core.captureFaces(std::ref(next));
    }
    ASSERT_TRUE(core.job());
    EXPECT_EQ(core.job()->facesDone, 3);
    // A 10 s hitch at 30 m/s moves 300 m: within 100 m + 3 x 30 m/s x 10 s, motion.
    p += v * 10.0;
    EXPECT_FALSE(core.beginFrame(p, v, 12.0, 10.0).teleport);
    EXPECT_TRUE(core.job());
    // 5 km in one frame is a teleport: counted, and the probe of the old place is dropped.
    const FrameEvents e = core.beginFrame(p + glm::dvec3(5000.0, 0.0, 3000.0), v, 12.0, kDt);
    EXPECT_TRUE(e.teleport);
    EXPECT_EQ(core.statistics().teleports, 1);
    EXPECT_EQ(core.abortedProbes(), 1);
    EXPECT_FALSE(core.job());
    // A non-finite camera is ignored, not a teleport.
    const double nan = std::nan("");
    EXPECT_FALSE(core.beginFrame({nan, nan, nan}, v, 12.0, kDt).teleport);
    EXPECT_EQ(core.statistics().teleports, 1);
}

// The camera's velocity as the frame loop reports it (app/frame/MethodStages.cpp): measured from
// the step itself, zero on the first frame and across a cut. Such a velocity explains any step,
// however long: the detector may not take it at its word.
struct StepVelocity {
    bool have = false;
    glm::dvec3 previous{0.0};
    glm::dvec3 operator()(const glm::dvec3& p, double dt, bool cut = false) {
        const glm::dvec3 v = have && dt > 0.0 && !cut ? (p - previous) / dt : glm::dvec3(0.0);
        have = true;
        previous = p;
        return v;
    }
};

// An unflagged jump of 9.9e7 m (a replay's coordinates reach 1e8 m) is a teleport, whether it
// reports its own step as the speed (as the frame loop does) or nothing; so is the way back, and
// a 5 km jump from a car at 30 m/s. The car's own steps before and after are motion.
TEST(CaptureCore, AHugeUnflaggedStepIsATeleportWhateverSpeedItReports) {
    for (const bool reportsStep : {true, false}) {
        SCOPED_TRACE(reportsStep ? "velocity from the step" : "no velocity");
        FakeCubeCapture capture(4);
        FlatProbeEnvironment environment;
        CaptureCore core(capture, environment, CaptureSettings{});
        StepVelocity velocity;
        glm::dvec3 p(0.0, 1.5, 0.0);
        const glm::dvec3 drive(30.0, 0.0, 0.0);
        int teleports = 0;
        auto frame = [&](const glm::dvec3& at) {
            const glm::dvec3 v = velocity(at, kDt);
            const bool t = core.beginFrame(at, reportsStep ? v : glm::dvec3(0.0), 12.0, kDt).teleport;
            teleports += t;
            return t;
        };
        for (int f = 0; f < 10; ++f, p += drive * kDt) EXPECT_FALSE(frame(p)) << f;
        const glm::dvec3 far = p + glm::dvec3(9.9e7, 0.0, 0.0);
        EXPECT_TRUE(frame(far));
        EXPECT_EQ(core.statistics().teleports, 1);
        EXPECT_TRUE(frame(p));  // and back
        for (int f = 0; f < 10; ++f) EXPECT_FALSE(frame(p += drive * kDt)) << f;
        EXPECT_TRUE(frame(p + glm::dvec3(3000.0, 0.0, -4000.0)));
        EXPECT_EQ(teleports, 3);
        EXPECT_EQ(core.statistics().teleports, 3);
    }
    // The fastest camera the rule believes in, its speed measured from its steps, only moves.
    FakeCubeCapture capture(4);
    FlatProbeEnvironment environment;
    CaptureCore core(capture, environment, CaptureSettings{});
    StepVelocity velocity;
    glm::dvec3 p(0.0, 500.0, 0.0);
    const glm::dvec3 v = kMaxCameraSpeed_mps * glm::normalize(glm::dvec3(3.0, 0.0, -4.0));
    for (int f = 0; f < 30; ++f, p += v * kDt) core.beginFrame(p, velocity(p, kDt), 12.0, kDt);
    EXPECT_EQ(core.statistics().teleports, 0);
}

// The steps of every shipped replay, at the strides runs use, reported as the frame loop reports
// them: the driving and flying is motion, and the stress flight's one cut is the one teleport.
TEST(CaptureCore, ShippedReplaysMoveWithoutTeleportsButAtTheirCuts) {
    const std::string dir = std::string(AMBIENCE_SOURCE_DIR) + "/replays/";
    for (const char* name : {"highway-drive", "mountain-drive", "low-flight", "stress-flight",
                             "far-flight", "day-timelapse", "ravine-dusk"}) {
        const Replay replay = readReplay(dir + name + ".json");
        for (const int stride : {1, 2, 30}) {
            SCOPED_TRACE(std::string(name) + " at stride " + std::to_string(stride));
            FakeCubeCapture capture(4);
            FlatProbeEnvironment environment;
            CaptureCore core(capture, environment, CaptureSettings{});
            StepVelocity velocity;
            const double dt = replay.step_s * stride;
            int cuts = 0;
            for (std::size_t i = 0; i < replay.samples.size(); i += std::size_t(stride)) {
                bool cut = false;  // a cut since the previous frame
                for (std::size_t j = i >= std::size_t(stride) ? i - stride + 1 : i; j <= i; ++j)
                    cut = cut || (i > 0 && replay.samples[j].cut);
                cuts += cut;
                const glm::dvec3& at = replay.samples[i].position_m;
                const double timeOfDay_h = replay.timeOfDayAt_h(replay.samples[i].time_s);
                const bool teleport =
                    core.beginFrame(at, velocity(at, dt, cut), timeOfDay_h, i ? dt : 0.0).teleport;
                EXPECT_EQ(teleport, cut) << "sample " << i;
            }
            EXPECT_EQ(cuts, std::string(name) == "stress-flight" ? 1 : 0);
            EXPECT_EQ(core.statistics().teleports, cuts);
        }
    }
}

TEST(CaptureCore, BudgetSpreadsAProbeOverFramesOrFillsAFrameWithProbes) {
    FlatProbeEnvironment environment;
    {
        FakeCubeCapture capture(4);
        CaptureSettings one;  // one face per frame, no prime
        one.primeProbes = 0;
        CaptureCore core(capture, environment, one);
        Counter next;
        for (int f = 0; f < 6; ++f) {
            core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
            core.captureFaces(std::ref(next));
            EXPECT_EQ(core.statistics().facesThisFrame, 1);
            const std::vector<CompletedProbe> done = core.takeCompleted();
            EXPECT_EQ(done.size(), f == 5 ? 1u : 0u);
            if (!done.empty()) {
                EXPECT_EQ(done[0].job.key, (ProbeKey{0, 0, 0}));
                EXPECT_DOUBLE_EQ(done[0].job.startTime_s, kDt);  // its first face's frame
            }
        }
        EXPECT_EQ(core.statistics().facesCaptured, 6);
        EXPECT_EQ(capture.calls().size(), 6u);
    }
    {
        FakeCubeCapture capture(4);
        CaptureSettings s;
        s.facesPerFrame = 36;
        s.primeProbes = 0;
        CaptureCore core(capture, environment, s);
        std::vector<std::size_t> busySeen;
        Counter counter;
        core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
        core.captureFaces([&](const std::vector<ProbeKey>& busy) {
            busySeen.push_back(busy.size());
            return counter(busy);
        });
        // Six whole probes, each asked for with the ones completed before it listed as busy.
        EXPECT_EQ(busySeen, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5}));
        const std::vector<CompletedProbe> done = core.takeCompleted();
        ASSERT_EQ(done.size(), 6u);
        // Each equals the projection of the same capture taken whole.
        FakeCubeCapture reference(4);
        const std::vector<float> cube = reference.captureAll({30.0, 2.0, 0.0}, 12.0);
        const ShRgb whole = toFloat(projectCubeMap(4, cube).sh);
        for (int k = 0; k < kShCoefficients; ++k)
            EXPECT_NEAR(done[3].sh.c[k].x, whole.c[k].x, 1e-5 * std::fabs(whole.c[0].x) + 1e-7);
    }
    {
        // Nothing to capture: the budget stays unused.
        FakeCubeCapture capture(4);
        CaptureCore core(capture, environment, CaptureSettings{});
        core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
        core.captureFaces([](const std::vector<ProbeKey>&) { return std::optional<ProbeRequest>(); });
        EXPECT_EQ(core.statistics().facesThisFrame, 0);
        EXPECT_TRUE(capture.calls().empty());
    }
}

// The prime (CaptureCore.h): in the first frame, primeProbes whole probes, each named as the
// budget's are and marked primed, then the budget's one face; nothing more until a teleport,
// which drops the probe in progress and primes again. A method that names nothing in the first
// frame is primed in the first frame it names a probe.
TEST(CaptureCore, PrimeCapturesWholeProbesAtTheFirstFrameAndAfterATeleport) {
    FlatProbeEnvironment environment;
    FakeCubeCapture capture(4);
    CaptureSettings s;
    s.primeProbes = 2;
    CaptureCore core(capture, environment, s);
    Counter next;
    EXPECT_FALSE(core.primeDue());
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
    EXPECT_TRUE(core.primeDue());
    core.captureFaces(std::ref(next));
    EXPECT_FALSE(core.primeDue());
    EXPECT_EQ(core.statistics().facesThisFrame, 2 * 6 + 1);
    EXPECT_EQ(core.statistics().primeFaces, 12);
    std::vector<CompletedProbe> done = core.takeCompleted();
    ASSERT_EQ(done.size(), 2u);
    for (int p = 0; p < 2; ++p) {
        EXPECT_TRUE(done[p].job.primed);
        EXPECT_EQ(done[p].job.key, (ProbeKey{0, p, 0}));
        // Each is the projection of the same capture taken whole.
        FakeCubeCapture reference(4);
        const ShRgb whole = toFloat(
            projectCubeMap(4, reference.captureAll({10.0 * p, 2.0, 0.0}, 12.0)).sh);
        EXPECT_LT(testing_support::maxDiff(done[p].sh, whole), 1e-5 * std::fabs(whole.c[0].x));
    }
    ASSERT_TRUE(core.job());  // the budget's face began the third
    EXPECT_EQ(core.job()->key, (ProbeKey{0, 2, 0}));
    // Later frames: the budget only; the probes they complete are not primes.
    for (int f = 0; f < 5; ++f) {
        core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
        core.captureFaces(std::ref(next));
        EXPECT_EQ(core.statistics().facesThisFrame, 1);
    }
    done = core.takeCompleted();
    ASSERT_EQ(done.size(), 1u);
    EXPECT_FALSE(done[0].job.primed);
    EXPECT_EQ(core.statistics().primeFaces, 12);
    // A teleport: the probe in progress is dropped, two more primes.
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
    core.captureFaces(std::ref(next));  // the fourth probe's first face
    core.beginFrame({9000, 2, 0}, {0, 0, 0}, 12.0, kDt);
    EXPECT_EQ(core.abortedProbes(), 1);
    core.captureFaces(std::ref(next));
    done = core.takeCompleted();
    ASSERT_EQ(done.size(), 2u);
    EXPECT_TRUE(done[0].job.primed && done[1].job.primed);
    EXPECT_EQ(core.statistics().primeFaces, 24);
    EXPECT_EQ(core.statistics().facesCaptured, 24 + 1 + 5 + 1 + 1);

    // Nothing named in the first frame: the prime waits for the first probe named.
    FakeCubeCapture idle(4);
    CaptureCore waiting(idle, environment, s);
    waiting.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
    waiting.captureFaces([](const std::vector<ProbeKey>&) { return std::optional<ProbeRequest>(); });
    EXPECT_TRUE(waiting.primeDue());
    EXPECT_EQ(waiting.statistics().facesThisFrame, 0);
    waiting.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
    Counter later;
    waiting.captureFaces(std::ref(later));
    EXPECT_FALSE(waiting.primeDue());
    EXPECT_EQ(waiting.statistics().primeFaces, 12);
    // primeProbes 0: the budget alone, from the first frame.
    FakeCubeCapture plain(4);
    s.primeProbes = 0;
    CaptureCore none(plain, environment, s);
    none.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
    Counter third;
    none.captureFaces(std::ref(third));
    EXPECT_EQ(none.statistics().facesThisFrame, 1);
    EXPECT_EQ(none.statistics().primeFaces, 0);
}

TEST(CaptureCore, PoisonedProbesAreCountedAndNeverHandedOn) {
    for (Poison kind : {Poison::NaN, Poison::Inf, Poison::Negative}) {
        FakeCubeCapture capture(4);
        capture.poisonEvery(2, kind);
        FlatProbeEnvironment environment;
        CaptureSettings s;
        s.facesPerFrame = 6;
        s.primeProbes = 0;
        CaptureCore core(capture, environment, s);
        Counter next;
        int handedOn = 0;
        for (int f = 0; f < 10; ++f) {
            core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
            core.captureFaces(std::ref(next));
            for (const CompletedProbe& c : core.takeCompleted()) {
                ++handedOn;
                for (const glm::vec3& v : c.sh.c) EXPECT_TRUE(std::isfinite(v.x + v.y + v.z));
            }
        }
        EXPECT_EQ(core.probesCompleted(), 10);
        EXPECT_EQ(core.statistics().rejectedProbes, capture.poisonedProbes());
        EXPECT_EQ(handedOn + capture.poisonedProbes(), 10);
        EXPECT_GT(capture.poisonedProbes(), 0);
    }
}

TEST(CaptureCore, FallbackFollowsTheTimeOfDayAndIsNeverNaN) {
    FakeCubeCapture capture(4);
    NanEnvironment environment;
    CaptureSettings s;
    s.fallbackRefresh_h = 0.5;
    CaptureCore core(capture, environment, s);
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0, kDt);
    EXPECT_TRUE(core.fallbackChanged());
    const ShRgb noon = core.fallback();
    EXPECT_GT(noon.c[0].x, 0.0f);
    // Less than the refresh interval: kept.
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.4, kDt);
    EXPECT_FALSE(core.fallbackChanged());
    // Night: recomputed, darker (the fake's sky follows the time of day).
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.2, kDt);
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 12.0 + 0.2 * 3, kDt);
    EXPECT_TRUE(core.fallbackChanged());
    // A broken fallback scene keeps the last good value.
    environment.broken = true;
    const ShRgb before = core.fallback();
    core.beginFrame({0, 2, 0}, {0, 0, 0}, 13.5, kDt);
    EXPECT_FALSE(core.fallbackChanged());
    for (int k = 0; k < kShCoefficients; ++k) EXPECT_EQ(core.fallback().c[k], before.c[k]);
}

// The volume and a baseline share the core: on the same moving camera, with the same poisoned
// captures and a teleport, they count faces, rejections and teleports alike.
TEST(CaptureCore, VolumeAndBaselineCountAlike) {
    FlatProbeEnvironment environment;
    FakeCubeCapture volumeCapture(4), gridCapture(4);
    volumeCapture.poisonEvery(3, Poison::NaN);
    gridCapture.poisonEvery(3, Poison::NaN);
    AmbienceVolumeSettings vs;
    BaselineSettings bs;
    vs.capture.facesPerFrame = bs.capture.facesPerFrame = 2;
    AmbienceVolume volume(volumeCapture, environment, vs);
    ScrollingGridMethod grid(gridCapture, environment, bs);
    glm::dvec3 p(0.0, 2.0, 0.0);
    const glm::dvec3 v(20.0, 0.0, 0.0);
    for (int f = 0; f < 120; ++f) {
        if (f == 60) p += glm::dvec3(20000.0, 0.0, 0.0);  // a cut
        for (AmbienceMethod* m : {static_cast<AmbienceMethod*>(&volume),
                                  static_cast<AmbienceMethod*>(&grid)}) {
            m->predictStage(p, v, 12.0, kDt);
            m->captureStage();
            m->storeStage();
        }
        p += v * kDt;
    }
    const MethodStatistics a = volume.methodStatistics(), b = grid.methodStatistics();
    // The budget's 2 a frame, and a prime of four whole probes at the first frame and the cut.
    const int primes = 2 * CaptureSettings{}.primeProbes * 6;
    EXPECT_EQ(a.primeFaces, primes);
    EXPECT_EQ(b.primeFaces, primes);
    EXPECT_EQ(a.facesCaptured, 240 + primes);
    EXPECT_EQ(b.facesCaptured, 240 + primes);
    EXPECT_EQ(a.teleports, 1);
    EXPECT_EQ(b.teleports, 1);
    EXPECT_EQ(a.rejectedProbes, volumeCapture.poisonedProbes());
    EXPECT_EQ(b.rejectedProbes, gridCapture.poisonedProbes());
    EXPECT_GT(a.rejectedProbes, 0);
}

}  // namespace
}  // namespace amb
