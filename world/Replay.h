// Replay.h — recorded camera paths: the versioned replay file format (JSON), reader and writer.
// The format is documented in replays/README.md.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "world/WorldSettings.h"

namespace amb {

// One camera state at a fixed step.
struct CameraSample {
    double time_s = 0.0;          // since the start of the replay
    glm::dvec3 position_m{0.0};   // world position of the eye
    glm::dvec3 forward{0, 0, -1}; // unit view direction
    glm::dvec3 up{0, 1, 0};       // unit, orthogonal to forward
    bool cut = false;             // a camera cut (teleport) happens before this sample
};

enum class ReplayMode { Drive, Fly, Static };

struct Replay {
    static constexpr int kFormatVersion = 1;
    std::string name;
    std::string description;
    WorldSettings world;
    ReplayMode mode = ReplayMode::Drive;
    double timeOfDayStart_h = 12.0;  // hours [0, 24)
    double timeRate = 1.0;           // hours of day per hour of replay (600 = time-lapse)
    double step_s = 1.0 / 60.0;      // the fixed step between samples
    std::vector<CameraSample> samples;

    double duration_s() const;
    // Time of day (wrapped to [0, 24)) at replay time t.
    double timeOfDayAt_h(double time_s) const;
    // Camera state at any time, interpolated between samples (no interpolation across a cut).
    CameraSample sampleAt(double time_s) const;
};

const char* toString(ReplayMode mode);

// Reads and validates; throws InputError naming the file, the field or sample index, and what
// was expected.
Replay readReplay(const std::string& path);
Replay parseReplay(const std::string& jsonText, const std::string& where);
void writeReplay(const Replay& replay, const std::string& path);
std::string formatReplay(const Replay& replay);

}  // namespace amb
