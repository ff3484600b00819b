// BenchRunner.h — running `ambience bench`'s jobs: each run a child process `ambience run ...`
// (Runner: its command line and folder), the jobs of a list side by side on worker threads, each
// replay's runs after its oracle run (runJobs).
#pragma once

#include <string>
#include <vector>

#include "app/bench/BenchJobs.h"

namespace amb::bench {

struct Runner {
    std::string exe, out, backend;  // `out` absolute
    int measureEvery = 30, maxFrames = 0, stride = 2;
    bool frames = false;
    // The reference oracle (lighting/ReferenceOracle.h) for every run, and the capture budget
    // whose runs also capture the ideal volume for the error budget (the others report its
    // spacing and schedule terms as one).
    bool reference = false;
    int referenceEvery = 6;
    int idealBudget = 1;
    int screenWitnesses = 0;  // per reference frame, in the runs at idealBudget
    // `run --reference-light` and, for bounce, the lattice (--bounce-spacing, -reach, -face).
    std::string referenceLight = "bounce";
    double bounceSpacing_m = 256.0, bounceReach_m = 500.0;
    int bounceFace = 32;
    double bounceCanopy_m = 10.0;
    std::string captureLight = "own";  // `run --capture-light`, passed when not own
    // Runs above this many faces per frame play the first fullLengthBudget / faces of the replay.
    int fullLengthBudget = 64;

    std::string dirOf(const Job& job) const;  // absolute

    // The run's folder with its settings files and command line, without the outcome of an
    // earlier run there.
    void prepare(const Job& job) const;

    // `ambience run ...` for the job (absolute paths: the same line runs anywhere).
    std::vector<std::string> args(const Job& job) const;

    // Runs the job here, records its exit status as an emitted line does, and reads it back.
    void run(Job& job) const;
};

// How each run is started (the options every child gets), after checking those options.
Runner benchRunner(const BenchOptions& o, const std::vector<Point>& points);

// The runs: replays x methods x points, per replay the cheapest method first (it captures the
// oracle unless a saved one matches), every replay's oracle run at the front.
std::vector<Job> benchJobs(const std::vector<ReplayRef>& replays,
                           const std::vector<std::string>& methods,
                           const std::vector<Point>& points);

// Runs argv with stdout and stderr into `log`; returns the exit status (or -signal).
int spawnAndWait(const std::vector<std::string>& args, const std::string& log);

// "bench: <replay>/<method>/<point> FAILED: <error>", for a run that failed.
std::string failureLine(const std::string& title, const Job& j);

// Runs the jobs on `workers` threads; jobs of a replay wait for that replay's oracle job. This
// thread shows the progress (ProgressBar: a bar on a terminal, else a line every few seconds)
// and a line for each run that failed.
void runJobs(std::vector<Job>& jobs, const Runner& runner, int workers, const std::string& title);

}  // namespace amb::bench
