// ChaseCamera.h — the main view's eye behind and above the car on drives (docs/ARCHITECTURE.md
// "Terrain and objects"). The replay's camera stays the car's eye, which the ambience, its
// scheduler and the error meter use; only the main view moves.
//
// The eye's offset from the car (world axes) follows a critically damped spring towards the
// offset behind and above the car's heading, stepped exactly for each frame's dt of simulation
// time (so a replay gives the same eye on every run and at any frame rate up to rounding); then
// it is kept `clearance_m` above the terrain and looks at the middle of the car.
#pragma once

#include <functional>

#include <glm/vec3.hpp>

#include "world/Replay.h"
#include "world/Vehicle.h"

namespace amb {

struct ChaseSettings {
    double distance_m = 6.5;       // behind the middle of the car, horizontally
    double height_m = 2.4;         // above the car's ground point
    double lookHeight_m = 1.0;     // looks at the middle of the car this high
    double frequency_per_s = 3.0;  // the spring's natural angular frequency (1 / time constant)
    double clearance_m = 1.0;      // never lower above the terrain
};

// One exact step of a critically damped spring x'' = -w^2 (x - target) - 2 w x' towards a fixed
// target: x(t) = target + (d0 + (v0 + w d0) t) exp(-w t), d0 = x0 - target. Stable for any dt.
void criticalSpringStep(glm::dvec3& x, glm::dvec3& v, const glm::dvec3& target,
                        double frequency_per_s, double dt_s);

class ChaseCamera {
  public:
    using GroundHeight = std::function<double(double x_m, double z_m)>;
    ChaseCamera(const ChaseSettings& settings, GroundHeight groundHeight);

    // The eye for the car at `car` after dt_s of simulation time; `cut` (or the first call)
    // puts the eye at rest where the spring is heading. time_s and cut are copied from `sample`.
    CameraSample update(const VehiclePose& car, double dt_s, bool cut, const CameraSample& sample);
    // Where the spring is heading: behind the middle of the car and above its ground point.
    static glm::dvec3 targetOffset(const VehiclePose& car, const ChaseSettings& settings);
    // The point the eye looks at.
    static glm::dvec3 lookAt(const VehiclePose& car, const ChaseSettings& settings);
    const glm::dvec3& offset() const { return offset_; }
    const ChaseSettings& settings() const { return settings_; }

  private:
    ChaseSettings settings_;
    GroundHeight groundHeight_;
    bool started_ = false;
    glm::dvec3 offset_{0.0}, velocity_{0.0};
};

}  // namespace amb
