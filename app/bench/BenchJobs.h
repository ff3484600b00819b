// BenchJobs.h — what `ambience bench` runs: the options it was given, the replays it plays, and
// one job (a replay x a method x a parameter point) with its outcome. Shared by the files of
// app/bench: BenchCommand.cpp (the command line, --emit, --collect), BenchRunFolders.cpp (names
// and run folders), BenchRunner.cpp (running a job list), BenchResults.cpp (results.csv,
// summary.md, plots) and BenchTune.cpp (--tune).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/bench/BenchSweep.h"

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
    int screenWitnesses = 0;
    int jobs = 0;
    int measureEvery = 10;
    int maxFrames = 0;
    int stride = 2;
    bool frames = false;  // render the main view too (slow on a software rasteriser)
    bool noFrames = false;
    bool tune = false;
    bool fromRuns = false;
    std::string tuneReplays = "highway-drive,mountain-drive,low-flight,stress-flight";
    int tuneRounds = 1;
    int tuneBudget = 1;  // faces per frame: the cost the tuning holds fixed
    double tuneMinGain = 0.002;
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
