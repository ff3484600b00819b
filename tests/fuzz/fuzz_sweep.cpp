// fuzz_sweep — amb::parseSweep (app/bench/BenchSweep.h), the parameter points of `ambience bench
// --sweep`. Accepted points must hold what the bench relies on: the default point first, unique
// labels without separators, 1 to kMaxFacesPerFrame faces per frame, settings objects that
// serialise.
#include <set>

#include "FuzzSupport.h"
#include "app/bench/BenchSweep.h"
#include "lighting/AmbienceMethod.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // The names `ambience run --ambient` takes (app/frame/MethodStages.cpp).
    static const std::vector<std::string> methods = {"volume", "nearest",  "grid",      "reactive",
                                                     "object", "constant", "hemisphere"};
    std::vector<amb::SweepPoint> points;
    try {
        points = amb::parseSweep(amb::fuzz::asText(data, size), "fuzz.json", methods);
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(!points.empty() && points.front().label == "default");
    std::set<std::string> labels;
    for (const amb::SweepPoint& p : points) {
        AMB_FUZZ_EXPECT(labels.insert(p.label).second);
        AMB_FUZZ_EXPECT(!p.label.empty() && p.label.find_first_of("/ _,;") == std::string::npos);
        AMB_FUZZ_EXPECT(p.facesPerFrame >= 1 && p.facesPerFrame <= amb::kMaxFacesPerFrame);
        AMB_FUZZ_EXPECT(p.volume.is_object() && p.baseline.is_object());
        // The bench writes these as the run's settings files.
        (void)p.volume.dump(2);
        (void)p.baseline.dump(2);
    }
    return 0;
}
