// AnchorStoreCorruption_test.cpp — damaged .vdb anchor stores: every corruption, truncation or
// absurd declared size gives InputError (never a crash, an abort, a hang or a huge allocation),
// the file is left as it was and the store keeps its contents; with the checksum recomputed
// after the damage (a forged file), the structure walk of AnchorStoreFile.h still stops
// everything OpenVDB could not read safely, and what loads is finite.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "lighting/AnchorStore.h"
#include "lighting/AnchorStoreFile.h"
#include "world/Error.h"

namespace amb {
namespace {

std::string tempPath(const std::string& name) {
    return std::string(AMBIENCE_BINARY_DIR) + "/AnchorStoreCorruption_" + name;
}

std::string readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

ShRgb makeSh(float v) {
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k) sh.c[k] = glm::vec3(v * (1 + k), v, 2.0f * v);
    return sh;
}

// A small store (anchors on three levels, one mid-blend), saved: the bytes under test (380 kB,
// mostly the node masks of the 41 grids' trees; the anchors share one top node per grid).
std::string smallStoreBytes() {
    AnchorStore store;
    store.insert({4, 7, 2}, makeSh(1.5f), {21.0, 3.0, 6.0}, 100.0, 9.25);
    store.insert({3, 1, 1}, makeSh(2.5f), {9.0, 2.5, 9.0}, 100.0, 9.25);
    store.advance(0.5);
    store.insert({0, 1, 1}, makeSh(0.5f), {243.0, 7.0, 243.0}, 100.0, 9.5);
    const std::string path = tempPath("small.vdb");
    store.save(path);
    std::string bytes = readBytes(path);
    std::remove(path.c_str());
    return bytes;
}

// The store a failed load must leave alone.
AnchorStore oneAnchorStore() {
    AnchorStore store;
    store.insert({4, 1, 1}, makeSh(1.0f), {3, 2, 3}, 100.0);
    return store;
}

bool finiteStore(const AnchorStore& store) {
    bool ok = true;
    store.forEach([&](const Anchor& a) {
        for (const ShRgb* sh : {&a.current, &a.target, &a.blendFrom}) {
            for (const auto& c : sh->c)
                for (int ch = 0; ch < 3; ++ch) ok &= std::isfinite(c[ch]);
        }
    });
    for (double x : {-300.0, -5.0, 0.0, 13.0, 250.0}) {
        const ShRgb v = store.interpolate(x, 0.7 * x);
        for (const auto& c : v.c)
            for (int ch = 0; ch < 3; ++ch) ok &= std::isfinite(c[ch]);
    }
    return ok;
}

// Positions to damage: every byte of the first `whole` (the header, the file metadata and the
// start of the first grid), then `spread` positions evenly over the rest.
std::vector<std::size_t> damagePositions(std::size_t size, std::size_t whole, std::size_t spread) {
    std::vector<std::size_t> at;
    for (std::size_t p = 0; p < std::min(size, whole); ++p) at.push_back(p);
    for (std::size_t n = 0; n < spread && size > whole; ++n)
        at.push_back(whole + n * (size - whole) / spread);
    return at;
}

// Loads `bytes` from a file into a store holding one anchor; returns whether it loaded, and
// checks on failure that the error is InputError, the store unchanged and the file untouched.
bool tryLoad(const std::string& bytes, const std::string& path, const std::string& label) {
    writeBytes(path, bytes);
    AnchorStore store = oneAnchorStore();
    try {
        store.load(path);
    } catch (const InputError& e) {
        EXPECT_EQ(store.size(), 1u) << label;
        EXPECT_NE(store.find({4, 1, 1}), nullptr) << label;
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << label << ": " << e.what();
        EXPECT_TRUE(readBytes(path) == bytes) << label << ": the file changed";
        return false;
    }
    EXPECT_TRUE(finiteStore(store)) << label;
    return true;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One changed byte anywhere (every position of the first 2 kB, 400 spread over the rest; one
// bit or all eight) is refused: the checksum no longer matches. (Before the checksum and the
// in-memory read, such files gave SIGSEGV, OpenVDB assertion aborts, heap overflows in its Blosc
// reader or "internal error" exits from data read after load.)
TEST(AnchorStoreCorruption, EveryByteFlipIsAnInputError) {
    const std::string good = smallStoreBytes();
    const std::string path = tempPath("flip.vdb");
    ASSERT_TRUE(tryLoad(good, path, "intact"));
    int refused = 0, positions = 0;
    for (std::size_t p : damagePositions(good.size(), 2048, 400)) {
        std::string bad = good;
        bad[p] = char(bad[p] ^ (p % 2 ? 0x01 : 0xFF));
        refused += !tryLoad(bad, path, "byte " + std::to_string(p));
        ++positions;
    }
    EXPECT_EQ(refused, positions);
    std::remove(path.c_str());
}

// Truncated at any length (0 to 600 bytes, 300 lengths spread over the file, and the last 64
// lengths): InputError. (Before: a store cut by one byte hung while memory grew to 8 GB.)
TEST(AnchorStoreCorruption, EveryTruncationIsAnInputError) {
    const std::string good = smallStoreBytes();
    const std::string path = tempPath("truncated.vdb");
    std::vector<std::size_t> lengths;
    for (std::size_t n = 0; n < 600; ++n) lengths.push_back(n);
    for (std::size_t n = 0; n < 300; ++n) lengths.push_back(n * good.size() / 300);
    for (std::size_t n = 1; n <= 64; ++n) lengths.push_back(good.size() - n);
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t n : lengths) {
        EXPECT_FALSE(tryLoad(good.substr(0, n), path, "length " + std::to_string(n)));
    }
    // And appended bytes.
    EXPECT_FALSE(tryLoad(good + std::string(1, '\0'), path, "one byte more"));
    EXPECT_LT(secondsSince(t0), 60.0);
    std::remove(path.c_str());
}

// The same damage with the checksum recomputed (as a deliberately forged file would have it):
// every file either loads into a finite store or is refused with InputError — the structure
// walk stops declared sizes, counts and node layouts OpenVDB would trust. Both outcomes occur
// (a changed coefficient or age still loads).
TEST(AnchorStoreCorruption, ForgedChecksumsNeverCrashAndLoadOnlyFiniteStores) {
    const std::string good = smallStoreBytes();
    const std::string path = tempPath("forged.vdb");
    int loaded = 0, refused = 0;
    for (std::size_t p : damagePositions(good.size(), 600, 300)) {
        for (unsigned char mask : {0x01, 0xFF}) {
            if (p < 600 && mask != (p % 2 ? 0x01 : 0xFF)) continue;  // one change per header byte
            std::string bad = good;
            bad[p] = char(bad[p] ^ mask);
            try {
                refreshAnchorStoreChecksum(bad, "forged");
            } catch (const InputError&) {
                // The header or metadata no longer parse: nothing to forge; refused as is.
            }
            if (tryLoad(bad, path, "forged byte " + std::to_string(p)))
                ++loaded;
            else
                ++refused;
        }
    }
    EXPECT_GT(loaded, 0);
    EXPECT_GT(refused, 0);
    std::remove(path.c_str());
}

// Field of the file-level metadata `name`: offset of its value and of its 4-byte size.
std::size_t metadataValueOffset(const std::string& bytes, const std::string& name) {
    const VdbFileSummary header = readVdbHeader(bytes, "test");
    const auto it = header.metadata.find(name);
    EXPECT_NE(it, header.metadata.end()) << name;
    return it == header.metadata.end() ? 0 : it->second.offset;
}

template <typename T>
void put(std::string& bytes, std::size_t at, T v) {
    std::memcpy(&bytes[at], &v, sizeof v);
}

// Sizes and counts that OpenVDB would allocate before checking them are refused from the
// bytes, quickly: a 2 GB metadata string, a 4 GB metadata name, 2^31 - 1 anchors and 2^31 - 1
// grids (both with a valid checksum). (Before: the anchor count was allocated as a vector
// before it was compared with the grids; the strings as std::string.)
TEST(AnchorStoreCorruption, HugeDeclaredSizesAreRefusedBeforeAllocation) {
    const std::string good = smallStoreBytes();
    const std::string path = tempPath("huge.vdb");
    const auto t0 = std::chrono::steady_clock::now();

    std::string longString = good;
    put(longString, metadataValueOffset(good, "format") - 4, std::uint32_t(0x7FFFFFFF));
    EXPECT_FALSE(tryLoad(longString, path, "2 GB metadata string"));

    std::string longName = good;
    put(longName, 57 + 4, std::uint32_t(0xFFFFFFF0));  // header, entry count, first name length
    EXPECT_FALSE(tryLoad(longName, path, "4 GB metadata name"));

    std::string manyAnchors = good;
    put(manyAnchors, metadataValueOffset(good, "anchors"),
        std::numeric_limits<std::int32_t>::max());
    refreshAnchorStoreChecksum(manyAnchors, "test");
    writeBytes(path, manyAnchors);
    try {
        AnchorStore().load(path);
        ADD_FAILURE() << "2^31 - 1 anchors loaded";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("for 2147483647 anchors"), std::string::npos)
            << e.what();
    }

    // The grid count follows the last metadata value.
    const VdbFileSummary header = readVdbHeader(good, "test");
    std::size_t metaEnd = 0;
    for (const auto& [name, value] : header.metadata)
        metaEnd = std::max(metaEnd, value.offset + value.bytes.size());
    std::string manyGrids = good;
    put(manyGrids, metaEnd, std::numeric_limits<std::int32_t>::max());
    refreshAnchorStoreChecksum(manyGrids, "test");
    writeBytes(path, manyGrids);
    try {
        AnchorStore().load(path);
        ADD_FAILURE() << "2^31 - 1 grids loaded";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("grid count 2147483647"), std::string::npos)
            << e.what();
    }
    EXPECT_LT(secondsSince(t0), 5.0);
    std::remove(path.c_str());
}

// A file larger than kMaxAnchorStoreFileBytes is refused from its size, before it is read; a
// directory or a device is not a store file.
TEST(AnchorStoreCorruption, OversizedFilesAndNonFilesAreRefused) {
    const std::string path = tempPath("oversized.vdb");
    {
        std::ofstream out(path, std::ios::binary);
        out.seekp(std::streamoff(kMaxAnchorStoreFileBytes));  // sparse: nothing is written
        out.put('\0');
    }
    ASSERT_GT(std::filesystem::file_size(path), kMaxAnchorStoreFileBytes);
    AnchorStore store = oneAnchorStore();
    EXPECT_THROW(store.load(path), InputError);
    EXPECT_THROW(store.load(std::string(AMBIENCE_BINARY_DIR)), InputError);
    EXPECT_THROW(store.load("/dev/zero"), InputError);
    EXPECT_EQ(store.size(), 1u);
    std::remove(path.c_str());
}

// Files of the previous format (no checksum, Blosc-compressed, read with delayed loading) are
// refused with a message naming the format, not read.
TEST(AnchorStoreCorruption, PreviousFormatIsRefusedByName) {
    openvdb::initialize();
    auto grid = openvdb::Int32Grid::create(-1);
    grid->setName("anchor_index_L0");
    openvdb::MetaMap meta;
    meta.insertMeta("format", openvdb::StringMetadata("ambience-anchor-store-v1"));
    const std::string path = tempPath("v1.vdb");
    openvdb::io::File file(path);
    file.write({grid}, meta);
    file.close();
    try {
        AnchorStore().load(path);
        ADD_FAILURE() << "a v1 file loaded";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("ambience-anchor-store-v1"), std::string::npos) << what;
        EXPECT_NE(what.find("ambience-anchor-store-v2"), std::string::npos) << what;
    }
    std::remove(path.c_str());
}

// save() writes beside the file and renames: the old file is replaced whole, no ".part" stays
// behind, and a save that cannot be written leaves nothing.
TEST(AnchorStoreCorruption, SaveReplacesTheFileWhole) {
    const std::string path = tempPath("replace.vdb");
    AnchorStore first = oneAnchorStore();
    first.save(path);
    AnchorStore second;
    second.insert({2, 3, -4}, makeSh(0.25f), {81.0, 1.0, -108.0}, 50.0);
    second.insert({2, 4, -4}, makeSh(0.5f), {108.0, 1.0, -108.0}, 50.0);
    second.save(path);
    EXPECT_FALSE(std::filesystem::exists(path + ".part"));
    AnchorStore loaded;
    loaded.load(path);
    EXPECT_EQ(loaded.size(), 2u);
    EXPECT_NE(loaded.find({2, 3, -4}), nullptr);
    EXPECT_EQ(loaded.find({4, 1, 1}), nullptr);
    const std::string missingDir = tempPath("no_such_dir") + "/store.vdb";
    EXPECT_THROW(second.save(missingDir), InputError);
    EXPECT_FALSE(std::filesystem::exists(missingDir + ".part"));
    std::remove(path.c_str());
}

}  // namespace
}  // namespace amb
