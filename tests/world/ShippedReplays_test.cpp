// ShippedReplays_test.cpp — the replays in replays/ read cleanly and still agree with the world
// they were recorded in (a change to the terrain or road code that moves the ground under a
// shipped replay fails here; regenerate with replays/make-replays.sh).
#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Heightfield.h"
#include "world/Replay.h"
#include "world/World.h"

namespace amb {
namespace {

std::string replayPath(const char* name) {
    return std::string(AMBIENCE_SOURCE_DIR) + "/replays/" + name + ".json";
}

// Where a replay stands to ravine country.
enum class Ravine {
    Away,   // none within 500 m of any sample: the figures tuned on it hold with or without gullies
    Shows,  // a gully under the camera
    Any,    // held out of tuning: it crosses whatever its world puts there, gullies included
};

struct Expect {
    const char* name;
    ReplayMode mode;
    double speedLo_mps, speedHi_mps;  // every step's speed, except across cuts
    double minDuration_s;
    int cuts;
    double staticHeight_m = 4.0;  // a static camera's eye above the ground
    Ravine ravine = Ravine::Away;
};

// Names the case in test listings (instead of a byte dump).
void PrintTo(const Expect& e, std::ostream* os) {
    *os << e.name;
}

class ShippedReplay : public testing::TestWithParam<Expect> {};

TEST_P(ShippedReplay, ReadsAndMatchesTheWorld) {
    const Expect e = GetParam();
    const Replay rp = readReplay(replayPath(e.name));
    EXPECT_EQ(rp.mode, e.mode);
    EXPECT_GE(rp.duration_s(), e.minDuration_s);
    const World world(rp.world);
    int cuts = 0;
    for (std::size_t i = 0; i < rp.samples.size(); ++i) {
        const CameraSample& s = rp.samples[i];
        const double ground = world.height(s.position_m.x, s.position_m.z);
        const double above = s.position_m.y - ground;
        switch (e.mode) {
            case ReplayMode::Drive:  // eye height 1.5 m over the road, the terrain flattened to it
                ASSERT_NEAR(above, 1.5, 0.5) << e.name << " sample " << i;
                break;
            case ReplayMode::Fly:  // never below the clearance
                ASSERT_GE(above, 20.0) << e.name << " sample " << i;
                break;
            case ReplayMode::Static:
                ASSERT_NEAR(above, e.staticHeight_m, 0.01) << e.name << " sample " << i;
                break;
        }
        if (i == 0) continue;
        if (s.cut) {
            ++cuts;
            continue;
        }
        const double v = glm::length(s.position_m - rp.samples[i - 1].position_m) / rp.step_s;
        ASSERT_GE(v, e.speedLo_mps - 1e-6) << e.name << " sample " << i;
        ASSERT_LE(v, e.speedHi_mps + 1e-6) << e.name << " sample " << i;
    }
    EXPECT_EQ(cuts, e.cuts);
    const Heightfield& hf = world.heightfield();
    if (e.ravine == Ravine::Any) return;
    if (e.ravine ==
        Ravine::Shows) {  // a gully at least 5 m deep within 30 m of the ground under the camera
        const glm::dvec3 p = rp.samples.front().position_m;
        double deepest = 0.0;
        for (double dx = -30.0; dx <= 30.0; dx += 1.0)
            for (double dz = -30.0; dz <= 30.0; dz += 1.0)
                deepest = std::max(deepest, hf.gullyDepth(p.x + dx, p.z + dz));
        EXPECT_GT(deepest, 5.0) << e.name;
        return;
    }
    // Ravine country keeps away from the tuning replays (600 m at its nearest), so the figures
    // measured on them hold with or without gullies: none within 500 m of any sample.
    for (std::size_t i = 0; i < rp.samples.size(); i += 60) {
        const glm::dvec3 p = rp.samples[i].position_m;
        for (double dx = -500.0; dx <= 500.0; dx += 100.0) {
            for (double dz = -500.0; dz <= 500.0; dz += 100.0) {
                if (std::hypot(dx, dz) > 500.0) continue;
                ASSERT_EQ(hf.ravineMask(p.x + dx, p.z + dz), 0.0)
                    << e.name << " sample " << i << " offset " << dx << ", " << dz;
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(
    Replays, ShippedReplay,
    testing::Values(
        Expect{"highway-drive", ReplayMode::Drive, 30.0, 30.0, 60.0, 0},
        Expect{"mountain-drive", ReplayMode::Drive, 15.0, 20.0, 60.0, 0},
        Expect{"low-flight", ReplayMode::Fly, 80.0, 80.0, 60.0, 0},
        Expect{"stress-flight", ReplayMode::Fly, 250.0, 250.0, 60.0, 1},
        Expect{"day-timelapse", ReplayMode::Static, 0.0, 0.0, 144.0, 0},
        Expect{"far-flight", ReplayMode::Fly, 120.0, 120.0, 40.0, 0},
        Expect{"ravine-dusk", ReplayMode::Static, 0.0, 0.0, 12.0, 0, 28.0, Ravine::Shows},
        Expect{"dusk-mountain-held-out", ReplayMode::Drive, 5.0, 16.0, 60.0, 0, 4.0, Ravine::Any},
        Expect{"hairpin-flight-held-out", ReplayMode::Fly, 70.0, 70.0, 50.0, 0, 4.0, Ravine::Any}),
    [](const testing::TestParamInfo<Expect>& info) {
        std::string n = info.param.name;
        for (char& c : n)
            if (c == '-') c = '_';
        return n;
    });

TEST(ShippedReplays, TimeLapseCoversADayAtRate600) {
    const Replay rp = readReplay(replayPath("day-timelapse"));
    EXPECT_NEAR(rp.timeRate, 600.0, 1e-9);
    EXPECT_GE(rp.duration_s() * rp.timeRate / 3600.0, 24.0 - 1e-9);
}

}  // namespace
}  // namespace amb
