// AnchorStoreFile.h — the bytes of anchor-store files (AnchorStore.h "Files"), checked before
// OpenVDB parses them.
//
// OpenVDB's reader trusts its input: a string length, a metadata size, a node count or a
// compressed block size read from the stream is allocated or looped over before anything checks
// it against the file, a truncated stream is read on as if it were zeros, and a failed library
// assertion ends the process. So AnchorStore::load reads the whole file (at most
// kMaxAnchorStoreFileBytes), verifies its CRC-32, then walks the OpenVDB stream here — every
// string, metadata value, grid descriptor, transform, node, mask and value block, each size
// checked against the bytes that remain — and accepts only the subset the saver writes:
//   - OpenVDB file format 222 to 224 with grid offsets (as io::File writes), offsets consistent,
//     nothing after the last grid;
//   - metadata of the types string (at most kMaxVdbStringBytes), bool, int32, int64, float,
//     double, vec3i, vec3s and vec3d, each of its exact size (no delayed-load metadata);
//   - grids of the standard types Int32, Float, Vec3S and Vec3D (trees 5-4-3), full precision,
//     not instanced, compressed with "active values" only (no Blosc or zlib blocks), with a
//     UniformScaleMap transform of positive finite scale;
//   - trees without tiles, no empty node, active voxels only in the plane y = 0, root children
//     in ascending order (the order OpenVDB keeps them in, so topology and buffers match).
// Only then are the same bytes handed to OpenVDB, from memory. The memory OpenVDB will take to
// hold the grids is estimated from the nodes and bounded too.
//
// No OpenVDB header here: the few format constants are restated.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace amb {

constexpr std::size_t kMaxAnchorStoreFileBytes = std::size_t(256) << 20;
constexpr std::size_t kMaxVdbStringBytes = 4096;
// File-level metadata holding the checksum: 8 lower-case hex digits, the CRC-32 (ISO-HDLC, as
// zlib and PNG) of the whole file with these 8 digits written as '0'.
constexpr const char* kAnchorStoreChecksumKey = "checksum_crc32";

struct VdbLimits {
    std::size_t maxGrids = 64;
    std::uint64_t maxActiveVoxels = std::uint64_t(1) << 24;  // over all grids
    std::uint64_t maxReadBytes = std::uint64_t(2) << 30;     // OpenVDB's memory for the grids
};

struct VdbMetadataValue {
    std::string type;        // OpenVDB metadata type name ("string", "int32", ...)
    std::string bytes;       // the value as stored (little-endian, strings without length)
    std::size_t offset = 0;  // where the value starts in the file
};

struct VdbGridSummary {
    std::string name;  // descriptor name
    std::string type;  // "Tree_int32_5_4_3", ...
    double voxelSize_m = 0.0;
    std::uint64_t activeVoxels = 0;
    std::uint64_t leaves = 0;
};

struct VdbFileSummary {
    std::map<std::string, VdbMetadataValue> metadata;  // file-level metadata
    std::vector<VdbGridSummary> grids;                 // empty from readVdbHeader
    std::uint64_t readBytes = 0;  // estimated memory OpenVDB needs to hold every grid
};

// The header and the file-level metadata only. Throws InputError(where, ...) naming the problem
// and the byte offset.
VdbFileSummary readVdbHeader(const std::string& bytes, const std::string& where);

// The whole file, as described at the top. Throws InputError(where, ...).
VdbFileSummary checkVdbFile(const std::string& bytes, const std::string& where,
                            const VdbLimits& limits = {});

// CRC-32 of `bytes` with the checksum value (8 bytes at `valueOffset`) taken as "00000000".
std::uint32_t anchorStoreChecksum(const std::string& bytes, std::size_t valueOffset);

// Throws InputError(where, ...) unless the file-level metadata holds kAnchorStoreChecksumKey
// and it matches the bytes (a corrupt or truncated file).
void verifyAnchorStoreChecksum(const std::string& bytes, const VdbFileSummary& header,
                               const std::string& where);

// Turns what openvdb::io::Stream wrote (compression "active values", file-level metadata with
// kAnchorStoreChecksumKey = "00000000") into the stored file: the delayed-load metadata OpenVDB
// adds to each grid is dropped (its mask is Blosc-compressed, which the loader does not accept),
// the grid offsets are recorded as io::File records them, and the checksum is filled in. The
// result passes checkVdbFile with `limits`, or InputError(where, ...) is thrown.
std::string sealAnchorStoreFile(const std::string& streamBytes, const std::string& where,
                                const VdbLimits& limits = {});

// Recomputes the checksum of `bytes` in place (for tests and repair tools that edited a file
// byte by byte). Throws InputError(where, ...) when the header or metadata cannot be read.
void refreshAnchorStoreChecksum(std::string& bytes, const std::string& where);

}  // namespace amb
