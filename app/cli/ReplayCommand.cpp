// ReplayCommand.cpp — `ambience replay info FILE` and `ambience replay make ... --out FILE`.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "app/cli/CliChecks.h"
#include "app/cli/Commands.h"
#include "lighting/CaptureCore.h"
#include "world/CameraPath.h"
#include "world/Conventions.h"
#include "world/Error.h"
#include "world/Replay.h"
#include "world/World.h"

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

// What `replay make` records: the path mode, the world, the clock and each mode's settings.
struct MakeOptions {
    std::string mode = "drive", out, name, description;
    WorldSettings world;
    double timeStart_h = 12.0, timeRate = 1.0, duration_s = 60.0, step_s = 1.0 / 60.0;
    double speed_mps = 0.0;  // 0: the mode's default (drive 30, fly 80)
    // drive
    std::string road = "highway";
    double startDistance_m = 0.0, laneOffset_m = 0.0, eyeHeight_m = 1.5, lateralAccel = 0.0;
    bool reverse = false;
    // fly
    double altitude_m = 120.0, clearance_m = 30.0, turnRadius_m = 400.0, heading_deg = 0.0;
    std::uint64_t flightSeed = 1;
    std::vector<double> start{0.0, 0.0};
    int cuts = 0;
    double cutJump_m = 3000.0;
    // static
    std::vector<double> at{0.0, 0.0};
    double height_m = 2.0, pitch_deg = 0.0;
};

// Records the replay `o` describes, checks it with the reader's rules and writes it.
void makeReplay(const MakeOptions& o) {
    constexpr double kDeg = kPi / 180.0;
    Replay rp;
    rp.name = o.name;
    rp.description = o.description;
    rp.world = o.world;
    rp.timeOfDayStart_h = o.timeStart_h >= 24.0 ? 0.0 : o.timeStart_h;
    rp.timeRate = o.timeRate;
    rp.step_s = o.step_s;
    const World world(o.world);
    if (o.mode == "drive") {
        rp.mode = ReplayMode::Drive;
        DriveSettings s;
        s.road = o.road;
        s.speed_mps = o.speed_mps > 0.0 ? o.speed_mps : 30.0;
        s.startDistance_m = o.startDistance_m;
        s.reverse = o.reverse;
        s.laneOffset_m = o.laneOffset_m;
        s.eyeHeight_m = o.eyeHeight_m;
        s.maxLateralAccel_mps2 = o.lateralAccel;
        s.duration_s = o.duration_s;
        s.step_s = o.step_s;
        rp.samples = makeDrivePath(world, s);
    } else if (o.mode == "fly") {
        rp.mode = ReplayMode::Fly;
        FlySettings s;
        s.speed_mps = o.speed_mps > 0.0 ? o.speed_mps : 80.0;
        s.altitude_m = o.altitude_m;
        s.clearance_m = std::min(o.clearance_m, o.altitude_m);
        s.turnRadius_m = o.turnRadius_m;
        s.duration_s = o.duration_s;
        s.step_s = o.step_s;
        ProceduralFlight plan;
        plan.seed = o.flightSeed;
        plan.start_m = {o.start[0], o.start[1]};
        plan.heading_rad = o.heading_deg * kDeg;
        plan.length_m = s.speed_mps * o.duration_s * 1.25 + 2000.0;
        plan.region_m = o.world.roadRegion_m;
        plan.cuts = o.cuts;
        plan.cutJump_m = o.cutJump_m;
        s.plan = makeFlightPlan(plan);
        rp.samples = makeFlyPath(world, s);
    } else {
        rp.mode = ReplayMode::Static;
        StaticSettings s;
        s.position_m = {o.at[0], o.at[1]};
        s.heightAboveTerrain_m = o.height_m;
        s.heading_rad = o.heading_deg * kDeg;
        s.pitch_rad = o.pitch_deg * kDeg;
        s.duration_s = o.duration_s;
        s.step_s = o.step_s;
        rp.samples = makeStaticPath(world, s);
    }
    if (rp.name.empty()) rp.name = o.mode;
    // Validate what we are about to write with the reader's rules (a bug here must not
    // produce a file that the reader refuses later).
    parseReplay(formatReplay(rp), o.out);
    writeReplay(rp, o.out);
    std::printf("wrote %s: %s, %zu samples, %.1f s\n", o.out.c_str(), toString(rp.mode),
                rp.samples.size(), rp.duration_s());
}

void addReplayInfoCommand(CLI::App& cmd) {
    auto* info =
        cmd.add_subcommand("info", "Print duration, distance, speed statistics and bounds");
    static std::string infoPath;
    static bool infoJson = false;
    info->add_option("file", infoPath, "Replay file (.json)")->required();
    info->add_flag("--json", infoJson, "Print JSON instead of text");
    info->callback([] {
        const Replay rp = readReplay(infoPath);
        if (infoJson) std::printf("%s\n", replayInfo(rp).dump(2).c_str());
        else printInfo(infoPath, rp);
    });
}

void addReplayMakeCommand(CLI::App& cmd) {
    auto* make = cmd.add_subcommand("make", "Record a new replay with the project's path code");
    static MakeOptions o;
    make->add_option("--mode", o.mode, "drive | fly | static")
        ->check(CLI::IsMember({"drive", "fly", "static"}))
        ->capture_default_str();
    make->add_option("--out", o.out, "Output replay file (.json)")->required();
    make->add_option("--name", o.name, "Short name stored in the file");
    make->add_option("--description", o.description, "One line stored in the file");
    make->add_option("--seed", o.world.seed, "World seed")
        ->check(SeedValidator())->capture_default_str();
    make->add_option("--latitude", o.world.latitude_deg, "Latitude [deg]")
        ->check(FiniteRange(-90.0, 90.0))->capture_default_str();
    make->add_option("--day", o.world.dayOfYear, "Day of year (1-366)")
        ->check(CLI::Range(1, 366))->capture_default_str();
    make->add_option("--time", o.timeStart_h, "Time of day at the start [h]")
        ->check(FiniteRange(0.0, 24.0))->capture_default_str();
    make->add_option("--time-rate", o.timeRate, "Hours of day per hour of replay")
        ->check(FiniteRange(0.0, 1.0e5))->capture_default_str();
    make->add_option("--duration", o.duration_s, "Duration [s]")
        ->check(FiniteRange(0.01, 86400.0))->capture_default_str();
    make->add_option("--step", o.step_s, "Fixed step [s]")
        ->check(FiniteRange(1e-4, 10.0))->capture_default_str();
    // No faster than the teleport rule believes a camera moves (lighting/CaptureCore.h).
    make->add_option("--speed", o.speed_mps, "Speed [m/s] (default: drive 30, fly 80)")
        ->check(FiniteRange(0.0, kMaxCameraSpeed_mps));
    make->add_option("--road", o.road, "drive: road name (highway, mountain)")
        ->capture_default_str();
    make->add_option("--start-distance", o.startDistance_m, "drive: start along the road [m]")
        ->check(FiniteRange(0.0, 1.0e7));
    make->add_flag("--reverse", o.reverse, "drive: from the road's end towards its start");
    make->add_option("--lane-offset", o.laneOffset_m, "drive: lateral offset, + right [m]")
        ->check(FiniteRange(-50.0, 50.0));
    make->add_option("--eye-height", o.eyeHeight_m, "drive: eye above the road [m]")
        ->check(FiniteRange(0.1, 100.0))->capture_default_str();
    make->add_option("--max-lateral-accel", o.lateralAccel,
                     "drive: slow down in curves to keep v^2 k below this [m/s^2]; "
                     "0 = constant speed")
        ->check(FiniteRange(0.0, 100.0));
    make->add_option("--altitude", o.altitude_m, "fly: height above the terrain [m]")
        ->check(FiniteRange(1.0, 1.0e5))->capture_default_str();
    make->add_option("--clearance", o.clearance_m, "fly: minimum height above the terrain [m]")
        ->check(FiniteRange(0.0, 1.0e5))->capture_default_str();
    make->add_option("--turn-radius", o.turnRadius_m, "fly: radius of turns [m]")
        ->check(FiniteRange(1.0, 1.0e5))->capture_default_str();
    make->add_option("--flight-seed", o.flightSeed, "fly: seed of the procedural flight plan")
        ->check(SeedValidator());
    make->add_option("--start", o.start, "fly: start point X,Z [m]")
        ->delimiter(',')->expected(2)->check(FiniteRange(-1.0e7, 1.0e7));
    make->add_option("--heading", o.heading_deg,
                     "fly/static: heading [deg], 0 = north (-Z), 90 = east")
        ->check(FiniteRange(-360.0, 360.0));
    make->add_option("--cuts", o.cuts, "fly: number of camera cuts (teleports)")
        ->check(CLI::Range(0, 1000));
    make->add_option("--cut-jump", o.cutJump_m, "fly: distance of each cut [m]")
        ->check(FiniteRange(0.0, 1.0e6));
    make->add_option("--at", o.at, "static: camera ground point X,Z [m]")
        ->delimiter(',')->expected(2)->check(FiniteRange(-1.0e7, 1.0e7));
    make->add_option("--height", o.height_m, "static: eye above the terrain [m]")
        ->check(FiniteRange(0.0, 1.0e5));
    make->add_option("--pitch", o.pitch_deg, "static: pitch [deg], + looks up")
        ->check(FiniteRange(-89.0, 89.0));
    make->callback([] { makeReplay(o); });
}

}  // namespace

void addReplayCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("replay", "Inspect or record replays (camera paths)");
    cmd->require_subcommand(1);
    addReplayInfoCommand(*cmd);
    addReplayMakeCommand(*cmd);
}

}  // namespace amb
