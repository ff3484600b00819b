// fuzz_anchor_store — amb::AnchorStore::load (lighting/AnchorStore.h) on arbitrary bytes
// written to a temporary .vdb file. A store that loads must answer lookups with finite values
// (NaN never enters the store) and must save and load again.
#include <cmath>

#include "FuzzSupport.h"
#include "lighting/AnchorStore.h"
#include "lighting/SH.h"
#include "world/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const amb::fuzz::TempInputFile file(data, size, ".vdb");
    amb::AnchorStore store;
    try {
        store.load(file.path());
    } catch (const amb::InputError&) {
        return 0;
    }
    for (double x : {0.0, 13.0, -200.0, 5000.0}) {
        const amb::ShRgb sh = store.interpolate(x, 0.7 * x);
        for (const auto& k : sh.c)
            for (int c = 0; c < 3; ++c) AMB_FUZZ_EXPECT(std::isfinite(k[c]));
    }
    store.advance(store.now_s() + 0.5);
    // What the store wrote, it reads back.
    const amb::fuzz::TempInputFile again(nullptr, 0, ".again.vdb");
    store.save(again.path());
    amb::AnchorStore reloaded;
    reloaded.load(again.path());
    AMB_FUZZ_EXPECT(reloaded.statistics().anchors == store.statistics().anchors);
    return 0;
}
