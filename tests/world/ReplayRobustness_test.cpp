// ReplayRobustness_test.cpp — inputs that the replay fuzzer (tests/fuzz/fuzz_replay) checks
// properties of, kept here as regression tests: the time of day stays in [0, 24) for any time,
// and what the writer makes the reader takes back.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "world/Error.h"
#include "world/Replay.h"

namespace amb {
namespace {

// A replay starting at midnight: a time a hair before the first sample gives hours of about
// -3e-18; fmod keeps the sign and adding 24 rounded to exactly 24.0, outside [0, 24).
TEST(ReplayRobustness, TimeOfDayJustBeforeMidnightWrapsToZero) {
    Replay rp;
    rp.timeOfDayStart_h = 0.0;
    rp.timeRate = 1.0;
    for (double t_s : {-1e-14, -1e-300, -0.0, 0.0, -3600.0 * 24.0, 3600.0 * 24.0}) {
        const double tod = rp.timeOfDayAt_h(t_s);
        EXPECT_GE(tod, 0.0) << t_s;
        EXPECT_LT(tod, 24.0) << t_s;
    }
    EXPECT_EQ(rp.timeOfDayAt_h(-1e-14), 0.0);
    // An hour before midnight is still 23 h (to a nanosecond of an hour).
    EXPECT_NEAR(rp.timeOfDayAt_h(-3600.0), 23.0, 1e-9);
}

}  // namespace
}  // namespace amb
