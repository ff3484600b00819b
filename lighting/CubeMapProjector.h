// CubeMapProjector.h — project an N x N x 6 RGB cube map to order-2 SH (thesis 7.4, 8.3, 9.2).
//
// Each texel is weighted by its exact solid angle (the atan2 area formula in double), not by the
// thesis' 4 pi / (6 N^2). For N <= kTableMaxFaceSize the per-texel weight x basis products (the
// thesis' nine "basis textures") are precomputed once per N, shared by all projectors, and the
// sum is a float multiply-add (AVX2 + FMA when the CPU has it; for N a multiple of 16 the face's
// mirror symmetry folds it to a quarter) in which no float partial sum holds more than 32
// products before it is flushed into double; larger N stream the weights in double. Faces can be
// added one at a time as a capture spread over six frames delivers them; re-adding a face replaces
// its earlier contribution.
//
// Bad-texel policy: a texel with any channel NaN, +-Inf or negative contributes nothing (it is
// treated as black) and is counted in badTexels(); it never reaches the coefficients.
//
// The sun, as the methods and the oracles leave it out: a face added with the capture's sun
// direction has the texel holding it replaced by its neighbours' sky (lighting/SunTexel.h, the
// same texel the capture put the disc in, at every face size); what that takes away (the disc's
// energy, L omega over the texel) is the directional light sun(), along the given direction.
// Sun extraction by luminance (Options::sunThreshold, off by default; for the ringing study and
// cube maps of unknown origin): texels whose luminance (Rec. 709 weights) exceeds it are left
// out of the SH and summed into sun() instead (irradiance sum L omega, direction the
// luminance-weighted mean), so the sun does not ring (SH.h).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/SH.h"

namespace amb {

// Exact solid angle (steradians) of texel (column i, row j) of an N x N cube face.
double cubeTexelSolidAngle(int i, int j, int n);

// One projector per capture stream; it is not thread-safe itself, the per-N tables it shares are.
class CubeMapProjector {
  public:
    static constexpr int kTableMaxFaceSize = 64;  // tables hold 9 floats per texel

    struct Options {
        // Luminance radiance [W sr^-1 m^-2] above which a texel is taken into the directional
        // sun light; infinity = no extraction. The methods and the oracles do not use it: they
        // pass the capture's sun direction to addFace instead (see above).
        double sunThreshold = std::numeric_limits<double>::infinity();
        // Use the AVX2 + FMA table kernels when the CPU has them (false: the portable loops,
        // e.g. to compare the two).
        bool allowAvx2 = true;
    };

    explicit CubeMapProjector(int faceSize);
    CubeMapProjector(int faceSize, const Options& options);

    int faceSize() const { return n_; }

    // Projects one face: `rgb` holds N x N texels, row-major from row 0, 3 floats per texel.
    // `face` is 0..5 in the order +X, -X, +Y, -Y, +Z, -Z. With `sunDirection` (that of the
    // capture the face comes from, CubeCapture::sunDirection), the sun's texel is left out as
    // above when it lies on this face; `rgb` itself is not changed.
    void addFace(int face, const float* rgb,
                 const std::optional<glm::dvec3>& sunDirection = std::nullopt);
    // Projects a whole map: 6 faces in order, each as in addFace.
    void addCubeMap(const float* rgb, const std::optional<glm::dvec3>& sunDirection = std::nullopt);

    void reset();
    bool complete() const;  // all six faces added
    int facesAdded() const;

    // Sums over the faces added so far.
    ShRgbD coefficients() const;
    DirectionalLight sun() const;
    std::int64_t badTexels() const;

    struct Table;  // per-N basis textures (defined in the .cpp)

  private:
    struct FaceSum {
        std::array<std::array<double, 3>, kShCoefficients> sh{};
        std::array<double, 3> sunIrradiance{};
        std::array<double, 3> sunDirection{};  // sum of luminance x omega x direction
        std::int64_t bad = 0;
        bool present = false;
    };
    void projectTable(int face, const float* rgb, FaceSum& sum);
    void projectStreaming(int face, const float* rgb, FaceSum& sum);
    void takeSunTexel(int face, int i, int j, float r, float g, float b, FaceSum& sum) const;

    int n_;
    Options options_;
    std::shared_ptr<const Table> table_;  // null for N > kTableMaxFaceSize
    std::vector<float> scratch_;          // the face de-interleaved: 3 planes of padded N^2
    std::vector<float> sunFace_;          // a face with its sun texel filled
    std::array<FaceSum, kCubeFaces> faces_;
};

// The result of projecting a whole cube map in one call.
struct CubeMapProjection {
    ShRgbD sh;
    DirectionalLight sun;
    std::int64_t badTexels = 0;
};
// `rgb`: 6 N^2 texels, face-major, row-major, 3 floats per texel (AMB_CHECKed size);
// `sunDirection`: the capture's, whose texel is left out (see above).
CubeMapProjection projectCubeMap(int n, const std::vector<float>& rgb,
                                 const CubeMapProjector::Options& options = {},
                                 const std::optional<glm::dvec3>& sunDirection = std::nullopt);

}  // namespace amb
