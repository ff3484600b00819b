// ReferenceLightFlags.h — what lights the reference's surfaces, on the command line of run and
// compare (and, passed through, bench): `--reference-light bounce|hemisphere` (default bounce:
// the scene's own bounce field, lighting/BounceField.h) and the field's lattice,
// `--bounce-spacing`, `--bounce-reach`, `--bounce-face`, `--bounce-canopy`; where the lattice's
// points stand; the field's record in a report; and `--capture-light own|reference` (run and
// bench: the methods' captures lit by that field too, a diagnostic).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include <nlohmann/json_fwd.hpp>

#include "lighting/BounceField.h"

namespace CLI {
class App;
}

namespace amb {

class World;

// The lattice a single run lays when nothing says otherwise: 128 m within 600 m of its path
// (a bench, with many runs to pay for, passes 256 m within 500 m).
BounceSettings runBounceSettings();

// Adds the options above to `cmd`, into `light` and `bounce` (which must outlive the parse).
void addReferenceLightOptions(CLI::App& cmd, std::string& light, BounceSettings& bounce);

// {"spacing_m", "reach_m", "faceSize", "tolerance", "solves": [{"timeOfDay_h", "points",
// "bounces", "converged", "changes", "maxPointChanges", "captures", "seconds"}, ...]}.
nlohmann::json bounceJson(const BounceSettings& settings, const std::vector<BounceSolve>& solves);

// Where the lattice's point (x, z) stands: the probes' rule (WorldProbeEnvironment::placeProbe,
// moved aside at most MeasureSettings::maxAside_m) at kBounceHeight_m, whatever height the
// methods' probes stand at, so the reference does not move with them. `world` must outlive it.
std::function<glm::dvec3(double x_m, double z_m)> bounceLatticePlacement(const World& world);

// `--capture-light own|reference` into `light` (which must outlive the parse); whether a text
// names one of the two.
void addCaptureLightOption(CLI::App& cmd, std::string& light);
bool isCaptureLight(const std::string& text);

}  // namespace amb
