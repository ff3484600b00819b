// fuzz_replay — amb::parseReplay (world/Replay.h) on arbitrary text. An accepted replay must
// also survive what the program does with it: interpolation at any time inside and outside its
// span, and a write-read round trip that gives the same samples.
#include <cmath>

#include "FuzzSupport.h"
#include "world/Error.h"
#include "world/Replay.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    amb::Replay replay;
    try {
        replay = amb::parseReplay(amb::fuzz::asText(data, size), "fuzz.json");
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(!replay.samples.empty());
    const double duration_s = replay.duration_s();
    AMB_FUZZ_EXPECT(std::isfinite(duration_s) && duration_s >= 0.0);
    const double t0 = replay.samples.front().time_s;
    for (double f : {-0.5, 0.0, 0.123, 0.5, 0.999, 1.0, 2.0}) {
        const double t = t0 + f * duration_s;
        const amb::CameraSample s = replay.sampleAt(t);
        AMB_FUZZ_EXPECT(std::isfinite(s.position_m.x) && std::isfinite(s.position_m.y) &&
                        std::isfinite(s.position_m.z));
        AMB_FUZZ_EXPECT(std::isfinite(s.forward.x) && std::isfinite(s.up.y));
        const double tod = replay.timeOfDayAt_h(t);
        AMB_FUZZ_EXPECT(tod >= 0.0 && tod < 24.0);
    }
    // What the writer makes, the reader takes back unchanged.
    const amb::Replay again = amb::parseReplay(amb::formatReplay(replay), "round trip");
    AMB_FUZZ_EXPECT(again.samples.size() == replay.samples.size());
    for (std::size_t i = 0; i < replay.samples.size(); ++i) {
        AMB_FUZZ_EXPECT(again.samples[i].time_s == replay.samples[i].time_s);
        AMB_FUZZ_EXPECT(again.samples[i].position_m == replay.samples[i].position_m);
        AMB_FUZZ_EXPECT(again.samples[i].cut == replay.samples[i].cut);
    }
    return 0;
}
