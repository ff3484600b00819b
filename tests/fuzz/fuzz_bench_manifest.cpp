// fuzz_bench_manifest — bench.json as `ambience bench --collect DIR` reads it (a bounded,
// link-refusing read, then amb::parseBenchManifest, app/bench/BenchCollect.h). An accepted
// manifest must name nothing outside its folder: plain, distinct replay names, absolute
// one-line replay paths, the sweep "" or "sweep.json", run folders one level below runs/, no
// control character anywhere; and it must write back as it was read.
#include <set>

#include "FuzzSupport.h"
#include "app/bench/BenchCollect.h"
#include "world/Error.h"
#include "world/TextFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const amb::fuzz::TempInputFile file(data, size, ".json");
    amb::BenchManifest m;
    try {
        m = amb::parseBenchManifest(
            amb::readTextFile(file.path(), "bench.json", amb::kMaxBenchManifestBytes,
                              amb::Links::Refuse),
            file.path());
    } catch (const amb::InputError&) {
        return 0;
    }
    std::set<std::string> names;
    AMB_FUZZ_EXPECT(!m.replays.empty());
    for (const auto& r : m.replays) {
        AMB_FUZZ_EXPECT(!r.name.empty() && names.insert(r.name).second);
        AMB_FUZZ_EXPECT(
            r.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                     "0123456789-_") == std::string::npos);
        AMB_FUZZ_EXPECT(!r.path.empty() && r.path.front() == '/');
        AMB_FUZZ_EXPECT(!amb::hasControlCharacter(r.path));
    }
    AMB_FUZZ_EXPECT(m.sweep.empty() || m.sweep == "sweep.json");
    for (const std::string& run : m.runs) {
        AMB_FUZZ_EXPECT(run.rfind("runs/", 0) == 0 && run.size() > 5);
        AMB_FUZZ_EXPECT(run.find('/', 5) == std::string::npos && run[5] != '.');
        AMB_FUZZ_EXPECT(!amb::hasControlCharacter(run));
    }
    for (const std::string* s : {&m.command, &m.methods, &m.budgets, &m.oracle, &m.backend})
        AMB_FUZZ_EXPECT(!amb::hasControlCharacter(*s));
    AMB_FUZZ_EXPECT(m.stride >= 1 && m.measureEvery >= 1 && m.maxFrames >= 0);
    const amb::BenchManifest back =
        amb::parseBenchManifest(amb::benchManifestJson(m).dump(), "round trip");
    AMB_FUZZ_EXPECT(amb::benchManifestJson(back) == amb::benchManifestJson(m));
    return 0;
}
