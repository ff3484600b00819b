// AnchorStoreVdb.cpp — the anchor store's OpenVDB side (AnchorStore.h, AnchorStoreImpl.h): the
// per-level index grids and the .vdb files. The one file of the store that includes OpenVDB.
//
// [SECTION] Storage       one int32 grid per level, (i, 0, k) -> pool slot
// [SECTION] Files (.vdb)
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/ValueAccessor.h>

#include "lighting/AnchorStoreFile.h"
#include "lighting/AnchorStoreImpl.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

namespace {

constexpr const char* kFormat = "ambience-anchor-store-v2";

// In memory, the per-level index grids use smaller nodes than the standard Int32Grid
// (internal nodes 16^3 and 8^3 instead of 32^3 and 16^3, leaves 4^3 instead of 8^3): the
// standard tree's first internal node alone holds a 32^3 child table (~260 kB), which would
// dominate the memory of a store of a few thousand anchors on a plane. Files hold standard
// Int32Grids (save/load convert), so standard OpenVDB tools read them.
using IndexTree = openvdb::tree::Tree4<std::int32_t, 4, 3, 2>::Type;
using IndexGrid = openvdb::Grid<IndexTree>;

}  // namespace

// ---- Storage ------------------------------------------------------------------------------------

struct AnchorIndexLevel {
    IndexGrid::Ptr grid;
};

AnchorStore::Impl::Impl(const AnchorStoreSettings& s) : settings(s) {
    openvdb::initialize();
    AMB_CHECK(s.levels >= 1 && s.levels <= kMaxAnchorLevels);
    AMB_CHECK(std::isfinite(s.coarsestSpacing_m) && s.coarsestSpacing_m > 0.0);
    AMB_CHECK(s.searchCells >= 1 && s.reachCells >= 1 && s.coarseReachCells >= 1);
    AMB_CHECK(s.finerWeight >= 0.0 && s.finerWeight <= 1.0);
    levels = s.levels;
    std::int64_t sc = 1;
    for (int L = levels - 1; L >= 0; --L) {
        scale[L] = sc;
        sc *= 3;
    }
    for (int L = 0; L < levels; ++L)
        spacing[L] = s.coarsestSpacing_m / double(scale[0] / scale[L]);
    fineSpacing = spacing[levels - 1];
    for (int L = 0; L < levels; ++L) {
        auto grid = IndexGrid::create(kNoAnchor);
        grid->setName("anchor_index_L" + std::to_string(L));
        grid->setTransform(openvdb::math::Transform::createLinearTransform(spacing[L]));
        grid->setGridClass(openvdb::GRID_UNKNOWN);
        grids.push_back({grid});
    }
}

AnchorStore::Impl::~Impl() = default;

std::int32_t AnchorStore::Impl::indexOf(const LatticeKey& canonicalKey) const {
    return grids[canonicalKey.level].grid->tree().getValue(
        openvdb::Coord(canonicalKey.i, 0, canonicalKey.k));
}
void AnchorStore::Impl::setIndex(const LatticeKey& canonicalKey, std::int32_t slot) {
    grids[canonicalKey.level].grid->tree().setValueOn(
        openvdb::Coord(canonicalKey.i, 0, canonicalKey.k), slot);
}
void AnchorStore::Impl::unsetIndex(const LatticeKey& canonicalKey) {
    grids[canonicalKey.level].grid->tree().setValueOff(
        openvdb::Coord(canonicalKey.i, 0, canonicalKey.k), kNoAnchor);
}
void AnchorStore::Impl::pruneIndex(int level) {
    openvdb::tools::pruneInactive(grids[level].grid->tree());
}
void AnchorStore::Impl::clearIndex() {
    for (auto& level : grids) level.grid->clear();
}
std::size_t AnchorStore::Impl::indexBytes() const {
    std::size_t bytes = 0;
    for (const auto& level : grids) bytes += std::size_t(level.grid->memUsage());
    return bytes;
}

AnchorStore::AnchorStore(const AnchorStoreSettings& settings)
    : impl_(std::make_unique<Impl>(settings)) {}
AnchorStore::~AnchorStore() = default;
AnchorStore::AnchorStore(AnchorStore&&) noexcept = default;
AnchorStore& AnchorStore::operator=(AnchorStore&&) noexcept = default;

// ---- Files --------------------------------------------------------------------------------------

namespace {

enum AnchorFlags : int { kFlagRegenerate = 1, kFlagExpired = 2 };

std::string shGridName(const char* what, int k) {
    return std::string(what) + "_" + std::to_string(k);
}

// The grids as OpenVDB's stream writer lays them out, with mask compression only (no Blosc or
// zlib blocks, whose declared sizes the loader would have to trust), sealed with the checksum
// (AnchorStoreFile.h) and written next to `path` first, so a failed save leaves the old file.
void writeStoreFile(const std::string& path, const openvdb::GridPtrVec& grids,
                    const openvdb::MetaMap& meta) {
    std::string bytes;
    try {
        std::ostringstream os(std::ios::binary);
        openvdb::io::Stream stream(os);
        stream.setCompression(openvdb::io::COMPRESS_ACTIVE_MASK);
        stream.write(grids, meta);
        bytes = sealAnchorStoreFile(os.str(), "anchor store");
    } catch (const std::exception& e) {
        throw InputError(path, std::string("cannot write anchor store: ") + e.what());
    }
    if (bytes.size() > kMaxAnchorStoreFileBytes) {
        throw InputError(path, "cannot write anchor store: " + std::to_string(bytes.size()) +
                                   " bytes, more than a store file may hold");
    }
    const std::string part = path + ".part";
    {
        std::ofstream out(part, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.close();
        if (!out) {
            std::remove(part.c_str());
            throw InputError(path, "cannot write anchor store");
        }
    }
    if (std::rename(part.c_str(), path.c_str()) != 0) {
        std::remove(part.c_str());
        throw InputError(path, "cannot write anchor store");
    }
}

template <typename GridT>
typename GridT::Ptr makePayloadGrid(const std::string& name, double fineSpacing,
                                    const typename GridT::ValueType& background) {
    auto grid = GridT::create(background);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(fineSpacing));
    return grid;
}

}  // namespace

void AnchorStore::save(const std::string& path) const {
    const Impl& m = *impl_;
    openvdb::GridPtrVec grids;
    for (const auto& level : m.grids) {
        const auto& g = level.grid;
        // Anchor numbers in the file are 0..n-1 in pool order (pool slots are not kept).
        auto copy = openvdb::Int32Grid::create(kNoAnchor);
        copy->setName(g->getName());
        copy->setTransform(g->transform().copy());
        grids.push_back(copy);
    }
    std::array<openvdb::Vec3SGrid::Ptr, kShCoefficients> current, target, from;
    for (int k = 0; k < kShCoefficients; ++k) {
        current[k] = makePayloadGrid<openvdb::Vec3SGrid>(shGridName("sh_current", k), m.fineSpacing,
                                                         openvdb::Vec3s(0.0f));
        target[k] = makePayloadGrid<openvdb::Vec3SGrid>(shGridName("sh_target", k), m.fineSpacing,
                                                        openvdb::Vec3s(0.0f));
        from[k] = makePayloadGrid<openvdb::Vec3SGrid>(shGridName("sh_blend_from", k), m.fineSpacing,
                                                      openvdb::Vec3s(0.0f));
        grids.push_back(current[k]);
        grids.push_back(target[k]);
        grids.push_back(from[k]);
    }
    auto position = makePayloadGrid<openvdb::Vec3DGrid>("captured_position", m.fineSpacing,
                                                        openvdb::Vec3d(0.0));
    auto age = makePayloadGrid<openvdb::FloatGrid>("age_s", m.fineSpacing, 0.0f);
    auto lifetime = makePayloadGrid<openvdb::FloatGrid>("lifetime_s", m.fineSpacing, 0.0f);
    auto blendElapsed = makePayloadGrid<openvdb::FloatGrid>("blend_elapsed_s", m.fineSpacing, 0.0f);
    auto presence = makePayloadGrid<openvdb::FloatGrid>("presence", m.fineSpacing, 0.0f);
    auto sinceBirth = makePayloadGrid<openvdb::FloatGrid>("since_birth_s", m.fineSpacing, 0.0f);
    auto tod = makePayloadGrid<openvdb::FloatGrid>("capture_time_of_day_h", m.fineSpacing, 0.0f);
    auto flags = makePayloadGrid<openvdb::Int32Grid>("flags", m.fineSpacing, 0);
    grids.push_back(position);
    for (auto& g : {age, lifetime, blendElapsed, presence, sinceBirth, tod}) grids.push_back(g);
    grids.push_back(flags);

    std::int32_t number = 0;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (!m.alive[n]) continue;
        const Anchor& a = m.pool[n];
        const auto levelGrid = openvdb::GridBase::grid<openvdb::Int32Grid>(grids[a.key.level]);
        levelGrid->tree().setValueOn(openvdb::Coord(a.key.i, 0, a.key.k), number++);
        const openvdb::Coord fine(std::int32_t(fineI(a.key)), 0, std::int32_t(fineK(a.key)));
        for (int k = 0; k < kShCoefficients; ++k) {
            current[k]->tree().setValueOn(
                fine, openvdb::Vec3s(a.current.c[k].x, a.current.c[k].y, a.current.c[k].z));
            target[k]->tree().setValueOn(
                fine, openvdb::Vec3s(a.target.c[k].x, a.target.c[k].y, a.target.c[k].z));
            from[k]->tree().setValueOn(
                fine, openvdb::Vec3s(a.blendFrom.c[k].x, a.blendFrom.c[k].y, a.blendFrom.c[k].z));
        }
        position->tree().setValueOn(
            fine,
            openvdb::Vec3d(a.capturedPosition_m.x, a.capturedPosition_m.y, a.capturedPosition_m.z));
        age->tree().setValueOn(fine, float(a.age_s(m.now)));
        lifetime->tree().setValueOn(fine, float(a.lifetime_s));
        blendElapsed->tree().setValueOn(
            fine, float(a.blendProgress >= 1.0f ? m.settings.blendTime_s : m.now - a.blendStart_s));
        presence->tree().setValueOn(fine, a.presence);
        sinceBirth->tree().setValueOn(fine, float(m.now - a.birth_s));
        tod->tree().setValueOn(fine, float(a.captureTimeOfDay_h));
        flags->tree().setValueOn(
            fine, (a.regenerationRequested ? kFlagRegenerate : 0) | (a.expired ? kFlagExpired : 0));
    }

    openvdb::MetaMap meta;
    meta.insertMeta("format", openvdb::StringMetadata(kFormat));
    meta.insertMeta("coarsest_spacing_m", openvdb::DoubleMetadata(m.settings.coarsestSpacing_m));
    meta.insertMeta("levels", openvdb::Int32Metadata(m.levels));
    meta.insertMeta("anchors", openvdb::Int32Metadata(number));
    meta.insertMeta("clock_s", openvdb::DoubleMetadata(m.now));
    meta.insertMeta(kAnchorStoreChecksumKey, openvdb::StringMetadata("00000000"));
    writeStoreFile(path, grids, meta);
}

namespace {

std::string coordString(const openvdb::Coord& c) {
    return "(" + std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " +
           std::to_string(c.z()) + ")";
}

template <typename GridT>
typename GridT::Ptr requireGrid(const openvdb::GridPtrVec& grids, const std::string& name,
                                const std::string& path) {
    for (const auto& g : grids) {
        if (g && g->getName() == name) {
            auto typed = openvdb::gridPtrCast<GridT>(g);
            if (!typed) {
                throw InputError(path, "grid '" + name + "' has type " + g->type() + ", expected " +
                                           GridT::gridType());
            }
            return typed;
        }
    }
    throw InputError(path, "grid '" + name + "' is missing");
}

template <typename GridT>
typename GridT::ValueType requireVoxel(const GridT& grid, const openvdb::Coord& c,
                                       const std::string& path) {
    typename GridT::ValueType v;
    if (!grid.tree().probeValue(c, v)) {
        throw InputError(path,
                         "grid '" + grid.getName() + "' has no value at voxel " + coordString(c));
    }
    return v;
}

// A file-level metadata value of the checked bytes (the walk checked its size).
template <typename T>
T metaValue(const VdbFileSummary& file, const char* name, const char* type,
            const std::string& path) {
    const auto it = file.metadata.find(name);
    if (it == file.metadata.end() || it->second.type != type) {
        throw InputError(path, std::string("metadata '") + name + "' is missing or not " + type);
    }
    T v;
    std::memcpy(&v, it->second.bytes.data(), sizeof(T));
    return v;
}

struct StoreFileHeader {
    std::int32_t anchors = 0;
};

// Everything that can be known before OpenVDB parses the bytes: the checksum (corruption and
// truncation stop here), the stream structure (AnchorStoreFile.h), the lattice and the anchor
// count, and the grids — each expected one present once with its type and voxel size, nothing
// else, the level grids holding `anchors` voxels together and every payload grid one per anchor.
StoreFileHeader checkStoreFile(const std::string& bytes, const std::string& path, double s0,
                               const std::vector<double>& spacing) {
    const VdbFileSummary header = readVdbHeader(bytes, path);
    const auto format = header.metadata.find("format");
    if (format == header.metadata.end() || format->second.type != "string" ||
        format->second.bytes != kFormat) {
        const std::string found =
            format == header.metadata.end() ? "missing" : "'" + format->second.bytes + "'";
        throw InputError(path, std::string("not an anchor store of format ") + kFormat +
                                   " (metadata 'format' is " + found + ")");
    }
    verifyAnchorStoreChecksum(bytes, header, path);
    const VdbFileSummary file = checkVdbFile(bytes, path);

    StoreFileHeader h;
    const double fileS0 = metaValue<double>(file, "coarsest_spacing_m", "double", path);
    const std::int32_t levels = metaValue<std::int32_t>(file, "levels", "int32", path);
    h.anchors = metaValue<std::int32_t>(file, "anchors", "int32", path);
    const double clock = metaValue<double>(file, "clock_s", "double", path);
    if (fileS0 != s0 || levels != std::int32_t(spacing.size())) {
        throw InputError(path, "lattice (s0 " + std::to_string(fileS0) + " m, " +
                                   std::to_string(levels) + " levels) differs from this store's");
    }
    if (!std::isfinite(clock)) throw InputError(path, "metadata 'clock_s' is not finite");
    if (h.anchors < 0) throw InputError(path, "metadata 'anchors' is negative");

    struct Expected {
        std::string name, type;
        double voxel_m;
    };
    std::vector<Expected> expected;
    for (std::size_t L = 0; L < spacing.size(); ++L)
        expected.push_back({"anchor_index_L" + std::to_string(L), "Tree_int32_5_4_3", spacing[L]});
    const std::size_t payloadFrom = expected.size();
    const double fine = spacing.back();
    for (const char* sh : {"sh_current", "sh_target", "sh_blend_from"}) {
        for (int k = 0; k < kShCoefficients; ++k)
            expected.push_back({shGridName(sh, k), "Tree_vec3s_5_4_3", fine});
    }
    expected.push_back({"captured_position", "Tree_vec3d_5_4_3", fine});
    for (const char* f : {"age_s", "lifetime_s", "blend_elapsed_s", "presence", "since_birth_s",
                          "capture_time_of_day_h"})
        expected.push_back({f, "Tree_float_5_4_3", fine});
    expected.push_back({"flags", "Tree_int32_5_4_3", fine});

    if (file.grids.size() != expected.size()) {
        throw InputError(path, std::to_string(file.grids.size()) + " grids, expected " +
                                   std::to_string(expected.size()));
    }
    std::uint64_t levelVoxels = 0;
    for (std::size_t e = 0; e < expected.size(); ++e) {
        const Expected& x = expected[e];
        const auto g = std::find_if(file.grids.begin(), file.grids.end(),
                                    [&](const VdbGridSummary& s) { return s.name == x.name; });
        if (g == file.grids.end()) throw InputError(path, "grid '" + x.name + "' is missing");
        if (g->type != x.type) {
            throw InputError(path,
                             "grid '" + x.name + "' has type " + g->type + ", expected " + x.type);
        }
        if (g->voxelSize_m != x.voxel_m) {
            throw InputError(path, "grid '" + x.name + "' has voxel size " +
                                       std::to_string(g->voxelSize_m) + " m, expected " +
                                       std::to_string(x.voxel_m));
        }
        if (e < payloadFrom) {
            levelVoxels += g->activeVoxels;
        } else if (g->activeVoxels != std::uint64_t(h.anchors)) {
            throw InputError(path, "grid '" + x.name + "' holds " +
                                       std::to_string(g->activeVoxels) + " values for " +
                                       std::to_string(h.anchors) + " anchors");
        }
    }
    if (levelVoxels != std::uint64_t(h.anchors)) {
        throw InputError(path, "metadata 'anchors' is " + std::to_string(h.anchors) +
                                   " but the level grids hold " + std::to_string(levelVoxels));
    }
    return h;
}

// OpenVDB parses the checked bytes from memory, all at once (no delayed loading, so nothing is
// read after load() returns); a read past the end throws instead of yielding zeros.
openvdb::GridPtrVecPtr parseStoreGrids(const std::string& bytes, const std::string& path) {
    try {
        std::istringstream is(bytes, std::ios::binary);
        is.exceptions(std::ios::failbit | std::ios::badbit | std::ios::eofbit);
        openvdb::io::Stream stream(is, /*delayLoad=*/false);
        openvdb::GridPtrVecPtr grids = stream.getGrids();
        if (!grids) throw InputError(path, "no grids");
        return grids;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path, std::string("cannot read anchor store: ") + e.what());
    }
}

// The payload grids (AnchorStore::save), found by name and type.
struct PayloadGrids {
    std::array<openvdb::Vec3SGrid::Ptr, kShCoefficients> current, target, from;
    openvdb::Vec3DGrid::Ptr position;
    openvdb::FloatGrid::Ptr age, lifetime, blendElapsed, presence, sinceBirth, tod;
    openvdb::Int32Grid::Ptr flags;

    PayloadGrids(const openvdb::GridPtrVec& grids, const std::string& path) {
        for (int k = 0; k < kShCoefficients; ++k) {
            current[k] = requireGrid<openvdb::Vec3SGrid>(grids, shGridName("sh_current", k), path);
            target[k] = requireGrid<openvdb::Vec3SGrid>(grids, shGridName("sh_target", k), path);
            from[k] = requireGrid<openvdb::Vec3SGrid>(grids, shGridName("sh_blend_from", k), path);
        }
        position = requireGrid<openvdb::Vec3DGrid>(grids, "captured_position", path);
        age = requireGrid<openvdb::FloatGrid>(grids, "age_s", path);
        lifetime = requireGrid<openvdb::FloatGrid>(grids, "lifetime_s", path);
        blendElapsed = requireGrid<openvdb::FloatGrid>(grids, "blend_elapsed_s", path);
        presence = requireGrid<openvdb::FloatGrid>(grids, "presence", path);
        sinceBirth = requireGrid<openvdb::FloatGrid>(grids, "since_birth_s", path);
        tod = requireGrid<openvdb::FloatGrid>(grids, "capture_time_of_day_h", path);
        flags = requireGrid<openvdb::Int32Grid>(grids, "flags", path);
    }
};

// The anchor stored at fine voxel `fine`, its times relative to the clock `now`; every value
// checked (finite coefficients within AnchorStore::kMaxCoefficient, finite position, positive
// lifetime, non-negative ages, presence in [0, 1], known flags).
Anchor readAnchor(const PayloadGrids& g, const openvdb::Coord& fine, double now, double blendTime_s,
                  const std::string& where, const std::string& path) {
    Anchor a;
    for (int k = 0; k < kShCoefficients; ++k) {
        const auto cv = requireVoxel(*g.current[k], fine, path);
        const auto tv = requireVoxel(*g.target[k], fine, path);
        const auto fv = requireVoxel(*g.from[k], fine, path);
        a.current.c[k] = {cv.x(), cv.y(), cv.z()};
        a.target.c[k] = {tv.x(), tv.y(), tv.z()};
        a.blendFrom.c[k] = {fv.x(), fv.y(), fv.z()};
    }
    if (!finiteSh(a.current, AnchorStore::kMaxCoefficient) ||
        !finiteSh(a.target, AnchorStore::kMaxCoefficient) ||
        !finiteSh(a.blendFrom, AnchorStore::kMaxCoefficient)) {
        throw InputError(path, where + ": coefficients not finite or out of range");
    }
    const auto p = requireVoxel(*g.position, fine, path);
    a.capturedPosition_m = {p.x(), p.y(), p.z()};
    const double ageV = requireVoxel(*g.age, fine, path);
    const double lifeV = requireVoxel(*g.lifetime, fine, path);
    const double blendV = requireVoxel(*g.blendElapsed, fine, path);
    const double presV = requireVoxel(*g.presence, fine, path);
    const double birthV = requireVoxel(*g.sinceBirth, fine, path);
    const double todV = requireVoxel(*g.tod, fine, path);
    const int flagV = requireVoxel(*g.flags, fine, path);
    const auto finiteNonNegative = [](double v) { return std::isfinite(v) && v >= 0.0; };
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()) ||
        !finiteNonNegative(ageV) || !std::isfinite(lifeV) || !(lifeV > 0.0) ||
        !finiteNonNegative(blendV) || !(presV >= 0.0 && presV <= 1.0) ||
        !finiteNonNegative(birthV) || !std::isfinite(todV) ||
        (flagV & ~(kFlagRegenerate | kFlagExpired)) != 0) {
        throw InputError(path, where + ": anchor state out of range");
    }
    a.captureTime_s = now - ageV;
    a.birth_s = now - birthV;
    a.lifetime_s = lifeV;
    a.captureTimeOfDay_h = todV;
    a.blendStart_s = now - blendV;
    a.blendProgress = float(blendTime_s > 0.0 ? clamp01(blendV / blendTime_s) : 1.0);
    a.presence = float(presV);
    a.presenceFrom = a.presence;
    a.presenceChange_s = now;
    a.regenerationRequested = (flagV & kFlagRegenerate) != 0;
    a.expired = (flagV & kFlagExpired) != 0;
    return a;
}

}  // namespace

void AnchorStore::load(const std::string& path) {
    // The whole file, bounded, checked byte by byte before OpenVDB sees it (AnchorStoreFile.h).
    const std::string bytes = readTextFile(path, "anchor store file", kMaxAnchorStoreFileBytes);
    const std::vector<double> spacing(impl_->spacing.begin(),
                                      impl_->spacing.begin() + impl_->levels);
    const StoreFileHeader header =
        checkStoreFile(bytes, path, impl_->settings.coarsestSpacing_m, spacing);
    const std::int32_t anchors = header.anchors;
    const openvdb::GridPtrVecPtr grids = parseStoreGrids(bytes, path);

    auto fresh = std::make_unique<Impl>(impl_->settings);
    Impl& m = *fresh;
    m.now = impl_->now;
    m.fallback = impl_->fallback;
    m.counters = impl_->counters;
    const PayloadGrids payload(*grids, path);

    std::vector<std::uint8_t> numberSeen(std::size_t(anchors), 0);
    for (int L = 0; L < m.levels; ++L) {
        const auto levelGrid =
            requireGrid<openvdb::Int32Grid>(*grids, "anchor_index_L" + std::to_string(L), path);
        for (auto it = levelGrid->cbeginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            const std::int32_t number = *it;
            const std::string where = "grid '" + levelGrid->getName() + "' voxel " + coordString(c);
            if (c.y() != 0) throw InputError(path, where + ": y must be 0");
            const LatticeKey key{L, c.x(), c.z()};
            if (!m.validKey(key) || m.canonical(key) != key) {
                throw InputError(path, where + ": not a canonical level-" + std::to_string(L) +
                                           " lattice point");
            }
            if (number < 0 || number >= anchors || numberSeen[std::size_t(number)]) {
                throw InputError(path, where + ": anchor number out of range or repeated");
            }
            numberSeen[std::size_t(number)] = 1;
            const openvdb::Coord fine(std::int32_t(std::int64_t(key.i) * m.scale[L]), 0,
                                      std::int32_t(std::int64_t(key.k) * m.scale[L]));
            Anchor a = readAnchor(payload, fine, m.now, m.settings.blendTime_s, where, path);
            a.key = key;
            const std::int32_t slot = m.allocate(a);
            m.setIndex(key, slot);
        }
    }
    if (m.count != std::size_t(anchors)) {
        throw InputError(path, "metadata 'anchors' is " + std::to_string(anchors) +
                                   " but the level grids hold " + std::to_string(m.count));
    }
    impl_ = std::move(fresh);
}

}  // namespace amb
