// ProbeCapture.cpp — see ProbeCapture.h.
#include "lighting/ProbeCapture.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "lighting/CubeCapture.h"
#include "lighting/CubeMapProjector.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

ProbeFacesResult captureProbeFaces(CubeCapture& capture, CubeMapProjector& projector,
                                   std::vector<float>& cube, const glm::dvec3& position_m,
                                   double timeOfDay_h, int facesDone, int budget, bool& bad) {
    using Clock = std::chrono::steady_clock;
    auto secondsSince = [](Clock::time_point t0) {
        return std::chrono::duration<double>(Clock::now() - t0).count();
    };
    ProbeFacesResult result;
    const int count = std::min(budget, kCubeFaces - facesDone);
    if (count <= 0) return result;
    CubeFaceMask mask = 0;
    for (int f = facesDone; f < facesDone + count; ++f) mask |= cubeFaceBit(f);

    auto t0 = Clock::now();
    capture.capture(position_m, timeOfDay_h, mask, cube);
    result.capture_s = secondsSince(t0);
    const std::size_t faceFloats = 3 * std::size_t(capture.faceSize()) * capture.faceSize();
    AMB_CHECK(cube.size() == faceFloats * kCubeFaces);

    t0 = Clock::now();
    for (int f = facesDone; f < facesDone + count; ++f) {
        const float* face = cube.data() + faceFloats * std::size_t(f);
        for (std::size_t t = 0; t < faceFloats && !bad; ++t) {
            if (!(face[t] >= 0.0f) || !std::isfinite(face[t])) bad = true;
        }
        projector.addFace(f, face);
    }
    result.project_s = secondsSince(t0);
    result.faces = count;
    return result;
}

}  // namespace amb
