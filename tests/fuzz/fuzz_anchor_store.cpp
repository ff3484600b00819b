// fuzz_anchor_store — amb::AnchorStore::load (lighting/AnchorStore.h) on arbitrary bytes
// written to a temporary .vdb file. A store that loads must answer lookups with finite values
// (NaN never enters the store) and must save and load again.
//
// Store files carry a CRC-32 that almost every mutation breaks, which would keep the fuzzer at
// the checksum test. So when the input's header can be read and holds the checksum, the first
// byte of the input picks: even, the checksum is recomputed for the mutated bytes (the fuzzer
// reaches the stream walk and OpenVDB's reader); odd, the bytes are loaded as they are.
#include <cinttypes>
#include <cmath>
#include <cstdio>

#include "FuzzSupport.h"
#include "lighting/AnchorStore.h"
#include "lighting/AnchorStoreFile.h"
#include "lighting/SH.h"
#include "world/Error.h"

namespace {

std::string withChecksumFixed(std::string bytes) {
    try {
        const amb::VdbFileSummary header = amb::readVdbHeader(bytes, "fuzz.vdb");
        const auto it = header.metadata.find(amb::kAnchorStoreChecksumKey);
        if (it == header.metadata.end() || it->second.bytes.size() != 8) return bytes;
        char digits[9];
        std::snprintf(digits, sizeof(digits), "%08" PRIx32,
                      amb::anchorStoreChecksum(bytes, it->second.offset));
        bytes.replace(it->second.offset, 8, digits, 8);
    } catch (const amb::InputError&) {
    }
    return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    std::string bytes = amb::fuzz::asText(data + 1, size - 1);
    if (data[0] % 2 == 0) bytes = withChecksumFixed(std::move(bytes));
    const amb::fuzz::TempInputFile file(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                        bytes.size(), ".vdb");
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
