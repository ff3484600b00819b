// CubeMapFile.h — a cube map as one image file (docs/ARCHITECTURE.md, "Cube maps"; world/Conventions.h).
//
// The file is a single image of width N and height 6N: the six N x N faces stacked vertically in
// the order +X, -X, +Y, -Y, +Z, -Z, face row 0 at the top of each face. Any format OpenImageIO
// reads is accepted (EXR for HDR; 8-bit formats are read as [0, 1]); a one-channel image is read
// as grey, extra channels beyond RGB (alpha) are ignored and never multiplied into the colour.
#pragma once

#include <string>
#include <vector>

namespace amb {

struct CubeMapImage {
    int n = 0;               // face size in texels
    std::vector<float> rgb;  // 6 N^2 texels: face-major, row-major, 3 floats per texel
};

// Largest face a cube-map file may have (2048: 6 x 2048^2 RGB floats, 288 MB) and most channels.
inline constexpr int kMaxCubeMapFace = 2048;
inline constexpr int kMaxCubeMapChannels = 16;

// Reads a vertical-strip cube map. Throws InputError naming the file and the problem (cannot be
// opened or decoded, height != 6 x width, width above kMaxCubeMapFace — refused from the header,
// before anything is allocated —, fewer than 3 channels and not grey, more than
// kMaxCubeMapChannels). Sets OpenImageIO's global "limits:imagesize_MB" to at most what the
// largest cube map needs.
CubeMapImage readCubeMap(const std::string& path);

// Writes `rgb` (layout as CubeMapImage::rgb, AMB_CHECKed size) as a vertical-strip image of
// width n and height 6n; the format follows the extension (EXR: 32-bit float). Throws
// InputError naming the file when it cannot be written.
void writeCubeMap(const std::string& path, int n, const std::vector<float>& rgb);

// Throws InputError naming `where` (an option, "--out") when writeCubeMap could not write `path`
// for its format: OpenImageIO has no writer for the file's extension. Creates no file: a command
// calls it with its other checks, before any work. (Whether the folder exists and is writable is
// the command's own check.)
void checkCubeMapOutput(const std::string& path, const std::string& where);

}  // namespace amb
