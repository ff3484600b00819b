// BenchResults.cpp — results.csv, summary.md and the plots of `ambience bench` (BenchResults.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include "app/bench/BenchCollect.h"
#include "app/bench/BenchResults.h"
#include "app/bench/BenchRunner.h"
#include "app/bench/BenchStats.h"
#include "world/DataPaths.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb::bench {

namespace fs = std::filesystem;

namespace {

// The object at `key` of `j`, or an empty object (a report read back may hold anything).
const json& objectAt(const json& j, const char* key) {
    static const json empty = json::object();
    if (!j.is_object()) return empty;
    const auto it = j.find(key);
    return it != j.end() && it->is_object() ? *it : empty;
}

// The string at `key` of `j`, or `fallback`.
std::string stringAt(const json& j, const char* key, const std::string& fallback) {
    if (!j.is_object()) return fallback;
    const auto it = j.find(key);
    return it != j.end() && it->is_string() ? it->get<std::string>() : fallback;
}

const std::vector<std::string> kColumns = {"replay",
                                           "method",
                                           "point",
                                           "params",
                                           "status",
                                           "error_message",
                                           "frames",
                                           "measured_frames",
                                           "error_mean",
                                           "error_p50",
                                           "error_p95",
                                           "error_max",
                                           "error_ring0_mean",
                                           "error_ring1_mean",
                                           "error_ring2_mean",
                                           "error_ring3_mean",
                                           "error_ring0_p95",
                                           "error_ring1_p95",
                                           "error_ring2_p95",
                                           "error_ring3_p95",
                                           "error_ring0_max",
                                           "error_ring1_max",
                                           "error_ring2_max",
                                           "error_ring3_max",
                                           "pop_p99",
                                           "pop_max",
                                           "pop_move_p99",
                                           "pop_move_max",
                                           "ambience_ms_median",
                                           "ambience_ms_p95",
                                           "frame_ms_median",
                                           "frame_ms_p95",
                                           "predict_ms_median",
                                           "predict_ms_p95",
                                           "capture_ms_median",
                                           "capture_ms_p95",
                                           "store_ms_median",
                                           "store_ms_p95",
                                           "interpolate_ms_median",
                                           "interpolate_ms_p95",
                                           "lookup_ms_median",
                                           "lookup_ms_p95",
                                           "share_of_frame",
                                           "faces_per_s",
                                           "faces_captured",
                                           "probes_max",
                                           "probes_end",
                                           "bytes_max",
                                           "bytes_end",
                                           "teleports",
                                           "rejected_probes",
                                           "mean_speed_mps",
                                           "oracle_s",
                                           "oracle",
                                           "self_error_mean",
                                           "budget_witnesses",
                                           "budget_total_rms",
                                           "budget_truncation",
                                           "budget_capture",
                                           "budget_spacing",
                                           "budget_schedule",
                                           "budget_closure",
                                           "car_error_mean",
                                           "tree_base_error_mean",
                                           "tree_crown_error_mean",
                                           "car_drawn_error_mean",
                                           "tree_base_drawn_error_mean",
                                           "tree_crown_drawn_error_mean",
                                           "screen_error_mean",
                                           "screen_terrain_error_mean",
                                           "screen_road_error_mean",
                                           "screen_object_error_mean",
                                           "screen_witnesses",
                                           "drawn_error_mean",
                                           "drawn_error_p95",
                                           "drawn_witnesses",
                                           "drawn_under_crown_error_mean",
                                           "drawn_under_crown_witnesses",
                                           "drawn_hidden_witnesses",
                                           "drawn_budget_witnesses",
                                           "drawn_budget_far_field",
                                           "drawn_budget_patch",
                                           "drawn_budget_model",
                                           "drawn_budget_truncation",
                                           "drawn_budget_closure",
                                           "drawn_per_point_error_mean",
                                           "drawn_bias_mean",
                                           "drawn_at_point_bias_mean",
                                           "drawn_scene_bias_mean",
                                           "drawn_placed_bias_mean",
                                           "reference_s",
                                           "wall_s",
                                           "run_dir"};

std::map<std::string, std::string> resultRow(const Job& job) {
    std::map<std::string, std::string> row;
    auto put = [&](const std::string& key, double v) {
        if (!std::isfinite(v)) return;
        char text[64];
        std::snprintf(text, sizeof(text), "%.6g", v);
        row[key] = text;
    };
    row["replay"] = job.replay.name;
    row["method"] = job.method;
    row["point"] = job.point.label;
    row["params"] = job.point.params;
    row["status"] = job.ok ? "ok" : "failed";
    row["error_message"] = job.error;
    row["run_dir"] = job.runDir;
    put("wall_s", job.wall_s);
    if (!job.ok) return row;
    const json& r = job.report;
    put("frames", number(r, {"frameCount"}));
    const json m = objectAt(r, "measurement");
    put("measured_frames", number(m, {"measuredFrames"}));
    put("error_mean", number(m, {"error", "mean"}));
    put("error_p50", number(m, {"error", "p50"}));
    put("error_p95", number(m, {"error", "p95"}));
    put("error_max", number(m, {"error", "max"}));
    if (m.contains("errorByRing") && m["errorByRing"].is_array()) {
        for (std::size_t ring = 0; ring < m["errorByRing"].size() && ring < 4; ++ring) {
            const json& e = m["errorByRing"][ring];
            const std::string name = "error_ring" + std::to_string(ring);
            put(name + "_mean", number(e, {"mean"}));
            put(name + "_p95", number(e, {"p95"}));
            put(name + "_max", number(e, {"max"}));
        }
    }
    put("pop_p99", number(m, {"pop", "p99"}));
    put("pop_max", number(m, {"pop", "max"}));
    put("pop_move_p99", number(m, {"pop_move", "p99"}));
    put("pop_move_max", number(m, {"pop_move", "max"}));
    put("mean_speed_mps", number(m, {"meanSpeed_mps"}));
    put("oracle_s", number(m, {"oracle_s"}));
    row["oracle"] = stringAt(m, "oracle", "self");
    if (m.contains("reference")) {
        const json& ref = m["reference"];
        const json& b = objectAt(ref, "budget");
        put("self_error_mean", number(b, {"selfError", "mean"}));
        put("budget_witnesses", number(b, {"count"}));
        put("budget_total_rms", number(b, {"rmsTotal"}));
        for (const char* term : {"truncation", "capture", "spacing", "schedule", "closure"})
            put(std::string("budget_") + term, number(b, {term}));
        for (const char* kind : {"car", "tree_base", "tree_crown"}) {
            put(std::string(kind) + "_error_mean", number(ref, {"objects", kind, "error", "mean"}));
            put(std::string(kind) + "_drawn_error_mean",
                number(ref, {"objects", kind, "drawn", "mean"}));
        }
        put("reference_s", number(ref, {"reference_s"}));
        if (number(ref, {"drawn", "error", "count"}) > 0) {
            put("drawn_error_mean", number(ref, {"drawn", "error", "mean"}));
            put("drawn_error_p95", number(ref, {"drawn", "error", "p95"}));
            put("drawn_witnesses", number(ref, {"drawn", "error", "count"}));
            put("drawn_under_crown_error_mean", number(ref, {"drawn", "underCrown", "mean"}));
            put("drawn_under_crown_witnesses", number(ref, {"drawn", "underCrown", "count"}));
            put("drawn_hidden_witnesses", number(ref, {"drawn", "hidden"}));
            if (number(ref, {"drawn", "budget", "count"}) > 0) {
                put("drawn_budget_witnesses", number(ref, {"drawn", "budget", "count"}));
                put("drawn_budget_far_field", number(ref, {"drawn", "budget", "farField"}));
                put("drawn_budget_patch", number(ref, {"drawn", "budget", "patch"}));
                put("drawn_budget_model", number(ref, {"drawn", "budget", "model"}));
                put("drawn_budget_truncation", number(ref, {"drawn", "budget", "truncation"}));
                put("drawn_budget_closure", number(ref, {"drawn", "budget", "closure"}));
                put("drawn_per_point_error_mean", number(ref, {"drawn", "budget", "perPoint"}));
                put("drawn_bias_mean", number(ref, {"drawn", "budget", "drawnBias"}));
                put("drawn_at_point_bias_mean", number(ref, {"drawn", "budget", "atPointBias"}));
                put("drawn_scene_bias_mean", number(ref, {"drawn", "budget", "sceneBias"}));
                put("drawn_placed_bias_mean", number(ref, {"drawn", "budget", "placedBias"}));
            }
        }
        if (number(ref, {"screen", "error", "count"}) > 0) {
            put("screen_error_mean", number(ref, {"screen", "error", "mean"}));
            put("screen_witnesses", number(ref, {"screen", "error", "count"}));
            for (const char* kind : {"terrain", "road", "object"})
                if (number(ref, {"screen", kind, "count"}) > 0)
                    put(std::string("screen_") + kind + "_error_mean",
                        number(ref, {"screen", kind, "mean"}));
        }
    }
    put("ambience_ms_median", number(r, {"ambience", "ambience_ms", "median"}));
    put("ambience_ms_p95", number(r, {"ambience", "ambience_ms", "p95"}));
    put("frame_ms_median", number(r, {"frame_ms", "median"}));
    put("frame_ms_p95", number(r, {"frame_ms", "p95"}));
    for (const char* stage : {"predict", "capture", "store", "interpolate"}) {
        put(std::string(stage) + "_ms_median", number(r, {"stages_ms", stage, "median"}));
        put(std::string(stage) + "_ms_p95", number(r, {"stages_ms", stage, "p95"}));
    }
    put("lookup_ms_median", number(r, {"ambience", "lookup_ms", "median"}));
    put("lookup_ms_p95", number(r, {"ambience", "lookup_ms", "p95"}));
    put("share_of_frame", number(r, {"ambience", "shareOfFrameTime"}));
    put("faces_per_s", number(r, {"ambience", "facesPerSecond"}));
    put("faces_captured", number(r, {"ambience", "facesCaptured"}));
    put("probes_max", number(r, {"ambience", "anchorsMax"}));
    put("probes_end", number(r, {"ambience", "anchorsEnd"}));
    put("bytes_max", number(r, {"ambience", "bytesMax"}));
    put("bytes_end", number(r, {"ambience", "bytesEnd"}));
    put("teleports", number(r, {"ambience", "teleports"}));
    put("rejected_probes", number(r, {"ambience", "rejectedProbes"}));
    return row;
}

std::string fmt(double v, const char* format) {
    if (!std::isfinite(v)) return "—";
    char text[64];
    std::snprintf(text, sizeof(text), format, v);
    return text;
}

// With --budgets: per replay, each method's mean error and ambience ms at each budget (the
// default point's family), ours against the best other method at that budget, and the Pareto
// front over every run of the replay (no other run both cheaper and more accurate).
// The headline error of a run over its measured frames up to `lastFrame`, from the run's CSV:
// the terrain witnesses of reference.csv with the reference oracle, else measure.csv's
// per-frame means (every measured frame has the same witnesses). NaN without data.
double errorUpTo(const std::string& dir, const Job& j, int lastFrame) {
    const bool reference =
        stringAt(objectAt(j.report, "measurement"), "oracle", "") == "reference";
    std::stringstream in;
    try {
        in.str(readTextFile(
            (fs::path(dir) / j.runDir / (reference ? "reference.csv" : "measure.csv")).string(),
            "measurement file", kMaxOracleFileBytes, Links::Refuse));
    } catch (const InputError&) {
        return std::nan("");
    }
    std::string line;
    if (!std::getline(in, line)) return std::nan("");
    double sum = 0.0;
    std::size_t count = 0;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
        if (f.size() < 6) continue;
        if (std::atoi(f[0].c_str()) > lastFrame) continue;
        if (reference && f[1].rfind("ring_", 0) != 0) continue;  // objects are not headline
        const double e = std::atof(f[reference ? 5 : 4].c_str());
        if (std::isfinite(e)) sum += e, ++count;
    }
    return count ? sum / double(count) : std::nan("");
}

// What a ratio compares.
enum class Measured { Sphere, Drawn, Screen };

// Our run against another of the same replay: the ratio of mean errors over the frames both
// measured, with its paired bootstrap 95 % interval (BenchStats.h), of what `Measured` names:
// the headline witnesses over the sphere of normals, the terrain witnesses at the drawn normal
// (reference runs only), or the screen witnesses.
RatioInterval ratioAgainst(const std::string& dir, const Job& ours, const Job& other,
                           Measured measured = Measured::Sphere) {
    const bool reference =
        stringAt(objectAt(ours.report, "measurement"), "oracle", "") == "reference";
    const auto errors = [&](const Job& j) {
        const std::string runDir = (fs::path(dir) / j.runDir).string();
        return measured == Measured::Screen
                   ? readScreenErrors(runDir)
                   : readFrameErrors(runDir, reference, measured == Measured::Drawn);
    };
    return pairedBootstrapRatio(errors(ours), errors(other));
}

void writeBudgetSection(std::ostream& out, const std::vector<Job>& jobs,
                        const std::vector<std::string>& replays, int fullLengthBudget,
                        const std::string& dir) {
    std::vector<int> budgets;
    std::vector<std::string> methods;
    for (const Job& j : jobs) {
        if (j.point.family.empty()) return;  // no --budgets
        if (std::find(budgets.begin(), budgets.end(), j.point.facesPerFrame) == budgets.end())
            budgets.push_back(j.point.facesPerFrame);
        if (std::find(methods.begin(), methods.end(), j.method) == methods.end())
            methods.push_back(j.method);
    }
    std::sort(budgets.begin(), budgets.end());
    auto errorOf = [](const Job& j) {
        return number(objectAt(j.report, "measurement"), {"error", "mean"});
    };
    auto msOf = [](const Job& j) { return number(j.report, {"ambience", "ambience_ms", "median"}); };
    out << "## Budget: error against cost\n\n";
    out << "Each cell: mean error / ambience ms per frame (median), default settings at each "
           "capture budget (faces per frame). Ours / best other = our mean error over the "
           "lowest of the other methods' at that budget, over the frames both measured, with "
           "its paired bootstrap 95 % interval. Runs above "
        << fullLengthBudget
        << " faces per frame play the first (" << fullLengthBudget
        << " / faces) of each replay, every method alike.\n\n";
    for (const std::string& replay : replays) {
        out << "### " << replay << "\n\n| faces per frame |";
        for (const auto& m : methods) out << " " << (m == "volume" ? "**volume (ours)**" : m) << " |";
        out << " ours / best other |\n|---|";
        for (std::size_t i = 0; i <= methods.size(); ++i) out << "---|";
        out << "\n";
        for (int b : budgets) {
            out << "| " << b << " |";
            double best = std::nan("");
            const Job *oursJob = nullptr, *bestJob = nullptr;
            for (const auto& m : methods) {
                const Job* found = nullptr;
                for (const Job& j : jobs)
                    if (j.replay.name == replay && j.method == m && j.point.family == "default" &&
                        j.point.facesPerFrame == b && j.ok)
                        found = &j;
                if (!found) {
                    out << " — |";
                    continue;
                }
                const double e = errorOf(*found);
                out << " " << fmt(e, "%.4f") << " / " << fmt(msOf(*found), "%.2f") << " |";
                if (m == "volume") oursJob = found;
                else if (std::isfinite(e) && !(e >= best)) best = e, bestJob = found;
            }
            out << " **"
                << (oursJob && bestJob ? formatRatio(ratioAgainst(dir, *oursJob, *bestJob)) : "—")
                << "** |\n";
        }
        // Runs above the full-length budget play a share of the replay: every run is also
        // measured over the frames all of them play, and the Pareto front is taken on that.
        int common = std::numeric_limits<int>::max();
        std::vector<const Job*> runs;
        for (const Job& j : jobs)
            if (j.replay.name == replay && j.ok && std::isfinite(msOf(j))) {
                runs.push_back(&j);
                common = std::min(common, int(number(j.report, {"frameCount"})) - 1);
            }
        std::map<const Job*, double> prefix;
        for (const Job* j : runs) prefix[j] = errorUpTo(dir, *j, common);
        out << "\nOver the frames every budget plays (0 to " << common
            << "), mean error: ";
        for (int b : budgets) {
            out << (b == budgets.front() ? "" : "; ") << b << " faces:";
            for (const auto& m : methods)
                for (const Job* j : runs)
                    if (j->method == m && j->point.family == "default" &&
                        j->point.facesPerFrame == b)
                        out << " " << (m == "volume" ? "**ours**" : m) << " "
                            << fmt(prefix[j], "%.3f");
        }
        std::vector<const Job*> front;
        for (const Job* a : runs) {
            if (!std::isfinite(prefix[a])) continue;
            bool dominated = false;
            for (const Job* b : runs) {
                if (!std::isfinite(prefix[b])) continue;
                const bool noWorse = msOf(*b) <= msOf(*a) && prefix[b] <= prefix[a];
                const bool better = msOf(*b) < msOf(*a) || prefix[b] < prefix[a];
                if (b != a && noWorse && better) dominated = true;
            }
            if (!dominated) front.push_back(a);
        }
        std::sort(front.begin(), front.end(),
                  [&](const Job* a, const Job* b) { return msOf(*a) < msOf(*b); });
        out << "\n\nPareto front over those frames (cheapest first): ";
        for (std::size_t i = 0; i < front.size(); ++i)
            out << (i ? ", " : "") << front[i]->method << " " << front[i]->point.label << " ("
                << fmt(prefix[front[i]], "%.3f") << " at " << fmt(msOf(*front[i]), "%.2f")
                << " ms)";
        out << "\n\n";
    }
}

// True for a job whose budgets the budget sections show: the default point of `replay` (at the
// ideal budget when the bench ran several capture budgets), run to the end.
bool budgetPoint(const Job& j, const std::string& replay, int idealBudget) {
    if (j.replay.name != replay || !j.ok) return false;
    if (j.point.family.empty()) return j.point.label == "default";
    return j.point.family == "default" && j.point.facesPerFrame == idealBudget;
}

// With the reference oracle: per replay, the error budget of each method at the default point
// of the ideal budget (RMS over the terrain witnesses of the reference frames), the errors on
// objects, and the pop along the car.
void writeErrorBudgetSection(std::ostream& out, const std::vector<Job>& jobs,
                             const std::vector<std::string>& replays, int idealBudget) {
    bool any = false;
    for (const Job& j : jobs)
        any |= j.ok && objectAt(j.report, "measurement").contains("reference");
    if (!any) return;
    out << "## Error budget against the reference oracle\n\n"
           "RMS over the terrain witnesses of the reference frames, each term relative to the "
           "reference irradiance (lighting/ReferenceOracle.h): **a** SH order-2 truncation, "
           "**b** capture resolution and scene simplification (16 x 16 coarse capture against "
           "the 64 x 64 full scene), **c** spacing and interpolation (an ideal volume of fresh "
           "captures at the lattice points the method reads, against a capture at the point), "
           "**d** scheduling, staleness and blending (the method against its ideal volume). "
           "Closure = (a² + b² + c² + d²) / total²: 1 when the terms add up as squares. Methods "
           "without a lattice show c + d in column d. Objects: mean error against the reference "
           "at the car (1 m above its ground point) and at tree bases and crowns within 6-48 m, "
           "at the drawn normal (the object's SH through the normal of the surface the witness "
           "stands for: a tree's trunk and crown facing the camera, the car's roof; a trunk "
           "takes the share its crown leaves, as the draw gives it), then in brackets over the "
           "sphere of normals. "
           "Screen: the screen-weighted mean error, at random pixels of the main view (terrain, "
           "road, plants and the car), of the ambient irradiance as the draw applies it against "
           "the reference at that surface point and normal (terrain / road / object means in "
           "brackets). Pop moving: along the car.\n\n";
    for (const std::string& replay : replays) {
        out << "### " << replay << "\n\n| method | total (RMS) | a truncation | b capture | "
               "c spacing | d schedule | closure | dominant | mean error | self-oracle error | "
               "car | tree base | tree crown | screen (terrain / road / object) | "
               "pop moving p99 / max |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for (const Job& j : jobs) {
            if (!budgetPoint(j, replay, idealBudget)) continue;
            const json m = objectAt(j.report, "measurement");
            if (!m.contains("reference")) continue;
            const json& ref = m["reference"];
            const json b = objectAt(ref, "budget");
            const double terms[4] = {number(b, {"truncation"}), number(b, {"capture"}),
                                     number(b, {"spacing"}), number(b, {"schedule"})};
            const char* names[4] = {"a", "b", "c", "d"};
            int dominant = 0;
            for (int t = 1; t < 4; ++t)
                if (std::isfinite(terms[t]) && !(terms[t] <= terms[dominant])) dominant = t;
            out << "| " << (j.method == "volume" ? "**volume (ours)**" : j.method) << " | "
                << fmt(number(b, {"rmsTotal"}), "%.4f");
            for (double t : terms) out << " | " << fmt(t, "%.4f");
            out << " | " << fmt(number(b, {"closure"}), "%.2f") << " | " << names[dominant]
                << " | " << fmt(number(b, {"error", "mean"}), "%.4f") << " | "
                << fmt(number(b, {"selfError", "mean"}), "%.4f");
            for (const char* kind : {"car", "tree_base", "tree_crown"})
                out << " | " << fmt(number(ref, {"objects", kind, "drawn", "mean"}), "%.3f") << " ("
                    << fmt(number(ref, {"objects", kind, "error", "mean"}), "%.3f") << ")";
            const auto screenMean = [&](const char* kind) {
                return number(ref, {"screen", kind, "count"}) > 0
                           ? number(ref, {"screen", kind, "mean"})
                           : std::nan("");
            };
            out << " | " << fmt(screenMean("error"), "%.3f") << " ("
                << fmt(screenMean("terrain"), "%.2f") << " / " << fmt(screenMean("road"), "%.2f")
                << " / " << fmt(screenMean("object"), "%.2f") << ")";
            out << " | " << fmt(number(m, {"pop_move", "p99"}), "%.4f") << " / "
                << fmt(number(m, {"pop_move", "max"}), "%.3f") << " |\n";
        }
        out << "\n";
    }
    out << "Plot: `error-budget.png` (squared terms stacked, per replay and method).\n\n";
}

// With the reference oracle and the ideal volume: per replay, the drawn-normal error of each
// method split into terms that add up to it (DrawnBudget, lighting/Metrics.h).
void writeDrawnBudgetSection(std::ostream& out, const std::vector<Job>& jobs,
                             const std::vector<std::string>& replays, int idealBudget) {
    bool any = false;
    for (const Job& j : jobs)
        any |= j.ok && number(objectAt(j.report, "measurement"),
                              {"reference", "drawn", "budget", "count"}) > 0;
    if (!any) return;
    out << "## Error budget at the drawn normal\n\n"
           "The mean error at the drawn normal (terrain witnesses) split into terms that add up "
           "to it, each what one more ideal stage of the draw's path takes off the error: "
           "**far field** (the method's interpolated probes against fresh captures of the far "
           "scene at the drawn patch's four corners, or its cell's vertices where it is lit "
           "per vertex, the near field and patch mean kept), "
           "**patch** (the patch's blend of its corners against the same path at the witness' "
           "own point and surface normal), **model** (what the ambience model misses at a point: "
           "the coarse capture scene and its lighting, the near field's spheres and ground), "
           "**truncation** (the reference's own order-2 SH at the normal). Closure = sum of the "
           "terms over the drawn mean: 1 by construction (a check, not a finding); a negative "
           "term is an ideal stage that uncovers errors that cancelled. Over the witnesses with "
           "all four steps (the runs that capture the ideal volume). **Per point**, beside the "
           "chain: the method's own answer (its far field as interpolated, the near field) at "
           "the witness' point and normal with no patch to blend across, the error a draw that "
           "evaluated the ambient per pixel would show.\n\n";
    for (const std::string& replay : replays) {
        out << "### " << replay << "\n\n| method | drawn mean | far field | patch | model | "
               "truncation | closure | largest | witnesses | per point |\n"
               "|---|---|---|---|---|---|---|---|---|---|\n";
        // Ours with its far-field term taken out, against the best other method's drawn mean:
        // the ratio's floor for far-field work alone while the other terms stay shared.
        double oursFloor = std::nan(""), bestOther = std::nan("");
        std::string bestMethod;
        for (const Job& j : jobs) {
            if (!budgetPoint(j, replay, idealBudget)) continue;
            const json b = objectAt(objectAt(objectAt(objectAt(j.report, "measurement"),
                                                      "reference"),
                                             "drawn"),
                                    "budget");
            if (!(number(b, {"count"}) > 0)) continue;
            if (j.method == "volume") {
                oursFloor = number(b, {"drawn"}) - number(b, {"farField"});
            } else if (!(number(b, {"drawn"}) >= bestOther)) {
                bestOther = number(b, {"drawn"}), bestMethod = j.method;
            }
            const char* names[4] = {"far field", "patch", "model", "truncation"};
            const double terms[4] = {number(b, {"farField"}), number(b, {"patch"}),
                                     number(b, {"model"}), number(b, {"truncation"})};
            int largest = 0;
            for (int t = 1; t < 4; ++t)
                if (std::fabs(terms[t]) > std::fabs(terms[largest])) largest = t;
            out << "| " << (j.method == "volume" ? "**volume (ours)**" : j.method) << " | "
                << fmt(number(b, {"drawn"}), "%.4f");
            for (double t : terms) out << " | " << fmt(t, "%+.4f");
            out << " | " << fmt(number(b, {"closure"}), "%.3f") << " | " << names[largest]
                << " | " << fmt(number(b, {"count"}), "%.0f") << " | "
                << fmt(number(b, {"perPoint"}), "%.4f") << " |\n";
        }
        if (std::isfinite(oursFloor) && bestOther > 0.0)
            out << "\nWith a far field as good as fresh captures (its term 0, the others kept), "
                   "ours would read "
                << fmt(oursFloor, "%.4f") << ": **" << fmt(oursFloor / bestOther, "%.3f")
                << "x** the best other here (" << bestMethod << ", " << fmt(bestOther, "%.4f")
                << "). While the patch, model and truncation terms are the same for every "
                   "method, no far field of ours takes the ratio much below that (only one that "
                   "errs the other way and cancels part of the shared bias).\n";
        out << "\n";
    }
}

}  // namespace

double number(const json& j, std::initializer_list<const char*> path) {
    const json* at = &j;
    for (const char* key : path) {
        if (!at->is_object() || !at->contains(key)) return std::nan("");
        at = &(*at)[key];
    }
    return at->is_number() ? at->get<double>() : std::nan("");
}

// A CSV field on one line: quoted when it holds a comma or a quote, control characters (a
// newline from a report read back) as spaces.
std::string csvField(const std::string& s) {
    if (s.find_first_of(",\"") == std::string::npos && !hasControlCharacter(s)) return s;
    std::string q = "\"";
    for (char c : s) {
        if (c == '"')
            q += "\"\"";
        else
            q += hasControlCharacter(std::string(1, c)) ? ' ' : c;
    }
    return q + "\"";
}

void writeResultsCsv(const std::vector<Job>& jobs, const std::string& path) {
    std::ostringstream out;
    for (std::size_t c = 0; c < kColumns.size(); ++c) out << (c ? "," : "") << kColumns[c];
    out << "\n";
    for (const Job& job : jobs) {
        const auto row = resultRow(job);
        for (std::size_t c = 0; c < kColumns.size(); ++c) {
            const auto it = row.find(kColumns[c]);
            out << (c ? "," : "") << (it == row.end() ? "" : csvField(it->second));
        }
        out << "\n";
    }
    writeTextFile(path, out.str(), "results");
}

// With the reference: what lit its surfaces (lighting/BounceField.h) and how its witnesses were
// placed, from the replay's first run that measured them (every run of a replay shares its
// reference).
std::string referenceLightLine(const std::vector<Job>& jobs, const std::string& replay) {
    for (const Job& j : jobs) {
        if (!j.ok || j.replay.name != replay) continue;
        const json m = objectAt(j.report, "measurement");
        if (!m.contains("reference") || !m["reference"].is_object()) continue;
        const json& ref = m["reference"];
        std::ostringstream out;
        const std::string light = stringAt(ref, "light", "hemisphere");
        out << "Reference light: **" << light << "**";
        const json solves =
            ref.contains("bounce") && ref["bounce"].is_object() && ref["bounce"].contains("solves")
                ? ref["bounce"]["solves"]
                : json::array();
        if (light == "bounce" && solves.is_array() && !solves.empty() && solves[0].is_object()) {
            const json& s = solves[0];
            const json changes = s.contains("changes") ? s["changes"] : json::array();
            out << " (its own bounce field: " << fmt(number(s, {"points"}), "%.0f")
                << " lattice points " << fmt(number(ref, {"bounce", "spacing_m"}), "%.0f")
                << " m apart within " << fmt(number(ref, {"bounce", "reach_m"}), "%.0f")
                << " m of the path"
                << (number(ref, {"bounce", "canopy_m"}) > 0.0
                        ? ", in two layers " + fmt(number(ref, {"bounce", "canopy_m"}), "%.0f") +
                              " m apart (surfaces read them by their height)"
                        : std::string())
                << ", " << fmt(number(s, {"bounces"}), "%.0f") << " bounces to a "
                << "change below 1 % (";
            bool first = true;
            for (const json& c : changes)
                if (c.is_number()) {
                    char text[32];
                    std::snprintf(text, sizeof text, "%.4f", c.get<double>());
                    out << (first ? "" : ", ") << text;
                    first = false;
                }
            out << "), solved in " << fmt(number(s, {"seconds"}), "%.0f") << " s"
                << (solves.size() > 1 ? ", the first of " + std::to_string(solves.size()) +
                                            " light epochs"
                                      : std::string())
                << ")";
        } else if (light == "hemisphere") {
            out << " (the fixed sky/ground hemisphere ambient)";
        }
        if (stringAt(ref, "captureLight", "own") == "reference")
            out << ". The methods' captures lit by the reference's own field too "
                   "(--capture-light reference: a diagnostic, not a method)";
        const double terrain = number(ref, {"drawn", "terrainWitnesses"});
        if (std::isfinite(terrain) && terrain > 0) {
            out << ". Terrain witnesses: " << fmt(terrain, "%.0f") << "; under a crown "
                << fmt(number(ref, {"drawn", "underCrown", "count"}), "%.0f")
                << " (in the drawn-normal mean, shown alone too), on hidden ground "
                << fmt(number(ref, {"drawn", "hidden"}), "%.0f")
                << " (left out); for the sphere figure's capture, moved aside out of a plant's "
                   "footprint "
                << fmt(number(ref, {"drawn", "movedAside"}), "%.0f") << ", lifted over a plant "
                << fmt(number(ref, {"drawn", "lifted"}), "%.0f")
                << " (the drawn-normal figure reads every witness at its own ground point)";
        }
        const double screen = number(ref, {"screen", "error", "count"});
        if (std::isfinite(screen) && screen > 0)
            out << ". Screen witnesses: " << fmt(screen, "%.0f") << ", and "
                << fmt(number(ref, {"screen", "leftOut"}), "%.0f")
                << " left out (their reference would stand inside a plant the view did not draw, "
                   "or inside the terrain)";
        out << ".\n\n";
        return out.str();
    }
    return "";
}

void writeSummary(const std::vector<Job>& jobs, const std::string& path,
                  const std::string& commandLine, const std::string& timing,
                  const std::string& oracle, int idealBudget, int fullLengthBudget) {
    std::ostringstream out;
    const std::string dir = fs::path(path).parent_path().string();
    out << "# Ambience bench: speed against error\n\n";
    out << "Command: `" << commandLine << "`  \n";
    out << timing << " **Oracle: " << oracle
        << (oracle == "reference"
                ? "** (the full scene at 64 x 64, irradiance straight from the cube map, on every "
                  "reference frame; lighting/ReferenceOracle.h)."
                : "** (the methods' own 16 x 16 coarse capture at the point, projected to order-2 "
                  "SH: it leaves out capture resolution, scene simplification and SH truncation).")
        << " Error = relative L2 distance of the applied irradiance from the oracle's over the "
           "sphere of normals, luminance-weighted, at the witness points "
           "(the camera's ground point and terrain patch corners in rings of 16-48, 48-144 and "
           "144-432 m). Pop = per-frame change of applied irradiance at fixed points less the "
           "oracle's own change; pop moving = along the camera's ground point (the car on "
           "drives), the per-frame change less the previous frame's (lighting/Metrics.h). "
           "Ambience ms = stages predict + capture + store + interpolate "
           "and the lookups, per frame (median). All methods have the same capture budget.\n\n";
    std::vector<std::string> replays;
    for (const Job& j : jobs)
        if (std::find(replays.begin(), replays.end(), j.replay.name) == replays.end())
            replays.push_back(j.replay.name);
    // Headline: default point, per replay.
    for (const std::string& replay : replays) {
        out << "## " << replay << "\n\n";
        const bool drawn = oracle == "reference";
        if (drawn) out << referenceLightLine(jobs, replay);
        if (drawn && replay == replays.front())
            out << "Error at the drawn normal: the terrain witnesses as the screen shows them, "
                   "the ambient the draw applies there (the drawn patch's corners, each at its "
                   "normal, interpolated across the patch; on a patch lit per vertex, "
                   "nearField.vertexAmbient_m, the vertices of its grid cell, interpolated as "
                   "its triangles) against the reference irradiance at "
                   "that surface point and its normal (lighting/Metrics.h ReferenceWitness); "
                   "witnesses under tree crowns are in the mean and also shown alone; those on "
                   "ground a bush, rock or trunk hides are left out. Sphere: the same "
                   "witnesses' error over the whole sphere of normals.\n\n";
        out << "| method | point | " << (drawn ? "error at the drawn normal (terrain) | " : "")
            << (drawn ? "sphere " : "")
            << "mean error | p95 error | max error | p99 pop | max pop | "
               "p99 pop moving | max pop moving | ambience ms (median) | faces/s | "
               "probes (max) | kB (max) |\n";
        out << (drawn ? "|---" : "") << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        const Job* ours = nullptr;
        std::vector<const Job*> others;
        for (const Job& j : jobs) {
            if (j.replay.name != replay) continue;
            if (!j.ok) {
                out << "| " << j.method << " | " << j.point.label
                    << " | failed: " << j.error.substr(0, 120) << " | | | | | | | | | |\n";
                continue;
            }
            const json& r = j.report;
            const json m = objectAt(r, "measurement");
            const double e = number(m, {"error", "mean"});
            if (j.point.label == "default" && j.method == "volume") ours = &j;
            if (j.point.label == "default" && j.method != "volume") others.push_back(&j);
            out << "| " << (j.method == "volume" ? "**volume (ours)**" : j.method) << " | "
                << j.point.label << " | ";
            if (drawn) {
                const auto d = [&](const char* a, const char* b) {
                    return number(m, {"reference", "drawn", a, b});
                };
                out << "**" << fmt(d("error", "mean"), "%.4f") << "** (under crowns "
                    << fmt(d("underCrown", "mean"), "%.3f") << ", "
                    << fmt(d("underCrown", "count"), "%.0f") << " of "
                    << fmt(d("error", "count"), "%.0f") << ") | ";
            }
            out << fmt(e, "%.4f") << " | "
                << fmt(number(m, {"error", "p95"}), "%.4f") << " | "
                << fmt(number(m, {"error", "max"}), "%.3f") << " | "
                << fmt(number(m, {"pop", "p99"}), "%.5f") << " | "
                << fmt(number(m, {"pop", "max"}), "%.3f") << " | "
                << fmt(number(m, {"pop_move", "p99"}), "%.5f") << " | "
                << fmt(number(m, {"pop_move", "max"}), "%.3f") << " | "
                << fmt(number(r, {"ambience", "ambience_ms", "median"}), "%.2f") << " | "
                << fmt(number(r, {"ambience", "facesPerSecond"}), "%.1f") << " | "
                << fmt(number(r, {"ambience", "anchorsMax"}), "%.0f") << " | "
                << fmt(number(r, {"ambience", "bytesMax"}) / 1024.0, "%.1f") << " |\n";
        }
        if (ours && !others.empty()) {
            // The drawn normal's ratio first (the headline) with the reference, then the
            // sphere's and the screen-weighted one.
            const std::vector<Measured> measures =
                drawn ? std::vector<Measured>{Measured::Drawn, Measured::Sphere, Measured::Screen}
                      : std::vector<Measured>{Measured::Sphere};
            const bool screen =
                !readScreenErrors((fs::path(dir) / ours->runDir).string()).byFrame.empty();
            for (const Measured measured : measures) {
                if (measured == Measured::Screen && !screen) continue;
                out << "\nOur "
                    << (measured == Measured::Drawn    ? "mean error at the drawn normal"
                        : measured == Measured::Screen ? "screen-weighted mean error (the "
                                                         "screen witnesses: terrain, road "
                                                         "and objects)"
                        : drawn                        ? "mean error over the sphere of normals"
                                                       : "mean error")
                    << " / each other method's (default points), over the frames both "
                       "measured, with the paired bootstrap 95 % interval (blocks of "
                       "consecutive measured frames resampled; app/bench/BenchStats.h):";
                int frames = 0;
                for (const Job* other : others) {
                    const RatioInterval r = ratioAgainst(dir, *ours, *other, measured);
                    frames = std::max(frames, r.frames);
                    out << (other == others.front() ? " " : "; ") << other->method << " **"
                        << formatRatio(r) << "**" << (r.excludesOne() ? "" : " (interval holds 1)");
                }
                out << " (" << frames << " frames).\n";
            }
            out << "\n";
        } else {
            out << "\n";
        }
    }
    // Stress: every replay (the fast flight with its cut, the time-lapse, the far flight), for
    // every method: finite error, memory held, teleports and rejected probes.
    out << "## Stress and memory (default point)\n\n";
    out << "| replay | method | frames | teleports | rejected probes | probes (max) | kB (max) | "
           "max error | finite |\n";
    out << "|---|---|---|---|---|---|---|---|---|\n";
    for (const Job& j : jobs) {
        if (j.point.label != "default" || !j.ok) continue;
        const json& r = j.report;
        const double maxError = number(r, {"measurement", "error", "max"});
        out << "| " << j.replay.name << " | " << j.method << " | "
            << fmt(number(r, {"frameCount"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "teleports"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "rejectedProbes"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "anchorsMax"}), "%.0f") << " | "
            << fmt(number(r, {"ambience", "bytesMax"}) / 1024.0, "%.1f") << " | "
            << fmt(maxError, "%.3f") << " | " << (std::isfinite(maxError) ? "yes" : "**NO**")
            << " |\n";
    }
    out << "\n";
    writeBudgetSection(out, jobs, replays, fullLengthBudget, fs::path(path).parent_path().string());
    writeErrorBudgetSection(out, jobs, replays, idealBudget);
    writeDrawnBudgetSection(out, jobs, replays, idealBudget);
    out << "## Plots\n\n";
    for (const std::string& replay : replays)
        out << "- `pareto-" << replay << ".png`, `error-over-time-" << replay << ".png`\n";
    out << "- `error-vs-speed.png`, `error-by-ring.png`\n\n";
    out << "Each run's report, measurement CSV, log and exact command line are in `runs/`.\n";
    writeTextFile(path, out.str(), "summary");
}

void drawPlots(const std::string& out) {
    // Beside the executable in the build tree, in P/share/ambience when installed (DataPaths.h).
    const fs::path script = findDataFile("bench-plots.py");
    if (script.empty()) {
        std::fprintf(stderr, "plots skipped: bench-plots.py found neither beside the executable "
                             "nor in its installed data folder\n");
        return;
    }
    // Debian's Python (the one python3-matplotlib installs into), else the first on PATH.
    const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
    if (spawnAndWait({"/usr/bin/env", python, "-c", "import matplotlib"}, "/dev/null") != 0) {
        std::fprintf(stderr,
                     "plots skipped: python3 with matplotlib is missing (Debian: apt-get install "
                     "python3-matplotlib); results.csv and summary.md are written\n");
        return;
    }
    const int rc = spawnAndWait({"/usr/bin/env", python, script.string(), out},
                                (fs::path(out) / "plots.log").string());
    if (rc != 0)
        std::fprintf(stderr, "plots failed (exit %d), see %s/plots.log\n", rc, out.c_str());
    else
        std::fprintf(stderr, "plots written (see %s/plots.log)\n", out.c_str());
}

}  // namespace amb::bench
