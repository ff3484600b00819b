// ProbeCapture.h — the next faces of a probe in progress: capture them, check them, project
// them as they arrive (shared by the volume and the baselines, so that every method spends the
// capture budget the same way).
#pragma once

#include <vector>

#include <glm/vec3.hpp>

namespace amb {

class CubeCapture;
class CubeMapProjector;

struct ProbeFacesResult {
    int faces = 0;  // faces captured by this call
    double capture_s = 0.0, project_s = 0.0;
};

// Captures faces facesDone .. min(5, facesDone + budget - 1) of the probe at `position_m` into
// `cube` and adds them to `projector`. A texel that is NaN, infinite or negative sets `bad` (the
// whole probe is spoilt; the projector zeroes and counts such texels, so its sums stay finite).
ProbeFacesResult captureProbeFaces(CubeCapture& capture, CubeMapProjector& projector,
                                   std::vector<float>& cube, const glm::dvec3& position_m,
                                   double timeOfDay_h, int facesDone, int budget, bool& bad);

}  // namespace amb
