// CubeMapFile.cpp — vertical-strip cube-map files through OpenImageIO (see CubeMapFile.h).
#include "lighting/CubeMapFile.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <OpenImageIO/imageio.h>
#include <boost/crc.hpp>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

namespace {

// OpenImageIO refuses, before decoding, any image whose uncompressed size exceeds its global
// "limits:imagesize_MB": lowered (never raised) to what the largest cube map needs, so a decoder
// never allocates for a header's absurd size either.
void limitImageSize() {
    const int needed_MB =
        int(std::size_t(kMaxCubeMapFace) * kMaxCubeMapFace * kCubeFaces * 4 * 4 >> 20) + 1;
    int current_MB = 0;
    if (!OIIO::getattribute("limits:imagesize_MB", current_MB) || current_MB <= 0 ||
        current_MB > needed_MB) {
        OIIO::attribute("limits:imagesize_MB", needed_MB);
    }
}

}  // namespace

namespace {

// A PNG file's chunk structure, checked before OpenImageIO reads it: libpng reports a file that
// ends inside a chunk by a long jump out of OpenImageIO's read callback, which leaks the error
// string on the way, and a corrupt chunk is better named here. Every chunk must lie inside the
// file and carry its CRC-32, up to IEND. Files without the PNG signature are left alone (their
// own decoders check them).
// The largest PNG cube map read: 2048 x 12288 RGBA, 16 bits, stored [bytes].
constexpr std::size_t kMaxPngFileBytes = std::size_t(kMaxCubeMapFace) * kMaxCubeMapFace *
                                         kCubeFaces * 8 + (std::size_t(1) << 20);

// A chunk type for a message: its letters, other bytes as '?'.
std::string printable(std::string type) {
    for (char& c : type)
        if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'))) c = '?';
    return type;
}

void checkPngChunks(const std::string& path) {
    static const char kSignature[8] = {'\x89', 'P', 'N', 'G', '\r', '\n', '\x1a', '\n'};
    {
        std::ifstream head(path, std::ios::binary);
        char first[8] = {};
        if (!head.read(first, 8) || std::memcmp(first, kSignature, 8) != 0) return;
    }
    const std::string bytes = readTextFile(path, "PNG cube map", kMaxPngFileBytes);
    auto be32 = [&](std::size_t at) {
        return std::uint32_t(std::uint8_t(bytes[at])) << 24 |
               std::uint32_t(std::uint8_t(bytes[at + 1])) << 16 |
               std::uint32_t(std::uint8_t(bytes[at + 2])) << 8 | std::uint32_t(std::uint8_t(bytes[at + 3]));
    };
    std::size_t at = 8;
    while (true) {
        if (bytes.size() - at < 8) {
            throw InputError(path, "PNG file ends at byte " + std::to_string(bytes.size()) +
                                       " without its IEND chunk (truncated)");
        }
        const std::uint32_t length = be32(at);
        const std::string type = bytes.substr(at + 4, 4);
        if (length > 0x7FFFFFFFu || bytes.size() - at - 8 < std::size_t(length) + 4) {
            throw InputError(path, "PNG chunk '" + printable(type) + "' at byte " + std::to_string(at) +
                                       " runs past the end of the file (truncated)");
        }
        boost::crc_32_type crc;
        crc.process_bytes(bytes.data() + at + 4, 4 + std::size_t(length));
        if (crc.checksum() != be32(at + 8 + length)) {
            throw InputError(path, "PNG chunk '" + printable(type) + "' at byte " + std::to_string(at) +
                                       " fails its CRC (corrupt)");
        }
        if (type == "IEND") return;
        at += 12 + std::size_t(length);
    }
}

}  // namespace

CubeMapImage readCubeMap(const std::string& path) {
    limitImageSize();
    checkPngChunks(path);
    // Colour is radiance: keep it as stored, never multiplied by an alpha channel.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) throw InputError(path, "cannot read the cube map: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.depth > 1) throw InputError(path, "a cube map must be a 2-D image, not a volume");
    // The header's size decides the allocation below: checked against the limit first.
    if (spec.width < 1 || spec.width > kMaxCubeMapFace ||
        std::int64_t(spec.height) != std::int64_t(kCubeFaces) * spec.width) {
        throw InputError(path,
                         "a cube map must be N wide and 6N high (faces stacked vertically, "
                         "N from 1 to " +
                             std::to_string(kMaxCubeMapFace) + "), got " +
                             std::to_string(spec.width) + " x " + std::to_string(spec.height));
    }
    if ((spec.nchannels != 1 && spec.nchannels < 3) || spec.nchannels > kMaxCubeMapChannels) {
        throw InputError(path, "a cube map needs 3 channels (RGB) or 1 (grey), got " +
                                   std::to_string(spec.nchannels));
    }
    CubeMapImage image;
    image.n = spec.width;
    const std::size_t texels = std::size_t(spec.width) * spec.height;
    image.rgb.resize(3 * texels);
    const int channels = spec.nchannels == 1 ? 1 : 3;
    std::vector<float> grey;
    void* target = image.rgb.data();
    if (channels == 1) {
        grey.resize(texels);
        target = grey.data();
    }
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, target)) {
        throw InputError(path, "cannot decode the cube map: " + in->geterror());
    }
    for (std::size_t t = 0; t < grey.size(); ++t) {
        image.rgb[3 * t] = image.rgb[3 * t + 1] = image.rgb[3 * t + 2] = grey[t];
    }
    return image;
}

void checkCubeMapOutput(const std::string& path, const std::string& where) {
    // The writer writeCubeMap asks for, created and dropped: nothing is opened or written.
    if (OIIO::ImageOutput::create(path)) return;
    (void)OIIO::geterror();  // the reason is the one below; keep OpenImageIO's queue empty
    const std::string ext = std::filesystem::path(path).extension().string();
    throw InputError(where, "cannot write a cube map to '" + path + "': " +
                                (ext.empty() ? std::string("no file extension")
                                             : "no image format writes '" + ext + "' files") +
                                " (.exr for HDR)");
}

void writeCubeMap(const std::string& path, int n, const std::vector<float>& rgb) {
    AMB_CHECK(n >= 1 && rgb.size() == std::size_t(kCubeFaces) * n * n * 3);
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw InputError(path, "cannot write the cube map: " + OIIO::geterror());
    const OIIO::ImageSpec spec(n, kCubeFaces * n, 3, OIIO::TypeDesc::FLOAT);
    if (!out->open(path, spec)) {
        throw InputError(path, "cannot write the cube map: " + out->geterror());
    }
    if (!out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()) || !out->close()) {
        throw InputError(path, "cannot write the cube map: " + out->geterror());
    }
}

}  // namespace amb
