// BenchTune.cpp — `ambience bench --tune`
// (BenchTune.h). Its own file: nothing else depends on it.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "app/bench/BenchResults.h"
#include "app/bench/BenchRunFolders.h"
#include "app/bench/BenchTune.h"
#include "lighting/AmbienceVolume.h"
#include "world/TextFile.h"

namespace amb::bench {

namespace fs = std::filesystem;

namespace {

// Coordinate descent over the scheduler's, the store's and the near field's main parameters, for
// the volume at the default capture budget: each parameter in turn tries the values around the current best,
// keeping a change only when the mean error over the tuning replays falls.
struct TuneParameter {
    std::vector<std::string> path;  // into the volume settings JSON
    double start;
    std::vector<double> factors;
    bool integer;
};

json withValue(json base, const std::vector<std::string>& path, double value, bool integer) {
    json* at = &base;
    for (std::size_t i = 0; i + 1 < path.size(); ++i) {
        if (!at->contains(path[i])) (*at)[path[i]] = json::object();
        at = &(*at)[path[i]];
    }
    if (integer)
        (*at)[path.back()] = int(std::lround(value));
    else
        (*at)[path.back()] = value;
    return base;
}

double valueAt(const json& j, const std::vector<std::string>& path, double fallback) {
    const json* at = &j;
    for (const auto& k : path) {
        if (!at->is_object() || !at->contains(k)) return fallback;
        at = &(*at)[k];
    }
    return at->is_number() ? at->get<double>() : fallback;
}

}  // namespace

void tune(const BenchOptions& o, const Runner& runner, int workers) {
    const auto replays = resolveReplays(o.tuneReplays);
    const AmbienceVolumeSettings d;
    const std::vector<TuneParameter> parameters = {
        {{"scheduler", "horizon_s"}, d.scheduler.horizon_s, {0.5, 2.0}, false},
        {{"scheduler", "corridorCells"}, d.scheduler.corridorCells, {0.5, 2.0}, false},
        {{"store", "blendTime_s"}, d.store.blendTime_s, {0.5, 2.0}, false},
        {{"scheduler", "finestRingCells"}, d.scheduler.finestRingCells, {0.5, 2.0}, false},
        {{"scheduler", "coarseRingCells"}, d.scheduler.coarseRingCells, {0.5, 2.0}, false},
        {{"store", "reachCells"}, double(d.store.reachCells), {2.0, 3.0}, true},
        // The two scales (lighting/NearField.h): what probes leave out, what points put back.
        {{"nearField", "captureRadius_m"}, d.capture.nearField.captureRadius_m, {0.75, 1.5}, false},
        {{"nearField", "radius_m"}, d.capture.nearField.radius_m, {0.75, 1.5}, false},
    };
    struct Candidate {
        std::string label;
        json volume;
        std::vector<double> errors;  // per replay
        double ms = 0.0, mean = 0.0;
    };
    std::vector<Candidate> tried;
    // Written as the tuning goes; a link planted at its name is replaced, not written through.
    const std::string tuneCsv = (fs::path(o.out) / "tune.csv").string();
    struct stat st {};
    if (::lstat(tuneCsv.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) ::unlink(tuneCsv.c_str());
    std::ofstream log(tuneCsv);
    log << "round,candidate,params,replay,mean_error,p95_error,pop_p99,ambience_ms_median,status\n";
    auto evaluate = [&](const json& volume, const std::string& label, int round) {
        std::vector<Job> jobs;
        for (const auto& r : replays) {
            Job j;
            j.replay = r;
            j.method = "volume";
            j.point.label = label;
            j.point.volume = volume;
            j.point.facesPerFrame = o.tuneBudget;
            j.point.params = pointParams(j.point);
            j.runDir = "tune/" + label + "__" + r.name;
            j.makesOracle = !fs::exists(fs::path(o.out) / "oracle" / (r.name + ".json"));
            jobs.push_back(j);
        }
        runJobs(jobs, runner, workers, "tune " + label);
        Candidate c{label, volume, {}, 0.0, 0.0};
        std::string params;
        flatten(volume, "volume", params);
        for (const Job& j : jobs) {
            const double e =
                j.ok ? number(j.report, {"measurement", "error", "mean"}) : std::nan("");
            const double ms = j.ok ? number(j.report, {"ambience", "ambience_ms", "median"}) : 0;
            c.errors.push_back(std::isfinite(e) ? e : std::numeric_limits<double>::infinity());
            c.mean += c.errors.back() / double(jobs.size());
            c.ms += ms / double(jobs.size());
            log << round << "," << label << "," << csvField(params) << "," << j.replay.name << ","
                << e << "," << number(j.report, {"measurement", "error", "p95"}) << ","
                << number(j.report, {"measurement", "pop", "p99"}) << "," << ms << ","
                << (j.ok ? "ok" : csvField("failed: " + j.error)) << "\n";
        }
        log << round << "," << label << "," << csvField(params) << ",(mean)," << c.mean << ",,,"
            << c.ms << ",\n";
        log.flush();
        tried.push_back(c);
        return c;
    };
    Candidate best = evaluate(json::object(), "t0", 0);
    std::fprintf(stderr, "tune: defaults give mean error %.4f\n", best.mean);
    int candidate = 0;
    for (int round = 1; round <= o.tuneRounds; ++round) {
        for (const TuneParameter& p : parameters) {
            const double current = valueAt(best.volume, p.path, p.start);
            for (double f : p.factors) {
                const double value =
                    p.integer ? std::max(1.0, std::round(current * f)) : current * f;
                if (value == current) continue;
                const Candidate c = evaluate(withValue(best.volume, p.path, value, p.integer),
                                             "t" + std::to_string(++candidate), round);
                std::fprintf(stderr, "tune: %s = %g -> mean error %.4f (best %.4f)\n",
                             p.path.back().c_str(), value, c.mean, best.mean);
                // A change must lower the mean error by a margin: smaller gains are within what
                // the witness sampling resolves, and they may cost lookups (wider search).
                if (c.mean < best.mean - o.tuneMinGain) best = c;
            }
        }
    }
    const std::string file = (fs::path(o.out) / "tuned-volume.json").string();
    writeTextFile(file, best.volume.dump(2) + "\n", "tuned settings");
    std::printf(
        "tuned settings %s: mean error %.4f over %s (defaults %.4f), budget %d face(s) "
        "per frame, ambience %.2f ms/frame: %s\n",
        best.label.c_str(), best.mean, o.tuneReplays.c_str(), tried.front().mean, o.tuneBudget,
        best.ms, file.c_str());
    // The best candidate for each replay on its own.
    for (std::size_t r = 0; r < replays.size(); ++r) {
        const Candidate* b = &tried.front();
        for (const Candidate& c : tried)
            if (c.errors[r] < b->errors[r]) b = &c;
        const std::string f = (fs::path(o.out) / ("tuned-" + replays[r].name + ".json")).string();
        writeTextFile(f, b->volume.dump(2) + "\n", "tuned settings");
        std::printf("  %s: best %s, mean error %.4f (defaults %.4f): %s\n", replays[r].name.c_str(),
                    b->label.c_str(), b->errors[r], tried.front().errors[r], f.c_str());
    }
    std::printf("  use with: ambience run --config %s\n", file.c_str());
}

}  // namespace amb::bench
