// ChaseCamera.cpp — the spring step, the chase offset and the eye.
#include "world/ChaseCamera.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <glm/geometric.hpp>

namespace amb {

void criticalSpringStep(glm::dvec3& x, glm::dvec3& v, const glm::dvec3& target,
                        double frequency_per_s, double dt_s) {
    if (!(dt_s > 0.0)) return;
    const double w = frequency_per_s;
    const glm::dvec3 d = x - target;
    const glm::dvec3 c = v + w * d;  // x(t) = target + (d + c t) e^{-wt}
    const double e = std::exp(-w * dt_s);
    x = target + (d + c * dt_s) * e;
    v = (c - w * (d + c * dt_s)) * e;
}

ChaseCamera::ChaseCamera(const ChaseSettings& settings, GroundHeight groundHeight)
    : settings_(settings), groundHeight_(std::move(groundHeight)) {}

glm::dvec3 ChaseCamera::targetOffset(const VehiclePose& car, const ChaseSettings& settings) {
    const glm::dvec3 ahead(std::sin(car.heading_rad), 0.0, std::cos(car.heading_rad));
    return (VehicleShape::centreZ_m() - settings.distance_m) * ahead +
           glm::dvec3(0.0, settings.height_m, 0.0);
}

glm::dvec3 ChaseCamera::lookAt(const VehiclePose& car, const ChaseSettings& settings) {
    return car.position_m + VehicleShape::centreZ_m() * vehicleForward(car) +
           glm::dvec3(0.0, settings.lookHeight_m, 0.0);
}

CameraSample ChaseCamera::update(const VehiclePose& car, double dt_s, bool cut,
                                 const CameraSample& sample) {
    const glm::dvec3 target = targetOffset(car, settings_);
    if (!started_ || cut) {
        offset_ = target;
        velocity_ = glm::dvec3(0.0);
        started_ = true;
    } else {
        criticalSpringStep(offset_, velocity_, target, settings_.frequency_per_s, dt_s);
    }
    CameraSample eye = sample;
    eye.position_m = car.position_m + offset_;
    if (groundHeight_) {
        const double floor_m =
            groundHeight_(eye.position_m.x, eye.position_m.z) + settings_.clearance_m;
        eye.position_m.y = std::max(eye.position_m.y, floor_m);
    }
    const glm::dvec3 toCar = lookAt(car, settings_) - eye.position_m;
    eye.forward = glm::length(toCar) > 1e-9 ? glm::normalize(toCar) : sample.forward;
    const glm::dvec3 right = glm::cross(eye.forward, glm::dvec3(0.0, 1.0, 0.0));
    eye.up = glm::length(right) > 1e-9
                 ? glm::normalize(glm::cross(glm::normalize(right), eye.forward))
                 : sample.up;
    return eye;
}

}  // namespace amb
