// FakeCubeCapture.cpp — see FakeCubeCapture.h.
#include "FakeCubeCapture.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "lighting/SH.h"
#include "world/Conventions.h"
#include "world/Sky.h"
#include "world/WorldSettings.h"

namespace amb {
namespace testing_support {

namespace {

// sin(2 pi x / period) with the phase reduced exactly first (x and period in metres; period an
// integer), so the value at 10^7 m is as accurate as near the origin.
double periodicSin(double x_m, double period_m) {
    const double r = x_m - period_m * std::floor(x_m / period_m);
    return std::sin(2.0 * kPi * r / period_m);
}

// Brightness of the day: 1 at noon, 0.02 at midnight.
double daylight(double timeOfDay_h) {
    return 0.02 + 0.98 * std::max(0.0, std::cos((timeOfDay_h - 12.0) * kPi / 12.0));
}

}  // namespace

FakeCubeCapture::FakeCubeCapture(int faceSize, bool skyModel) : n_(faceSize) {
    if (skyModel) sky_ = std::make_unique<Sky>(WorldSettings{});
}
FakeCubeCapture::~FakeCubeCapture() = default;

glm::dvec3 FakeCubeCapture::groundColour(double x_m, double z_m) {
    return {0.25 + 0.15 * periodicSin(x_m, 81.0), 0.3 + 0.1 * periodicSin(z_m, 54.0),
            0.15 + 0.1 * periodicSin(x_m + z_m, 243.0)};
}

glm::dvec3 FakeCubeCapture::radiance(const glm::dvec3& dir, const glm::dvec3& position_m,
                                     double timeOfDay_h) const {
    const double day = daylight(timeOfDay_h);
    if (dir.y >= 0.0) {
        if (sky_) return glm::dvec3(sky_->radiance(dir, timeOfDay_h));
        return day * glm::dvec3(20.0 + 10.0 * dir.y, 30.0 + 15.0 * dir.y, 60.0 + 30.0 * dir.y);
    }
    // Ground seen from the probe: colour of the point where the ray meets y = 0, lit by a sky of
    // ~100 (analytic units).
    const double t = position_m.y / std::max(1e-3, -dir.y);
    const double reach = std::min(t, 200.0);
    const glm::dvec3 c = groundColour(position_m.x + dir.x * reach, position_m.z + dir.z * reach);
    return c * (100.0 * day / kPi);
}

CubeCaptureStats FakeCubeCapture::capture(const glm::dvec3& position_m, double timeOfDay_h,
                                          CubeFaceMask faces, std::vector<float>& cube) {
    const std::size_t faceTexels = std::size_t(n_) * n_;
    if (cube.size() != 6 * faceTexels * 3) cube.assign(6 * faceTexels * 3, 0.0f);
    calls_.push_back({position_m, timeOfDay_h, faces});
    if (faces & cubeFaceBit(0)) {
        ++probeCounter_;
        poisonThisProbe_ = poisonEvery_ > 0 && probeCounter_ % poisonEvery_ == 0;
        if (poisonThisProbe_) ++poisoned_;
    }
    CubeCaptureStats stats;
    for (int f = 0; f < 6; ++f) {
        if (!(faces & cubeFaceBit(f))) continue;
        ++stats.faces;
        for (int j = 0; j < n_; ++j) {
            for (int i = 0; i < n_; ++i) {
                const glm::dvec3 dir = glm::normalize(cubeTexelDirection(f, i, j, n_));
                const glm::dvec3 l = radiance(dir, position_m, timeOfDay_h);
                const std::size_t t = f * faceTexels + std::size_t(j) * n_ + i;
                for (int c = 0; c < 3; ++c) cube[3 * t + c] = float(l[c]);
            }
        }
        if (poisonThisProbe_ && f == poisonFace_) {
            const std::size_t t = f * faceTexels + faceTexels / 2;
            float bad = 0.0f;
            switch (poison_) {
                case Poison::NaN:
                    bad = std::numeric_limits<float>::quiet_NaN();
                    break;
                case Poison::Inf:
                    bad = std::numeric_limits<float>::infinity();
                    break;
                case Poison::Negative:
                    bad = -1.0f;
                    break;
                case Poison::None:
                    bad = cube[3 * t + 1];
                    break;
            }
            cube[3 * t + 1] = bad;
        }
    }
    return stats;
}

void FlatProbeEnvironment::fallbackCubeMap(double timeOfDay_h, int n,
                                           std::vector<float>& rgb) const {
    const double day = daylight(timeOfDay_h);
    rgb.assign(std::size_t(6) * n * n * 3, 0.0f);
    for (int f = 0; f < 6; ++f) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const bool up = cubeTexelDirection(f, i, j, n).y >= 0.0;
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                const float v = float(day * (up ? 40.0 : 8.0));
                rgb[3 * t + 0] = v;
                rgb[3 * t + 1] = v;
                rgb[3 * t + 2] = v;
            }
        }
    }
}

CubeCaptureStats FurnaceCapture::capture(const glm::dvec3& position_m, double, CubeFaceMask faces,
                                         std::vector<float>& cube) {
    lastAmbient = light_ ? double(luminance(shIrradiance(light_->shAt(position_m),
                                                         glm::vec3(0.0f, 1.0f, 0.0f))))
                         : 0.0;
    const float l = float(rho_ / kPi * (direct_ + lastAmbient));
    cube.assign(std::size_t(6) * n_ * n_ * 3, l);
    ++captures;
    if (light_) ++litCaptures;
    CubeCaptureStats s;
    s.faces = __builtin_popcount(faces & kAllCubeFaces);
    return s;
}

}  // namespace testing_support
}  // namespace amb
