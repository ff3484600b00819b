// fuzz_volume_settings — amb::ambienceSettingsFromJson (lighting/AmbienceVolume.h). Settings the
// reader accepts must be settings the volume runs with: the volume and the nearest-anchor method
// are built from them and driven for a few frames (stub capture), and every lookup is finite;
// and the settings file the schema writes of them reads back equal.
#include <memory>

#include "FuzzStubs.h"
#include "FuzzSupport.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"
#include "lighting/SH.h"
#include "lighting/SettingsSchema.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    amb::AmbienceVolumeSettings settings;
    try {
        settings = amb::ambienceSettingsFromJson(amb::fuzz::asText(data, size), "fuzz.json");
    } catch (const amb::InputError&) {
        return 0;
    }
    // What the reader takes, the schema's writer writes back as a file it reads equal.
    {
        const auto& schema = amb::volumeSettingsSchema();
        AMB_FUZZ_EXPECT(schema.equal(amb::ambienceSettingsFromJson(schema.write(settings), "fuzz.json"), settings));
    }
    amb::fuzz::StubCapture capture;
    amb::fuzz::StubEnvironment environment;
    for (const char* name : {"volume", "nearest"}) {
        auto method = amb::makeCapturingMethod(name, capture, environment, settings, {}, nullptr);
        amb::fuzz::driveAndCheck(*method);
    }
    return 0;
}
