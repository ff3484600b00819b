// fuzz_volume_settings — amb::ambienceSettingsFromJson (lighting/AmbienceVolume.h). Settings the
// reader accepts must be settings the volume runs with: the volume and the nearest-anchor method
// are built from them and driven for a few frames (stub capture), and every lookup is finite.
#include <cmath>
#include <memory>

#include "FuzzStubs.h"
#include "FuzzSupport.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"
#include "lighting/SH.h"
#include "world/Error.h"

namespace {

bool finite(const amb::ShRgb& sh) {
    for (const auto& k : sh.c)
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(k[c])) return false;
    return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    amb::AmbienceVolumeSettings settings;
    try {
        settings = amb::ambienceSettingsFromJson(amb::fuzz::asText(data, size), "fuzz.json");
    } catch (const amb::InputError&) {
        return 0;
    }
    amb::fuzz::StubCapture capture;
    amb::fuzz::StubEnvironment environment;
    for (const char* name : {"volume", "nearest"}) {
        auto method = amb::makeCapturingMethod(name, capture, environment, settings, {}, nullptr);
        // A short drive: 14 frames at 30 m/s, so a probe completes and enters the store.
        for (int f = 0; f < 14; ++f) {
            const glm::dvec3 camera(0.5 * f, 2.0, 0.25 * f);
            method->predictStage(camera, glm::dvec3(30.0, 0.0, 15.0), 12.0 + 0.001 * f, 1.0 / 60);
            method->captureStage();
            method->storeStage();
        }
        for (double x : {0.0, 3.0, -40.0, 1000.0})
            AMB_FUZZ_EXPECT(finite(method->shAt(x, 0.5 * x)));
    }
    return 0;
}
