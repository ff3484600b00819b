// ReferenceLightFlags.h — what lights the reference's surfaces, on the command line of run and
// compare (and, passed through, bench): `--reference-light bounce|hemisphere` (default bounce:
// the scene's own bounce field, lighting/BounceField.h) and the field's lattice,
// `--bounce-spacing`, `--bounce-reach`, `--bounce-face`, `--bounce-canopy`; and the field's
// record in a report.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "lighting/BounceField.h"

namespace CLI {
class App;
}

namespace amb {

// The lattice a single run lays when nothing says otherwise: 128 m within 600 m of its path
// (a bench, with many runs to pay for, passes 256 m within 500 m).
BounceSettings runBounceSettings();

// Adds the options above to `cmd`, into `light` and `bounce` (which must outlive the parse).
void addReferenceLightOptions(CLI::App& cmd, std::string& light, BounceSettings& bounce);

// {"spacing_m", "reach_m", "faceSize", "tolerance", "solves": [{"timeOfDay_h", "points",
// "bounces", "converged", "changes", "maxPointChanges", "captures", "seconds"}, ...]}.
nlohmann::json bounceJson(const BounceSettings& settings, const std::vector<BounceSolve>& solves);

}  // namespace amb
