// CubeMapFile.cpp — vertical-strip cube-map files through OpenImageIO (see CubeMapFile.h).
#include "lighting/CubeMapFile.h"

#include <cstddef>
#include <cstdint>

#include <OpenImageIO/imageio.h>

#include "world/Conventions.h"
#include "world/Error.h"

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

CubeMapImage readCubeMap(const std::string& path) {
    limitImageSize();
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
