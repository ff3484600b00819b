// fuzz_baseline_settings — amb::baselineSettingsFromJson (lighting/Baselines.h). Settings the
// reader accepts must be settings the baselines run with: the grid, the reactive cache and the
// per-object method are built from them and driven for a few frames (stub capture), and every
// lookup is finite; and the settings file the schema writes of them reads back equal.
#include <memory>

#include "FuzzStubs.h"
#include "FuzzSupport.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"
#include "lighting/SH.h"
#include "lighting/SettingsSchema.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    amb::BaselineSettings settings;
    try {
        settings = amb::baselineSettingsFromJson(amb::fuzz::asText(data, size), "fuzz.json");
    } catch (const amb::InputError&) {
        return 0;
    }
    // What the reader takes, the schema's writer writes back as a file it reads equal.
    {
        const auto& schema = amb::baselineSettingsSchema();
        AMB_FUZZ_EXPECT(schema.equal(amb::baselineSettingsFromJson(schema.write(settings), "fuzz.json"), settings));
    }
    amb::fuzz::StubCapture capture;
    amb::fuzz::StubEnvironment environment;
    for (const char* name : {"grid", "reactive", "object"}) {
        auto method = amb::makeCapturingMethod(name, capture, environment, {}, settings, nullptr);
        amb::fuzz::driveAndCheck(*method);
    }
    return 0;
}
