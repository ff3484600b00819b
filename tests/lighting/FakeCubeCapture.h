// FakeCubeCapture.h — CPU stand-ins for the GL capture and the world, for the ambience tests.
//
// FakeCubeCapture fills faces analytically: above the horizon the sky (either the Preetham sky
// model of world/Sky.h or, for speed, a cheap analytic gradient), below it a ground whose colour
// depends on the probe's position (so neighbouring anchors differ). It can poison chosen probes
// with NaN, +Inf or negative texels, and logs every call.
// FurnaceCapture: a closed scene of uniform albedo lit by a direct irradiance and by the surface
// light it is given, for tests of multiple bounces.
// FlatProbeEnvironment: flat ground at y = 0, probes probeHeight_m above it, no plants.
// (Kept in its own translation unit: it needs world/Sky.h but not lighting/SH.h.)
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/CubeCapture.h"
#include "lighting/ProbeEnvironment.h"

namespace amb {

class Sky;

namespace testing_support {

enum class Poison { None, NaN, Inf, Negative };

class FakeCubeCapture : public CubeCapture {
  public:
    explicit FakeCubeCapture(int faceSize = 16, bool skyModel = false);
    ~FakeCubeCapture() override;

    int faceSize() const override { return n_; }
    CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override;

    // Radiance the fake shows in unit direction `dir` from `position_m` at `timeOfDay_h`.
    glm::dvec3 radiance(const glm::dvec3& dir, const glm::dvec3& position_m,
                        double timeOfDay_h) const;
    // Ground colour (linear RGB) at (x, z): varies over tens of metres, exact far from the origin
    // (the phase is reduced with the lattice period before the trigonometry).
    static glm::dvec3 groundColour(double x_m, double z_m);

    // Every `every`-th probe (counted by calls that include face 0, from 1) gets one poisoned
    // texel in the face `face`.
    void poisonEvery(int every, Poison kind, int face = 3) {
        poisonEvery_ = every;
        poison_ = kind;
        poisonFace_ = face;
    }
    struct Call {
        glm::dvec3 position_m;
        double timeOfDay_h;
        CubeFaceMask faces;
    };
    const std::vector<Call>& calls() const { return calls_; }
    std::int64_t poisonedProbes() const { return poisoned_; }

  private:
    int n_;
    std::unique_ptr<Sky> sky_;  // null: analytic gradient sky
    std::vector<Call> calls_;
    int probeCounter_ = 0;
    int poisonEvery_ = 0;
    Poison poison_ = Poison::None;
    int poisonFace_ = 3;
    bool poisonThisProbe_ = false;
    std::int64_t poisoned_ = 0;
};

// A closed scene of uniform albedo rho (a furnace): every texel sees a surface lit by a direct
// irradiance E_d and by the surface light's irradiance there for an upward normal, so its
// radiance is L = rho / pi (E_d + E_amb(p)), p the capture's position. The SH of a uniform
// radiance L gives E = pi L for every normal: a field read back as the surface light makes each
// capture one bounce more, E_k = rho (E_d + E_k-1), whose limit is rho E_d / (1 - rho).
class FurnaceCapture final : public CubeCapture {
  public:
    FurnaceCapture(double rho, double direct, int faceSize = 8)
        : rho_(rho), direct_(direct), n_(faceSize) {}
    int faceSize() const override { return n_; }
    CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override;
    void setSurfaceLight(const SurfaceLight* light) override { light_ = light; }
    const SurfaceLight* light() const { return light_; }
    int captures = 0;      // calls
    int litCaptures = 0;   // calls made with a surface light set
    double lastAmbient = 0.0;  // E_amb of the latest call (0 without a light)

  private:
    double rho_, direct_;
    int n_;
    const SurfaceLight* light_ = nullptr;
};

class FlatProbeEnvironment : public ProbeEnvironment {
  public:
    explicit FlatProbeEnvironment(double probeHeight_m = 2.0) : height_m_(probeHeight_m) {}
    glm::dvec3 placeProbe(double x_m, double z_m, double) const override {
        return {x_m, height_m_, z_m};
    }
    // 15 degrees per hour (the equator at an equinox).
    double sunAngularSpeed_radPerHour() const override { return 3.14159265358979 / 12.0; }
    // A uniform grey sky over a darker ground (brightness follows the time of day: day > night).
    void fallbackCubeMap(double timeOfDay_h, int n, std::vector<float>& rgb) const override;

  private:
    double height_m_;
};

}  // namespace testing_support
}  // namespace amb
