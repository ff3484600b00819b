// AnchorStoreFile.cpp — the structure walk, checksum and sealing of anchor-store files (see
// AnchorStoreFile.h). The walk mirrors OpenVDB's stream reader (io::Archive, GridDescriptor,
// MetaMap, Transform, RootNode/InternalNode/LeafNode::readTopology and readBuffers,
// io::readCompressedValues) for the accepted subset, and refuses everything else.
#include "lighting/AnchorStoreFile.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <utility>

#include <boost/crc.hpp>

#include "world/Error.h"

namespace amb {

namespace {

// OpenVDB format constants (version.h, io/Compression.h, tree/*.h).
constexpr std::int64_t kVdbMagic = 0x56444220;
constexpr std::uint32_t kMinFileVersion = 222;  // NODE_MASK_COMPRESSION: per-grid compression
constexpr std::uint32_t kMaxFileVersion = 224;  // MULTIPASS_IO (OpenVDB 10)
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 4 + 1 + 36;
constexpr std::size_t kHasGridOffsetsAt = 8 + 4 + 4 + 4;
constexpr std::uint32_t kCompressActiveMask = 0x2;  // COMPRESS_ACTIVE_MASK, nothing else
constexpr int kNoMaskAndAllValues = 6;              // per-node metadata byte: 0..6
constexpr std::size_t kMaxMetadataEntries = 64;
constexpr std::size_t kMaxTypeNameBytes = 64;
constexpr int kLeafLog2 = 3, kNode4Log2 = 4, kNode5Log2 = 5;
constexpr std::int32_t kRootChildSpan = 1 << (kLeafLog2 + kNode4Log2 + kNode5Log2);  // 4096
constexpr const char* kDelayedLoadType = "__delayedload";

struct GridType {
    const char* name;
    std::size_t valueBytes;
};
constexpr std::array<GridType, 4> kGridTypes{{{"Tree_int32_5_4_3", 4},
                                              {"Tree_float_5_4_3", 4},
                                              {"Tree_vec3s_5_4_3", 12},
                                              {"Tree_vec3d_5_4_3", 24}}};

// Exact sizes of the accepted fixed-size metadata types (TypedMetadata<T>::readValue reads
// sizeof(T) whatever the stored size says, so any other size would desynchronise the reader).
std::size_t metadataSize(const std::string& type) {
    static const std::pair<const char*, std::size_t> kSizes[] = {
        {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},
        {"double", 8}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}};
    for (const auto& [name, size] : kSizes) {
        if (type == name) return size;
    }
    return 0;
}

// Memory OpenVDB takes per node of a 5-4-3 tree of `valueBytes` values: the internal nodes'
// tables hold a value or a child pointer per entry (rounded up as a union or, for values wider
// than a pointer, a pair), leaves a dense buffer; the internal nodes' read also allocates a
// temporary array of all their values.
std::uint64_t tableEntryBytes(std::size_t valueBytes) {
    const std::uint64_t v = (valueBytes + 7) / 8 * 8;
    return valueBytes <= 8 ? 8 : v + 8;
}
std::uint64_t internalNodeBytes(int log2, std::size_t valueBytes) {
    const std::uint64_t entries = std::uint64_t(1) << (3 * log2);
    return entries * (tableEntryBytes(valueBytes) + valueBytes) + entries / 4 + 64;
}
std::uint64_t leafBytes(std::size_t valueBytes) {
    return 512 * valueBytes + 64 + 64;
}

using Mask = std::vector<std::uint64_t>;

int popcount(const Mask& m) {
    int n = 0;
    for (std::uint64_t w : m) n += __builtin_popcountll(w);
    return n;
}

// Calls f(n) for every set bit n, in increasing order.
void forEachOn(const Mask& m, const std::function<void(std::uint32_t)>& f) {
    for (std::size_t w = 0; w < m.size(); ++w) {
        std::uint64_t word = m[w];
        while (word) {
            const int b = __builtin_ctzll(word);
            f(std::uint32_t(w * 64 + std::size_t(b)));
            word &= word - 1;
        }
    }
}

// The y index of bit n of a node mask (n = x << 2L | y << L | z).
std::uint32_t maskY(std::uint32_t n, int log2) {
    return (n >> log2) & ((1u << log2) - 1);
}

// What sealing needs to know about one grid (positions in the walked bytes).
struct GridLayout {
    std::size_t offsetsAt = 0;    // the descriptor's three int64 offsets
    std::size_t gridPos = 0;      // first byte after them (compression flags)
    std::size_t metaCountAt = 0;  // the grid metadata's entry count
    std::uint32_t cutEntries = 0;
    std::size_t blockPos = 0;  // first leaf buffer
    std::size_t endPos = 0;
};

class Walker {
  public:
    Walker(const std::string& bytes, std::string where, const VdbLimits& limits, bool sealing)
        : b_(bytes), where_(std::move(where)), limits_(limits), sealing_(sealing) {}

    VdbFileSummary header();
    VdbFileSummary whole();

    std::vector<std::pair<std::size_t, std::size_t>> cuts;  // [begin, end) to drop (sealing)
    std::vector<GridLayout> layouts;

  private:
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(where_, what + " (at byte " + std::to_string(p_) + ")");
    }
    void need(std::uint64_t n, const std::string& what) const {
        if (n > b_.size() - p_) {
            fail(what + " needs " + std::to_string(n) + " bytes, the file has " +
                 std::to_string(b_.size() - p_) + " left");
        }
    }
    template <typename T>
    T get(const std::string& what) {
        need(sizeof(T), what);
        T v;
        std::memcpy(&v, b_.data() + p_, sizeof(T));
        p_ += sizeof(T);
        return v;
    }
    void skip(std::uint64_t n, const std::string& what) {
        need(n, what);
        p_ += std::size_t(n);
    }
    std::string string(const std::string& what, std::size_t maxBytes) {
        const std::uint32_t n = get<std::uint32_t>(what + " length");
        if (n > maxBytes) {
            fail(what + " declares " + std::to_string(n) + " bytes (at most " +
                 std::to_string(maxBytes) + ")");
        }
        need(n, what);
        std::string s = b_.substr(p_, n);
        p_ += n;
        return s;
    }
    Mask mask(int log2, const std::string& what) {
        const std::size_t words = (std::size_t(1) << (3 * log2)) / 64;
        need(words * 8, what);
        Mask m(words);
        std::memcpy(m.data(), b_.data() + p_, words * 8);
        p_ += words * 8;
        return m;
    }

    std::map<std::string, VdbMetadataValue> metadata(const std::string& what, bool gridLevel,
                                                     GridLayout* layout);
    void compressedValues(const Mask& valueMask, int log2, std::size_t valueBytes,
                          const std::string& what);
    void internalNode(int log2, std::size_t valueBytes, std::vector<Mask>& leafMasks,
                      VdbGridSummary& grid, const std::string& what);
    void grid(std::size_t index, VdbFileSummary& summary);

    const std::string& b_;
    std::string where_;
    VdbLimits limits_;
    bool sealing_;
    std::size_t p_ = 0;
    std::uint64_t readBytes_ = 0;
    std::uint64_t activeVoxels_ = 0;
};

std::map<std::string, VdbMetadataValue> Walker::metadata(const std::string& what, bool gridLevel,
                                                         GridLayout* layout) {
    if (layout) layout->metaCountAt = p_;
    const std::uint32_t count = get<std::uint32_t>(what + " count");
    if (count > kMaxMetadataEntries) {
        fail(what + " declares " + std::to_string(count) + " entries (at most " +
             std::to_string(kMaxMetadataEntries) + ")");
    }
    std::map<std::string, VdbMetadataValue> out;
    for (std::uint32_t e = 0; e < count; ++e) {
        const std::size_t entryStart = p_;
        const std::string name = string(what + " name", kMaxVdbStringBytes);
        const std::string item = what + " '" + name + "'";
        const std::string type = string(item + " type", kMaxTypeNameBytes);
        const std::uint32_t size = get<std::uint32_t>(item + " size");
        if (sealing_ && gridLevel && type == kDelayedLoadType) {
            // Written by OpenVDB itself into the stream being sealed: dropped whole.
            skip(size, item);
            cuts.push_back({entryStart, p_});
            ++layout->cutEntries;
            continue;
        }
        if (type == "string") {
            if (size > kMaxVdbStringBytes) {
                fail(item + " declares " + std::to_string(size) + " bytes (at most " +
                     std::to_string(kMaxVdbStringBytes) + ")");
            }
        } else {
            const std::size_t expected = metadataSize(type);
            if (expected == 0) fail(item + " has an unsupported type '" + type + "'");
            if (size != expected) {
                fail(item + " of type " + type + " has " + std::to_string(size) +
                     " bytes, expected " + std::to_string(expected));
            }
        }
        need(size, item);
        VdbMetadataValue value{type, b_.substr(p_, size), p_};
        p_ += size;
        if (!out.emplace(name, std::move(value)).second) fail(item + " appears twice");
    }
    return out;
}

// io::readCompressedValues with COMPRESS_ACTIVE_MASK: a metadata byte, up to two inactive
// values, an optional selection mask, then the active values (or all, for metadata 6).
void Walker::compressedValues(const Mask& valueMask, int log2, std::size_t valueBytes,
                              const std::string& what) {
    const int meta = get<std::int8_t>(what + " compression byte");
    if (meta < 0 || meta > kNoMaskAndAllValues) {
        fail(what + " has compression byte " + std::to_string(meta) + " (expected 0..6)");
    }
    if (meta == 2 || meta == 4 || meta == 5) skip(valueBytes, what + " inactive value");
    if (meta == 5) skip(valueBytes, what + " second inactive value");
    const std::uint64_t entries = std::uint64_t(1) << (3 * log2);
    if (meta == 3 || meta == 4 || meta == 5) skip(entries / 8, what + " selection mask");
    const std::uint64_t count =
        meta == kNoMaskAndAllValues ? entries : std::uint64_t(popcount(valueMask));
    skip(count * valueBytes, what + " values");
}

// InternalNode::readTopology for a node of 2^log2 children per axis: child and value masks,
// the node's values, then its children's topology; leaves (log2 = 4 children) keep their masks.
void Walker::internalNode(int log2, std::size_t valueBytes, std::vector<Mask>& leafMasks,
                          VdbGridSummary& grid, const std::string& what) {
    const Mask children = mask(log2, what + " child mask");
    const Mask values = mask(log2, what + " value mask");
    if (popcount(values) != 0) fail(what + " has active tiles");
    if (popcount(children) == 0) fail(what + " is empty");
    forEachOn(children, [&](std::uint32_t n) {
        if (maskY(n, log2) != 0) fail(what + " has a child off the plane y = 0");
    });
    compressedValues(values, log2, valueBytes, what);
    readBytes_ += internalNodeBytes(log2, valueBytes);
    forEachOn(children, [&](std::uint32_t) {
        if (log2 == kNode5Log2) {
            internalNode(kNode4Log2, valueBytes, leafMasks, grid, what + " > node");
            return;
        }
        Mask leaf = mask(kLeafLog2, what + " > leaf mask");
        const int on = popcount(leaf);
        if (on == 0) fail(what + " has an empty leaf");
        forEachOn(leaf, [&](std::uint32_t v) {
            if (maskY(v, kLeafLog2) != 0) fail(what + " has a voxel off the plane y = 0");
        });
        grid.activeVoxels += std::uint64_t(on);
        ++grid.leaves;
        readBytes_ += leafBytes(valueBytes);
        leafMasks.push_back(std::move(leaf));
    });
}

void Walker::grid(std::size_t index, VdbFileSummary& summary) {
    VdbGridSummary g;
    GridLayout layout;
    const std::string at = "grid " + std::to_string(index);
    g.name = string(at + " name", kMaxVdbStringBytes);
    const std::string what = "grid '" + g.name + "'";
    g.type = string(what + " type", kMaxTypeNameBytes);
    std::size_t valueBytes = 0;
    for (const GridType& t : kGridTypes) {
        if (g.type == t.name) valueBytes = t.valueBytes;
    }
    if (valueBytes == 0) fail(what + " has an unsupported type '" + g.type + "'");
    if (!string(what + " instance parent", kMaxVdbStringBytes).empty())
        fail(what + " is an instance of another grid");
    layout.offsetsAt = p_;
    const std::int64_t gridPos = get<std::int64_t>(what + " offsets");
    const std::int64_t blockPos = get<std::int64_t>(what + " offsets");
    const std::int64_t endPos = get<std::int64_t>(what + " offsets");
    layout.gridPos = p_;
    if (!sealing_ && gridPos != std::int64_t(p_)) fail(what + " has a wrong grid offset");

    if (get<std::uint32_t>(what + " compression") != kCompressActiveMask)
        fail(what + " uses a compression other than 'active values'");
    const auto meta = metadata(what + " metadata", true, &layout);
    if (auto it = meta.find("name");
        it != meta.end() && (it->second.type != "string" || it->second.bytes != g.name)) {
        fail(what + " has metadata 'name' that differs from its descriptor");
    }
    if (string(what + " transform type", kMaxTypeNameBytes) != "UniformScaleMap")
        fail(what + " has a transform other than a uniform scale");
    std::array<double, 15> map{};
    for (double& v : map) v = get<double>(what + " transform");
    for (double v : map) {
        if (!std::isfinite(v)) fail(what + " has a non-finite transform");
    }
    if (!(map[0] > 0.0) || map[1] != map[0] || map[2] != map[0])
        fail(what + " has a transform scale that is not uniform and positive");
    g.voxelSize_m = map[0];

    // Topology: one buffer, the root's background, no tiles, children in ascending order.
    if (get<std::int32_t>(what + " buffer count") != 1)
        fail(what + " has a buffer count other than 1");
    skip(valueBytes, what + " background");
    if (get<std::uint32_t>(what + " tile count") != 0) fail(what + " has root tiles");
    const std::uint32_t children = get<std::uint32_t>(what + " child count");
    std::vector<Mask> leafMasks;
    std::array<std::int32_t, 3> previous{};
    for (std::uint32_t c = 0; c < children; ++c) {
        std::array<std::int32_t, 3> origin{};
        for (std::int32_t& v : origin) v = get<std::int32_t>(what + " child origin");
        const std::string child = what + " root child " + std::to_string(c);
        if ((origin[0] & (kRootChildSpan - 1)) || origin[1] != 0 ||
            (origin[2] & (kRootChildSpan - 1))) {
            fail(child + " is not aligned on the plane y = 0");
        }
        if (c > 0 &&
            !(origin[0] > previous[0] || (origin[0] == previous[0] && origin[2] > previous[2])))
            fail(child + " is out of order");
        previous = origin;
        readBytes_ += 96;  // the root's table entry
        internalNode(kNode5Log2, valueBytes, leafMasks, g, child);
    }
    layout.blockPos = p_;
    if (!sealing_ && blockPos != std::int64_t(p_)) fail(what + " has a wrong block offset");

    // Buffers: each leaf's mask again (as in the topology) and its values.
    for (std::size_t n = 0; n < leafMasks.size(); ++n) {
        const std::string leaf = what + " leaf " + std::to_string(n);
        if (mask(kLeafLog2, leaf + " mask") != leafMasks[n])
            fail(leaf + " mask differs from the topology's");
        compressedValues(leafMasks[n], kLeafLog2, valueBytes, leaf);
    }
    layout.endPos = p_;
    if (!sealing_ && endPos != std::int64_t(p_)) fail(what + " has a wrong end offset");

    activeVoxels_ += g.activeVoxels;
    if (activeVoxels_ > limits_.maxActiveVoxels) {
        fail("more than " + std::to_string(limits_.maxActiveVoxels) + " active voxels");
    }
    if (readBytes_ > limits_.maxReadBytes) {
        fail("the grids need more than " + std::to_string(limits_.maxReadBytes >> 20) +
             " MB of memory to read");
    }
    summary.grids.push_back(std::move(g));
    layouts.push_back(layout);
}

VdbFileSummary Walker::header() {
    VdbFileSummary summary;
    if (get<std::int64_t>("header") != kVdbMagic) fail("not an OpenVDB file (magic number)");
    const std::uint32_t version = get<std::uint32_t>("header");
    if (version < kMinFileVersion || version > kMaxFileVersion) {
        fail("OpenVDB file format " + std::to_string(version) + " (this build reads " +
             std::to_string(kMinFileVersion) + " to " + std::to_string(kMaxFileVersion) + ")");
    }
    skip(8, "header");  // library version
    const char offsets = get<char>("header");
    if (offsets != (sealing_ ? 0 : 1)) fail("header: unexpected grid-offsets flag");
    skip(36, "header");  // UUID
    summary.metadata = metadata("file metadata", false, nullptr);
    return summary;
}

VdbFileSummary Walker::whole() {
    VdbFileSummary summary = header();
    const std::int32_t count = get<std::int32_t>("grid count");
    if (count < 0 || std::size_t(count) > limits_.maxGrids) {
        fail("grid count " + std::to_string(count) + " (at most " +
             std::to_string(limits_.maxGrids) + ")");
    }
    for (std::int32_t g = 0; g < count; ++g) grid(std::size_t(g), summary);
    if (p_ != b_.size()) fail(std::to_string(b_.size() - p_) + " bytes after the last grid");
    summary.readBytes = readBytes_;
    return summary;
}

std::string hex8(std::uint32_t v) {
    char s[9];
    std::snprintf(s, sizeof s, "%08x", v);
    return s;
}

template <typename T>
void put(std::string& bytes, std::size_t at, T v) {
    std::memcpy(&bytes[at], &v, sizeof(T));
}

const VdbMetadataValue& checksumField(const VdbFileSummary& header, const std::string& where) {
    const auto it = header.metadata.find(kAnchorStoreChecksumKey);
    if (it == header.metadata.end()) {
        throw InputError(where, std::string("metadata '") + kAnchorStoreChecksumKey +
                                    "' is missing: the file is corrupt or was not written by "
                                    "AnchorStore::save");
    }
    if (it->second.type != "string" || it->second.bytes.size() != 8) {
        throw InputError(
            where, std::string("metadata '") + kAnchorStoreChecksumKey + "' is not 8 hex digits");
    }
    return it->second;
}

}  // namespace

VdbFileSummary readVdbHeader(const std::string& bytes, const std::string& where) {
    if (bytes.size() < kHeaderBytes) throw InputError(where, "too short for an OpenVDB file");
    return Walker(bytes, where, {}, false).header();
}

VdbFileSummary checkVdbFile(const std::string& bytes, const std::string& where,
                            const VdbLimits& limits) {
    return Walker(bytes, where, limits, false).whole();
}

std::uint32_t anchorStoreChecksum(const std::string& bytes, std::size_t valueOffset) {
    AMB_CHECK(valueOffset <= bytes.size() && bytes.size() - valueOffset >= 8);
    boost::crc_32_type crc;
    crc.process_bytes(bytes.data(), valueOffset);
    crc.process_bytes("00000000", 8);
    crc.process_bytes(bytes.data() + valueOffset + 8, bytes.size() - valueOffset - 8);
    return crc.checksum();
}

void verifyAnchorStoreChecksum(const std::string& bytes, const VdbFileSummary& header,
                               const std::string& where) {
    const VdbMetadataValue& field = checksumField(header, where);
    const std::string computed = hex8(anchorStoreChecksum(bytes, field.offset));
    if (field.bytes != computed) {
        throw InputError(where, "checksum mismatch (stored " + field.bytes + ", computed " +
                                    computed + "): the file is corrupt or truncated");
    }
}

void refreshAnchorStoreChecksum(std::string& bytes, const std::string& where) {
    const VdbFileSummary header = readVdbHeader(bytes, where);
    const std::size_t offset = checksumField(header, where).offset;
    bytes.replace(offset, 8, hex8(anchorStoreChecksum(bytes, offset)));
}

std::string sealAnchorStoreFile(const std::string& streamBytes, const std::string& where,
                                const VdbLimits& limits) {
    // Walk what the stream writer produced, noting the delayed-load metadata and the grid
    // positions.
    Walker walker(streamBytes, where, limits, true);
    walker.whole();
    std::string out;
    out.reserve(streamBytes.size());
    std::vector<std::pair<std::size_t, std::size_t>> shift;  // old position -> bytes cut before
    std::size_t from = 0, removed = 0;
    for (const auto& [begin, end] : walker.cuts) {
        out.append(streamBytes, from, begin - from);
        removed += end - begin;
        shift.push_back({end, removed});
        from = end;
    }
    out.append(streamBytes, from, std::string::npos);
    const auto moved = [&](std::size_t old) {
        std::size_t before = 0;
        for (const auto& [end, total] : shift) {
            if (end <= old) before = total;
        }
        return old - before;
    };
    // The stored form: grid offsets present and filled in, as io::File writes them.
    out[kHasGridOffsetsAt] = 1;
    for (const GridLayout& g : walker.layouts) {
        if (g.cutEntries > 0) {
            std::uint32_t count;
            std::memcpy(&count, streamBytes.data() + g.metaCountAt, sizeof count);
            put(out, moved(g.metaCountAt), std::uint32_t(count - g.cutEntries));
        }
        const std::size_t at = moved(g.offsetsAt);
        put(out, at, std::int64_t(moved(g.gridPos)));
        put(out, at + 8, std::int64_t(moved(g.blockPos)));
        put(out, at + 16, std::int64_t(moved(g.endPos)));
    }
    refreshAnchorStoreChecksum(out, where);
    // What is written must be what the loader accepts.
    checkVdbFile(out, where, limits);
    return out;
}

}  // namespace amb
