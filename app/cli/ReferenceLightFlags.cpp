// ReferenceLightFlags.cpp — the reference light's options and report fields.
#include "app/cli/ReferenceLightFlags.h"

#include <cmath>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "lighting/Metrics.h"
#include "lighting/ProbeEnvironment.h"

namespace amb {

BounceSettings runBounceSettings() {
    BounceSettings s;
    s.spacing_m = 128.0;
    s.reach_m = 600.0;
    return s;
}

void addReferenceLightOptions(CLI::App& cmd, std::string& light, BounceSettings& bounce) {
    cmd.add_option("--reference-light", light,
                   "what lights the reference's surfaces besides the sun: bounce (default: the "
                   "scene's own indirect light, a lattice of full-scene captures iterated until "
                   "a bounce changes it by less than 1 %) or hemisphere (the fixed sky/ground "
                   "ambient the near field also models)");
    cmd.add_option("--bounce-spacing", bounce.spacing_m,
                   "bounce lattice spacing [m] (default " + std::to_string(int(bounce.spacing_m)) +
                       ")");
    cmd.add_option("--bounce-reach", bounce.reach_m,
                   "bounce lattice points within this distance of the path [m] (default " +
                       std::to_string(int(bounce.reach_m)) + ")");
    cmd.add_option("--bounce-face", bounce.faceSize,
                   "face size of the bounce lattice's captures (default " +
                       std::to_string(bounce.faceSize) + ")");
    cmd.add_option("--bounce-canopy", bounce.canopy_m,
                   "a second layer of bounce points this far above the first [m], read by "
                   "surfaces by their height; 0: one layer (default " +
                       std::to_string(int(bounce.canopy_m)) + ")");
}

std::function<glm::dvec3(double, double)> bounceLatticePlacement(const World& world) {
    WorldProbeEnvironmentSettings placement;
    placement.probeHeight_m = kBounceHeight_m;
    auto env = std::make_shared<const WorldProbeEnvironment>(world, placement);
    const double maxAside_m = MeasureSettings{}.maxAside_m;
    return [env, maxAside_m](double x_m, double z_m) { return env->placeProbe(x_m, z_m, maxAside_m); };
}

void addCaptureLightOption(CLI::App& cmd, std::string& light) {
    cmd.add_option("--capture-light", light,
                   "with a bounce-lit reference: what lights the surfaces of the methods' "
                   "captures besides the sun, own (default: each method's settings) or reference "
                   "(the reference's bounce field, which no method has: a diagnostic of how much "
                   "of the error is that light)");
}

bool isCaptureLight(const std::string& text) { return text == "own" || text == "reference"; }

nlohmann::json bounceJson(const BounceSettings& settings, const std::vector<BounceSolve>& solves) {
    using nlohmann::json;
    json list = json::array();
    for (const BounceSolve& s : solves)
        list.push_back({{"timeOfDay_h", s.timeOfDay_h},
                        {"points", s.points},
                        {"bounces", s.bounces},
                        {"converged", s.converged},
                        {"changes", s.changes},
                        {"maxPointChanges", s.maxPointChanges},
                        {"captures", s.captures},
                        {"seconds", s.seconds}});
    return {{"spacing_m", settings.spacing_m},
            {"reach_m", settings.reach_m},
            {"faceSize", settings.faceSize},
            {"tolerance", settings.tolerance},
            {"canopy_m", settings.canopy_m},
            {"solves", list}};
}

}  // namespace amb
