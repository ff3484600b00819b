// BenchStats.h — how sure a bench's "ours against another method" ratio is (no GL).
//
// Two runs of one replay are measured on the same frames at the same witnesses against the
// same oracle, so their errors pair up frame by frame. The ratio of their mean errors is given
// with a 95 % interval from a paired moving-block bootstrap over the measured frames: blocks of
// consecutive measured frames (errors of nearby frames are correlated: the camera has hardly
// moved) are drawn with replacement, the same blocks for both runs, until as many frames are
// drawn as were measured; the ratio of the resampled means is taken 2000 times, and the
// interval is its 2.5th to 97.5th percentile. Block length: ceil(n^(1/3)) frames, the usual
// order for a mean of a weakly dependent series. The resampling is seeded, so a summary is
// written the same way twice.
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace amb {

// Per measured frame: the sum of the errors at its witnesses and their count.
struct FrameErrors {
    std::map<int, std::pair<double, int>> byFrame;
    void add(int frame, double error) {
        auto& f = byFrame[frame];
        f.first += error;
        ++f.second;
    }
    double mean() const;  // over every witness; NaN when empty
};

// The headline witnesses of a run folder: the terrain rows ("ring_*") of reference.csv with
// the reference oracle, else measure.csv's per-frame mean error (every measured frame has the
// same witnesses). Read through the bounded, link-refusing reader; a file that is missing or
// unreadable gives no frames.
// With `drawn`, reference.csv's "drawn" column instead (the terrain witnesses at the drawn
// normal; witnesses without one are left out).
FrameErrors readFrameErrors(const std::string& runDir, bool reference, bool drawn = false);

// The screen witnesses of a run folder (screen.csv: random pixels of the main view, terrain,
// road and objects, each the error of the ambient as drawn there): the "error" column per frame.
// A run without the file gives no frames.
FrameErrors readScreenErrors(const std::string& runDir);

struct RatioInterval {
    double ratio = 0.0;         // mean(ours) / mean(other) over the frames both measured
    double lo = 0.0, hi = 0.0;  // 95 % interval
    int frames = 0;             // frames both measured (0: no interval)
    bool excludesOne() const { return frames > 0 && (hi < 1.0 || lo > 1.0); }
};

// The paired moving-block bootstrap above, over the frames both runs measured.
RatioInterval pairedBootstrapRatio(const FrameErrors& ours, const FrameErrors& other,
                                   int resamples = 2000, std::uint64_t seed = 20061);

// "0.62 [0.58, 0.66]" (or "—" without frames).
std::string formatRatio(const RatioInterval& r);

}  // namespace amb
