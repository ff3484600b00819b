// ReferenceOracle.h — the reference oracle, independent of every method, and the error budget
// that splits a method's error against it into its causes (docs/ARCHITECTURE.md "Measuring speed
// against error").
//
// [SECTION] Reference oracle
//   At a witness point: a 64 x 64 cube map of the full scene as the main view draws it (every
//   plant with its full mesh, bushes and rocks, the terrain at its finest level near the point;
//   the capture's CaptureScene::Full), the sun's texel left out exactly as the methods leave it
//   out: the texel the capture put the disc in, found by the capture's sun direction and filled
//   from its neighbours' sky (lighting/SunTexel.h), the same light left out at 64^2 as at the
//   methods' 16^2 (the renderer lights the sun apart). Its irradiance is taken straight from the
//   cube map (CubeIrradiance: exact per texel) at the directions of a sphere rule, never through
//   SH. Kept per witness: those irradiances, and the order-2 SH of the same cube (the projector's),
//   for the budget's term a.
// [SECTION] Error on the reference
//   ||E_x - E_ref|| / ||E_ref|| over the sphere of normals by the rule (ReferenceIrradiance.h);
//   the rule of degree 9 is exact for the SH parts and resolves the smooth higher bands of E_ref.
// [SECTION] Error budget
//   Each term makes one factor ideal and is relative to ||E_ref||:
//     a  truncation   E_ref against E of P2 (the order-2 SH of the reference cube);
//     b  capture      P2 against the coarse 16 x 16 capture at the same point (capture
//                     resolution, scene simplification);
//     c  spacing      the coarse capture at the point against the ideal volume: fresh coarse
//                     captures at the lattice points the method's interpolation reads there
//                     (AmbienceMethod::idealSupport), interpolated with its weights;
//     d  schedule     the ideal volume against what the method applies (staleness, blending,
//                     holes, the scheduler's choices).
//   total = E_ref against the applied E. Since E_ref - P2 is orthogonal to every order-2 field,
//   total^2 = a^2 + |P2 - applied|^2 exactly (up to the rule), and b, c, d split the second part;
//   they add up as squares when their errors are uncorrelated, which summarizeBudget reports
//   (sum of squares over total squared). Methods without a lattice get c and d as one term.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/ReferenceIrradiance.h"
#include "lighting/SH.h"

namespace amb {

struct ReferenceSettings {
    int faceSize = 64;       // texels per face edge of the reference capture
    int legendreNodes = 5;   // sphere rule (sphereProductRule): degree 9, 50 directions
    int every = 3;           // a reference on every K-th measured frame (1: all)
    int objectTrees = 2;     // trees per reference frame, each with a base and a crown witness
    double objectNear_m = 6.0, objectFar_m = 48.0;  // trees taken at these distances
    double carHeight_m = 1.0;                       // the car's witness above its ground point
    // Capture the ideal volume (term c; four coarse captures per witness). Off: c and d are
    // reported as one term, and the reference costs no captures beyond its own.
    bool idealVolume = true;
};

struct ReferenceSample {
    ShRgb sh;                            // order-2 SH of the reference cube (P2)
    std::vector<glm::vec3> irradiance;   // E_ref at the rule's directions
};

// The reference of one cube map (N x N faces, layout of CubeCapture) whose capture put the sun
// at `sunDirection` (CubeCapture::sunDirection; none: no sun), the sun's texel and bad texels
// left out.
ReferenceSample referenceSample(int faceSize, const std::vector<float>& cube,
                                const std::optional<glm::dvec3>& sunDirection,
                                const SphereRule& rule);

// The cube as the methods' projection sees it, in place: the sun's texel filled from its
// neighbours (fillSunTexel, lighting/SunTexel.h) and bad texels (NaN, infinite or negative)
// zeroed.
void dropSunTexel(std::vector<float>& cube, int faceSize,
                  const std::optional<glm::dvec3>& sunDirection);
// E_ref(n) at one normal: a reference cube captured at `probe`, the sun's texel dropped.
glm::dvec3 referenceIrradianceAt(int faceSize, std::vector<float> cube,
                                 const std::optional<glm::dvec3>& sunDirection,
                                 const glm::dvec3& normal);
// |a - ref| / |ref| with luminance-weighted channels (one normal: a screen witness).
double irradianceRelativeError(const glm::dvec3& applied, const glm::dvec3& ref);
// lum(a) / lum(ref) - 1, signed (luminance with the same weights): whether the error is too
// bright (> 0) or too dark.
double irradianceBias(const glm::dvec3& applied, const glm::dvec3& ref);

// ||E_sh - E_ref|| and ||E_ref|| by the rule.
double referenceDistance(const ReferenceSample& ref, const ShRgb& sh, const SphereRule& rule);
double referenceNorm(const ReferenceSample& ref, const SphereRule& rule);

struct BudgetTerms {
    double total = 0.0;       // applied against the reference
    double truncation = 0.0;  // a
    double capture = 0.0;     // b
    double spacing = 0.0;     // c (NaN when the method has no lattice)
    double schedule = 0.0;    // d (c and d together when it has none)
    double self = 0.0;        // applied against the coarse capture (the self-oracle's error)
};
// The terms at one witness (see above); `ideal` empty for a method without a lattice.
BudgetTerms budgetTerms(const ReferenceSample& ref, const ShRgb& coarse,
                        const std::optional<ShRgb>& ideal, const ShRgb& applied,
                        const SphereRule& rule);

// Root mean squares of the terms over witnesses (NaN spacing terms count as part of schedule).
struct BudgetSummary {
    std::size_t count = 0;
    double total = 0.0, truncation = 0.0, capture = 0.0, spacing = 0.0, schedule = 0.0;
    double meanTotal = 0.0;     // the mean (not RMS) of total, as the headline error
    bool hasSpacing = false;    // every witness had an ideal volume
    // (a^2 + b^2 + c^2 + d^2) / total^2 over the RMS values: 1 when the terms add up as squares.
    double closure() const;
};
BudgetSummary summarizeBudget(const std::vector<BudgetTerms>& terms);

}  // namespace amb
