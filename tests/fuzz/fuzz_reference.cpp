// fuzz_reference — amb::ErrorMeter::loadReference (lighting/Metrics.h), the reference cache of
// `ambience run --reference`, on arbitrary bytes written to a temporary file. The signature is
// fixed ("fuzz"); the seed corpus carries it, so the fuzzer reaches the entries and the screen
// witnesses' list. Only InputError may come out, and nothing is captured by loading.
#include "FuzzStubs.h"
#include "FuzzSupport.h"
#include "lighting/Metrics.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static amb::fuzz::StubCapture capture;
    static const amb::fuzz::StubEnvironment environment;
    const amb::fuzz::TempInputFile file(data, size, ".json");
    amb::ErrorMeter meter(capture, environment, amb::MeasureSettings{});
    meter.attachReference(capture, amb::ReferenceSettings{}, true);
    try {
        meter.loadReference(file.path(), "fuzz");
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(meter.referenceCaptures() == 0);
    return 0;
}
