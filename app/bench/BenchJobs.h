// BenchJobs.h — what `ambience bench` runs: the options it was given, the replays it plays, and
// one job (a replay x a method x a parameter point) with its outcome. Shared by the files of
// app/bench: BenchCommand.cpp (the command line, --emit, --collect), BenchRunFolders.cpp (names
// and run folders), BenchRunner.cpp (running a job list), BenchResults.cpp (results.csv,
// summary.md, plots).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/bench/BenchSweep.h"
#include "lighting/BounceField.h"

namespace amb::bench {

using nlohmann::json;

struct ReplayRef {
    std::string name, path;  // path absolute
};

struct BenchOptions {
    std::string replays, methods, sweep, budgets, out = "out/bench";
    std::string oracle = "self";
    int referenceEvery = 6;
    int fullLengthBudget = 3;
    // Screen witnesses per reference frame; -1: kDefaultScreenWitnesses with the reference
    // oracle, none with the self-oracle.
    int screenWitnesses = -1;
    // What lights the reference's surfaces (lighting/BounceField.h; `run --reference-light`):
    // the bounce field over a lattice of 256 m within 500 m of each run's path by default.
    std::string referenceLight = "bounce";
    BounceSettings bounce;
    // What lights the surfaces of the methods' captures (`run --capture-light`): own or
    // reference (the reference's bounce field, a diagnostic).
    std::string captureLight = "own";
    int jobs = 0;
    int measureEvery = 10;
    int maxFrames = 0;
    int stride = 2;
    bool frames = false;  // render the main view too (slow on a software rasteriser)
    bool noFrames = false;
    bool tune = false;  // the removed --tune, refused with a pointer to `ambience tune`
    bool fromRuns = false;
    std::string backend = "auto";
    std::string emit;     // --emit DIR: write the runs as command lines, run nothing
    std::string collect;  // --collect DIR: the results of runs emitted there
    // With --collect: the replays as emitted (their files need not be here), and where the
    // runs were read from in the summary.
    std::vector<ReplayRef> resolved;
    std::vector<std::string> emitted;  // the run folders bench.json lists
    bool collected = false;
};

using Point = SweepPoint;  // app/bench/BenchSweep.h

// Screen witnesses per reference frame of a reference bench unless --screen-witnesses says
// otherwise: 32 random pixels a frame, the same pixels for every method (the generator is seeded
// by the frame), so methods are compared pixel for pixel; each pixel's reference is captured once
// per replay (the reference cache) and read back by every other method's run. Measured on the
// highway's first 300 frames (10 reference frames, docs/HISTORY.md "Reference light"): the mean
// over 32 a frame moves by +-19 % (95 %) from the choice of pixels alone, against +-25 % at 8 and
// +-11 % at 64; the frames add as much again, so the absolute screen figure of one short bench is
// a rough one, and what a bench compares, the methods on the same pixels, is the steadier part.
inline constexpr int kDefaultScreenWitnesses = 32;

struct Job {
    ReplayRef replay;
    std::string method;
    Point point;
    std::string runDir;  // relative to --out
    bool makesOracle = false;
    // Results.
    bool ok = false;
    std::string error;
    json report;
    double wall_s = 0.0;
};

}  // namespace amb::bench
