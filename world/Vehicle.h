// Vehicle.h — the camera's own car on drives: a low-poly car as a plain mesh (body lofted through
// cross-sections, glass, four wheels, lights; 332 triangles), and where it stands given the
// replay's camera sample.
//
// Local frame: +Z forward, +Y up, origin on the ground under the driver's eye, which the replay
// keeps DriveSettings::eyeHeight_m (1.5 m) above the road: just above the top of the windscreen,
// so the first-person (hood) view sees the bonnet at the bottom of the image and nothing of the
// roof. The car reaches from kRearZ_m to kFrontZ_m; its wheels touch the ground plane y = 0.
#pragma once

#include <functional>

#include <glm/vec3.hpp>

#include "world/Replay.h"
#include "world/WorldMesh.h"

namespace amb {

// Where the car stands this frame.
struct VehiclePose {
    glm::dvec3 position_m{0.0};  // ground point under the driver's eye (the local origin)
    double heading_rad = 0.0;    // rotation about +Y taking the car's +Z to its forward
    double pitch_rad = 0.0;      // nose up > 0, about the car's own +X (applied before heading)
};

struct VehicleShape {
    static constexpr double kRearZ_m = -3.05, kFrontZ_m = 1.35;
    static constexpr double kRearAxleZ_m = -2.15, kFrontAxleZ_m = 0.6;
    static constexpr double kWheelRadius_m = 0.33;
    static constexpr double kHalfWidth_m = 0.88;
    static constexpr double kRoofY_m = 1.44;
    // The middle of the car, along its length (where a chase camera looks).
    static constexpr double centreZ_m() { return 0.5 * (kRearZ_m + kFrontZ_m); }
};

WorldMesh makeVehicleMesh();

// The unit direction the car faces (heading and pitch) in world axes.
glm::dvec3 vehicleForward(const VehiclePose& pose);

// The car under a drive replay's eye: `eyeHeight_m` below it, facing the eye's horizontal
// forward. With `groundHeight` (terrain height at x, z) the car pitches to the ground under its
// axles; without it the car stays level.
VehiclePose vehiclePoseFromEye(const CameraSample& eye, double eyeHeight_m,
                               const std::function<double(double, double)>& groundHeight = {});

// The mesh `mesh` pitched by `pitch_rad` about local +X (nose up > 0), positions and normals.
WorldMesh pitchedMesh(const WorldMesh& mesh, double pitch_rad);

}  // namespace amb
