// Heightfield.h — the endless natural terrain h(x, z) before roads: fBm plus ridged noise with
// domain warping, evaluated at any double-precision (x, z); normals; moisture. In ravine
// country (a slow mask over about a tenth of the land) erosion gullies up to 8 m deep and
// about 15 m wide cut into it; roads are routed and graded over the broad terrain
// without them, as a road builder bridges or fills a gully.
//
// Precision: every noise octave is GLM's classic Perlin noise (glm/gtc/noise.hpp), which is
// periodic with a period of exactly 289 lattice units. Each octave maps (x, z) to its lattice
// coordinates in double (rotation, frequency, seed offset), reduces them exactly into [0, 289)
// and only then evaluates the noise, in double. The reduction is exact (an integer multiple of
// 289 is subtracted from a double of the same magnitude), so the terrain 10^6 m from the origin
// is computed with the same relative precision as at the origin: no float ever sees a large
// coordinate.
#pragma once

#include <array>
#include <cstdint>

#include <glm/vec3.hpp>

#include "world/WorldSettings.h"

namespace amb {

class Heightfield {
  public:
    explicit Heightfield(const WorldSettings& settings);

    double height(double x_m, double z_m) const;      // metres above the datum
    // The terrain without its gullies (what roads are routed and graded over).
    double broadHeight(double x_m, double z_m) const;
    // How far the gullies cut below the broad terrain at (x, z), >= 0; 0 outside ravine country.
    double gullyDepth(double x_m, double z_m) const;
    // Ravine country's weight at (x, z) in [0, 1]: the gullies' depth is this times their own.
    double ravineMask(double x_m, double z_m) const;
    // False only where no gully cuts within radius_m of (x, z): ravine country's noise there, by
    // the noise's slope bound (kNoiseSlopeBound), stays below where the country begins. One
    // noise evaluation, conservative; true does not promise a gully.
    bool mayHaveGullies(double x_m, double z_m, double radius_m) const;
    // Bound on the slope of classicNoise in lattice units: sampled maxima come to about 3.2.
    static constexpr double kNoiseSlopeBound = 4.0;
    static constexpr double kGullyDepth_m = 8.0;      // deepest cut, mid ravine country
    static constexpr double kGullyWavelength_m = 110.0;  // of the noise whose zero lines they follow
    glm::dvec3 normal(double x_m, double z_m) const;  // unit, +Y up
    double moisture(double x_m, double z_m) const;    // [0, 1]

    // Moisture for a point whose height is already known (saves one height evaluation).
    double moistureAt(double x_m, double z_m, double height_m) const;
    // Horizontal step of the central differences behind normal().
    static constexpr double kNormalStep_m = 0.5;
    // Perlin evaluations behind one height() call: 8 in lowlands, 12 where mountains rise, 2
    // more in ravine country.
    static constexpr int kMaxOctavesPerHeight = 14;

    // One octave's mapping from world (x, z) to noise lattice coordinates: rotation by the
    // octave's angle, scaling by its frequency, a seed-dependent offset.
    struct Octave {
        double cosA = 1.0, sinA = 0.0;  // rotation
        double frequency_per_m = 1.0;   // lattice units per metre
        double offsetU = 0.0, offsetV = 0.0;
    };

    // One octave of GLM Perlin noise in about [-1, 1] at (x, z), evaluated precisely at any
    // magnitude of (x, z) (see the header comment). Also used by other world fields.
    static double octaveNoise(const Octave& octave, double x_m, double z_m);
    // GLM's classic Perlin noise glm::perlin(dvec2(u, v)) bit for bit, for u, v in [0, 289]
    // (one period), about four times faster: the period's permutation polynomial and each
    // lattice hash's gradient are tables made once with GLM's own arithmetic.
    static double classicNoise(double u, double v);
    // An octave for other fields (vegetation clumps, ...): rotation and offset from (seed, salt).
    static Octave makeOctave(std::uint64_t seed, std::uint64_t salt, double wavelength_m);

  private:
    double warpedHeight(double x_m, double z_m) const;

    double waterLevel_m_;
    std::array<Octave, 1> warpU_, warpV_;  // domain warp, one octave per component
    std::array<Octave, 2> continent_;      // large-scale land/lowland/mountain mask
    std::array<Octave, 4> ridged_;         // ridged multifractal mountains
    std::array<Octave, 3> hills_;          // fBm hills and detail
    std::array<Octave, 2> moisture_;       // moisture field
    Octave ravine_;                        // ravine country's mask
    std::array<Octave, 2> gully_;          // the gullies' course, and their depth along it
};

}  // namespace amb
