// CameraPath.h — camera paths sampled at a fixed step: drive along a road, fly a flight plan
// above the terrain, or stand still.
//
// Every path is a polyline of eye positions that the camera walks with chords of exactly
// speed * step (so the distance between consecutive samples, the "arc length per step" of the
// sampled path, is the requested speed times the step, up to rounding), except across a cut.
// Orientation: forward looks at a point a little further along the path (a look-ahead, which
// smooths the view), up is world +Y made orthogonal to forward.
// Headings (at the user interface): 0 = north (-Z), pi/2 = east (+X) (Sky.h axes).
// Bad settings (unknown road, non-positive speed, a path too short for the duration ...) throw
// InputError naming the setting.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "world/Replay.h"

namespace amb {

class World;

// ---- Drive ------------------------------------------------------------------------------------

struct DriveSettings {
    std::string road = "highway";  // a Road::name of World::roads()
    double speed_mps = 30.0;       // cruising speed
    double startDistance_m = 0.0;  // arc length along the road where the drive starts
    bool reverse = false;          // drive from the road's end towards its start
    double laneOffset_m = 0.0;     // lateral offset, + right of travel; |.| < half width
    double eyeHeight_m = 1.5;      // above the road surface
    // > 0: slow down in curves so that speed^2 * curvature <= this, changing speed at most at
    // maxSpeedChange_mps2; 0: constant speed.
    double maxLateralAccel_mps2 = 0.0;
    double maxSpeedChange_mps2 = 2.0;
    double lookAhead_m = 25.0;  // the view looks at the path this far ahead
    double duration_s = 60.0;
    double step_s = 1.0 / 60.0;
};

// Throws InputError if the road ends before the duration is over.
std::vector<CameraSample> makeDrivePath(const World& world, const DriveSettings& settings);

// ---- Fly --------------------------------------------------------------------------------------

// Legs of waypoints in the ground plane (x, z) [m]. Each leg is flown through its waypoints
// with circular turns at the interior ones; between legs the camera cuts (teleports) to the
// next leg's first waypoint, and that sample has CameraSample::cut set.
struct FlightPlan {
    std::vector<std::vector<glm::dvec2>> legs;
    double length_m() const;  // total length of the straight legs (turns shorten it slightly)
};

struct FlySettings {
    FlightPlan plan;
    double speed_mps = 80.0;
    double altitude_m = 120.0;    // nominal height above the terrain
    double clearance_m = 30.0;    // never closer to the terrain than this (<= altitude_m)
    double turnRadius_m = 400.0;  // radius of the turns at waypoints (less if legs are short)
    double maxClimb = 0.3;        // bound on |dy| / horizontal distance of the flight level
    double smoothing_m = 600.0;   // terrain features shorter than this are not followed
    double lookAhead_s = 1.0;     // the view looks at the path this long ahead
    double duration_s = 60.0;
    double step_s = 1.0 / 60.0;
};

// Throws InputError if the plan ends before the duration is over.
std::vector<CameraSample> makeFlyPath(const World& world, const FlySettings& settings);

// A procedural plan of straight legs and turns: from `start_m` at `heading_rad`, segments of
// random length with random turns, steering back towards the start when leaving the square of
// half-width region_m around it; `cuts` teleports of about cutJump_m (clamped to that square)
// spread evenly over the length.
struct ProceduralFlight {
    std::uint64_t seed = 1;
    glm::dvec2 start_m{0.0};
    double heading_rad = 0.0;
    double length_m = 10000.0;  // flown length over all legs
    double segmentMin_m = 600.0;
    double segmentMax_m = 2000.0;
    double maxTurn_rad = 1.6;
    double region_m = 6000.0;
    int cuts = 0;
    double cutJump_m = 3000.0;
};
FlightPlan makeFlightPlan(const ProceduralFlight& settings);

// ---- Static -----------------------------------------------------------------------------------

struct StaticSettings {
    glm::dvec2 position_m{0.0};  // (x, z)
    double heightAboveTerrain_m = 2.0;
    double heading_rad = 0.0;  // view direction in the ground plane
    double pitch_rad = 0.0;    // + looks up
    double duration_s = 60.0;
    double step_s = 1.0 / 60.0;
};
std::vector<CameraSample> makeStaticPath(const World& world, const StaticSettings& settings);

}  // namespace amb
