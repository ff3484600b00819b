// ReplayCommand.cpp — `ambience replay info FILE` and `ambience replay make ... --out FILE`.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "app/Commands.h"
#include "world/Error.h"
#include "world/Replay.h"

namespace amb {

namespace {

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const double idx = p * (v.size() - 1);
    const std::size_t i = static_cast<std::size_t>(idx);
    const double f = idx - i;
    return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

// Duration, distance, speed statistics and bounds of a replay, as JSON.
nlohmann::ordered_json replayInfo(const Replay& rp) {
    std::vector<double> speeds;
    double distance = 0.0;
    int cuts = 0;
    glm::dvec3 lo(1e300), hi(-1e300);
    for (std::size_t i = 0; i < rp.samples.size(); ++i) {
        const glm::dvec3 p = rp.samples[i].position_m;
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
        if (i == 0) continue;
        if (rp.samples[i].cut) {
            ++cuts;
            continue;
        }
        const double d = glm::length(p - rp.samples[i - 1].position_m);
        distance += d;
        speeds.push_back(d / (rp.samples[i].time_s - rp.samples[i - 1].time_s));
    }
    nlohmann::ordered_json j;
    j["name"] = rp.name;
    j["description"] = rp.description;
    j["mode"] = toString(rp.mode);
    j["seed"] = rp.world.seed;
    j["samples"] = rp.samples.size();
    j["step_s"] = rp.step_s;
    j["duration_s"] = rp.duration_s();
    j["distance_m"] = distance;
    j["cuts"] = cuts;
    j["speed_mps"] = {{"min", speeds.empty() ? 0.0 : *std::min_element(speeds.begin(), speeds.end())},
                      {"median", percentile(speeds, 0.5)},
                      {"mean", rp.duration_s() > 0 ? distance / rp.duration_s() : 0.0},
                      {"p95", percentile(speeds, 0.95)},
                      {"max", speeds.empty() ? 0.0 : *std::max_element(speeds.begin(), speeds.end())}};
    j["bounds_m"] = {{"min", {lo.x, lo.y, lo.z}}, {"max", {hi.x, hi.y, hi.z}}};
    j["timeOfDay_h"] = {{"start", rp.timeOfDayStart_h},
                        {"end", rp.timeOfDayAt_h(rp.duration_s())},
                        {"rate", rp.timeRate}};
    return j;
}

void printInfo(const std::string& path, const Replay& rp) {
    const auto j = replayInfo(rp);
    std::printf("replay     %s (%s)\n", path.c_str(), rp.name.c_str());
    if (!rp.description.empty()) std::printf("           %s\n", rp.description.c_str());
    std::printf("mode       %s, world seed %llu, latitude %.2f deg, day %d\n", toString(rp.mode),
                static_cast<unsigned long long>(rp.world.seed), rp.world.latitude_deg,
                rp.world.dayOfYear);
    std::printf("samples    %zu at %.4f s (%.1f Hz), %d camera cut(s)\n", rp.samples.size(),
                rp.step_s, 1.0 / rp.step_s, j["cuts"].get<int>());
    std::printf("duration   %.2f s\n", rp.duration_s());
    std::printf("distance   %.1f m\n", j["distance_m"].get<double>());
    const auto& s = j["speed_mps"];
    std::printf("speed      min %.2f  median %.2f  mean %.2f  p95 %.2f  max %.2f m/s\n",
                s["min"].get<double>(), s["median"].get<double>(), s["mean"].get<double>(),
                s["p95"].get<double>(), s["max"].get<double>());
    const auto& b = j["bounds_m"];
    std::printf("bounds     x [%.1f, %.1f]  y [%.1f, %.1f]  z [%.1f, %.1f] m\n",
                b["min"][0].get<double>(), b["max"][0].get<double>(), b["min"][1].get<double>(),
                b["max"][1].get<double>(), b["min"][2].get<double>(), b["max"][2].get<double>());
    std::printf("time       %.2f h -> %.2f h (rate %g)\n", rp.timeOfDayStart_h,
                rp.timeOfDayAt_h(rp.duration_s()), rp.timeRate);
}

}  // namespace

void addReplayCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("replay", "Inspect or record replays (camera paths)");
    cmd->require_subcommand(1);

    // ---- replay info ----
    auto* info = cmd->add_subcommand("info", "Print duration, distance, speed statistics and bounds");
    static std::string infoPath;
    static bool infoJson = false;
    info->add_option("file", infoPath, "Replay file (.json)")->required();
    info->add_flag("--json", infoJson, "Print JSON instead of text");
    info->callback([] {
        const Replay rp = readReplay(infoPath);
        if (infoJson) std::printf("%s\n", replayInfo(rp).dump(2).c_str());
        else printInfo(infoPath, rp);
    });

    // ---- replay make ---- (path code lands with world/CameraPath)
    auto* make = cmd->add_subcommand("make", "Record a new replay with the project's path code");
    make->callback([] { throw InputError("replay make", "not built yet"); });
}

}  // namespace amb
