// FuzzStubs.h — a tiny CPU capture and a flat environment, so the settings and oracle targets
// can build the objects that consume what the readers accepted (no GL, no world); and the drive
// every settings target gives the methods it builds.
#pragma once

#include <cmath>
#include <vector>

#include <glm/vec3.hpp>

#include "FuzzSupport.h"
#include "lighting/AmbienceMethod.h"
#include "lighting/CubeCapture.h"
#include "lighting/ProbeEnvironment.h"

namespace amb::fuzz {

// Faces of 4 x 4 texels: a sky that brightens upwards over a darker ground, varying with the
// probe's position so anchors differ.
class StubCapture final : public CubeCapture {
  public:
    int faceSize() const override { return 4; }
    CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override {
        const int n = faceSize();
        cube.resize(std::size_t(6 * n * n * 3));
        CubeCaptureStats stats;
        for (int f = 0; f < 6; ++f) {
            if (!(faces & cubeFaceBit(f))) continue;
            ++stats.faces;
            for (int t = 0; t < n * n; ++t) {
                const float base = f == 2 ? 1.0f : f == 3 ? 0.1f : 0.4f;
                const float wobble = 0.05f * float((int(position_m.x + position_m.z) + t) % 7);
                for (int c = 0; c < 3; ++c)
                    cube[std::size_t(((f * n * n) + t) * 3 + c)] =
                        base + wobble + 0.01f * float(c) + 0.001f * float(timeOfDay_h);
            }
        }
        return stats;
    }
};

class StubEnvironment final : public ProbeEnvironment {
  public:
    glm::dvec3 placeProbe(double x_m, double z_m, double) const override { return {x_m, 2.0, z_m}; }
    double sunAngularSpeed_radPerHour() const override { return 0.2618; }  // 2 pi / 24 h
    void fallbackCubeMap(double, int n, std::vector<float>& rgb) const override {
        rgb.assign(std::size_t(6 * n * n * 3), 0.3f);
    }
};

// A short drive of `method` (14 frames at 30 m/s, so a probe completes and is stored, with a few
// lookups noted for the methods that place probes by demand); then every lookup must be finite.
inline void driveAndCheck(AmbienceMethod& method) {
    const double x[] = {0.0, 5.0, -30.0}, z[] = {0.0, 7.0, 12.0};
    for (int f = 0; f < 14; ++f) {
        const glm::dvec3 camera(0.5 * f, 2.0, 0.25 * f);
        method.noteLookups(3, x, z);
        method.predictStage(camera, glm::dvec3(30.0, 0.0, 15.0), 12.0 + 0.001 * f, 1.0 / 60);
        method.captureStage();
        method.storeStage();
    }
    for (double p : {0.0, 3.0, -40.0, 1000.0}) {
        const ShRgb sh = method.shAt(p, 0.5 * p);
        for (const auto& k : sh.c)
            for (int c = 0; c < 3; ++c) AMB_FUZZ_EXPECT(std::isfinite(k[c]));
    }
}

}  // namespace amb::fuzz
