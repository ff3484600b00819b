// fuzz_oracle — amb::ErrorMeter::loadOracle (lighting/Metrics.h), the oracle cache of
// `ambience run --oracle`, on arbitrary bytes written to a temporary file. The signature is
// fixed ("fuzz"); the seed corpus carries it, so the fuzzer reaches the entries.
#include "FuzzStubs.h"
#include "FuzzSupport.h"
#include "lighting/Metrics.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static amb::fuzz::StubCapture capture;
    static const amb::fuzz::StubEnvironment environment;
    const amb::fuzz::TempInputFile file(data, size, ".json");
    amb::ErrorMeter meter(capture, environment, amb::MeasureSettings{});
    try {
        meter.loadOracle(file.path(), "fuzz");
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(meter.oracleCaptures() == 0);
    return 0;
}
