// CubeMapFile.h — a cube map as one image file (DESIGN.md, "Cube maps"; world/Conventions.h).
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

// Reads a vertical-strip cube map. Throws InputError naming the file and the problem (cannot be
// opened or decoded, height != 6 x width, fewer than 3 channels and not grey).
CubeMapImage readCubeMap(const std::string& path);

// Writes `rgb` (layout as CubeMapImage::rgb, AMB_CHECKed size) as a vertical-strip image of
// width n and height 6n; the format follows the extension (EXR: 32-bit float). Throws
// InputError naming the file when it cannot be written.
void writeCubeMap(const std::string& path, int n, const std::vector<float>& rgb);

}  // namespace amb
