// Metrics.h — how wrong the applied ambience is, and how much it pops (docs/ARCHITECTURE.md
// "Measuring speed against error").
//
// [SECTION] Irradiance distance
//   For coefficient sets a, b the irradiance difference over the sphere of normals has the closed
//   form (the basis is orthonormal over the sphere, E(n) = sum_k Ahat_l L_k Y_k(n)):
//       ||E_a - E_b||^2 = sum_c w_c sum_k Ahat_l(k)^2 (a_kc - b_kc)^2,
//   w_c = Rec. 709 luminance weights (0.2126, 0.7152, 0.0722): a channel counts as much as it
//   contributes to perceived brightness, and a colour error still counts. The relative error of
//   an applied set against the oracle is ||E_applied - E_oracle|| / ||E_oracle||.
// [SECTION] Pop
//   The change of the applied irradiance at a fixed world point from one frame to the next, less
//   the oracle's own change over that frame (the light itself moving with the time of day):
//       pop = ||(A_t - A_{t-1}) - (O_t - O_{t-1})|| / ||O_{t-1}||.
//   The oracle is captured only on measured frames, so its per-frame change is taken as linear
//   between two measured frames (its change there comes from the time of day alone: the captured
//   scene is static).
// [SECTION] Pop along a moving point
//   The camera's ground point moves (on drives the car stands there). Applied there, A_t (the
//   value at frame t's point on frame t) changes because the point crosses the field and
//   because the field changes; both are smooth for a smooth field crossed at a steady speed, so
//   a pop is the part of a frame's change that the previous frame's change does not predict,
//   the second difference along the path, relative to the applied value:
//       pop_move = ||(A_t - A_{t-1}) - (A_{t-1} - A_{t-2})|| / ||A_{t-1}||.
//   A step J in one frame counts twice (J / ||A|| as it comes, again as it is not repeated); a
//   gradient g crossed at speed v gives nothing, a change of gradient g1 -> g2 (a bilinear
//   field's cell boundary) |g1 - g2| v dt, a blend at a steady rate nothing but its start and
//   end. The oracle's own change (the time of day) is smooth and cancels. Measured every frame
//   of a run with a measurement; a frame moving the point more than kMoveCut_m (a camera cut)
//   restarts it.
// [SECTION] Witness points
//   On a measured frame: the camera's ground point (ring 0) and, for each ring r >= 1 with
//   radius band [R_{r-1}, R_r), `perRing` terrain patch corners (a 32 m lattice, the corners of
//   the finest terrain patches) near radius (R_{r-1} + R_r) / 2, at angles spread around the
//   camera and turned by the golden angle from one measured frame to the next, so that over a
//   replay every direction is sampled. Pop points: the camera's ground point and the first
//   popPoints - 1 ring-1 witnesses, held fixed from one measured frame to the next.
// [SECTION] Oracle
//   A fresh capture at the exact point and time with the same capture settings: the probe placed
//   as the volume places its probes (probeHeight above the ground, moved out of plants), six
//   faces, projected with the sun's texel left out by its direction as the methods leave it. It
//   does not depend on the method, so a run can save the oracle of a replay and other runs of the
//   same replay read it back.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json_fwd.hpp>

#include "lighting/CubeCapture.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/ReferenceOracle.h"
#include "lighting/SH.h"
#include "world/Conventions.h"

namespace amb {

class AmbienceMethod;
class CubeCapture;

// ---- Irradiance distance ---------------------------------------------------------------------
// (luminance weights w_c: kLuminanceWeights, world/Conventions.h)

// ||E_a - E_b|| over the sphere of normals (see above), in irradiance units x sqrt(sr).
double irradianceDistance(const ShRgb& a, const ShRgb& b);
// ||E_a||.
double irradianceNorm(const ShRgb& a);
// ||E_applied - E_oracle|| / ||E_oracle||; the oracle's norm is floored at `floor` so a black
// oracle (a sealed cave, a moonless night) gives a large but finite number.
double relativeIrradianceError(const ShRgb& applied, const ShRgb& oracle, double floor = 1e-9);
// Pop at one point (see above): appliedChange = A_t - A_{t-1}, oracleChange = O_t - O_{t-1},
// oracle = O_{t-1} (the scale).
double popValue(const ShRgb& appliedChange, const ShRgb& oracleChange, const ShRgb& oracle,
                double floor = 1e-9);

// ---- Statistics ------------------------------------------------------------------------------
struct Summary {
    std::size_t count = 0;
    double mean = 0.0, p50 = 0.0, p95 = 0.0, p99 = 0.0, max = 0.0;
};
// Percentiles by linear interpolation between order statistics; empty input gives zeros.
// Non-finite values are counted in `count` but make mean and max infinite (they are never
// dropped silently).
Summary summarize(std::vector<double> values);

// ---- Witness points --------------------------------------------------------------------------
struct MeasureSettings {
    int every = 30;  // measure every K-th frame (0: never)
    // Ring bands [m]: ring r >= 1 covers [ringRadii[r-1], ringRadii[r]).
    std::vector<double> ringRadii{16.0, 48.0, 144.0, 432.0};
    int perRing = 4;                // witnesses per ring
    int popPoints = 3;              // the camera's ground point + popPoints - 1 ring-1 witnesses
    double cornerSpacing_m = 32.0;  // witnesses sit on this lattice (terrain patch corners)
    double maxAside_m = 4.0;        // oracle probe placement, as CaptureSettings::maxAside_m
    // Retired with CaptureSettings::sunThreshold: the oracles leave the sun's texel out by its
    // direction (CubeCapture::sunDirection), as the methods do. Kept until its setters go.
    double sunThreshold = kSunThreshold_Wpsrm2;
    int rings() const { return int(ringRadii.size()); }  // ring 0 + ringRadii.size() - 1 bands
};

struct Witness {
    double x_m = 0.0, z_m = 0.0;
    int ring = 0;
};
// The witnesses of the `measuredIndex`-th measured frame for a camera at (x, z).
std::vector<Witness> witnessPoints(const MeasureSettings& settings, double cameraX_m,
                                   double cameraZ_m, int measuredIndex);

// What the method applies at a witness, as the draw reads it: shAt at the camera's ground point
// (ring 0, an object), cornerShAtPoint at terrain patch corners (rings >= 1), at `point_m`,
// where the oracle looks from (the near field, lighting/NearField.h, needs the point).
ShRgb appliedAt(const AmbienceMethod& method, const Witness& w, const glm::dvec3& point_m);

// The oracle SH at ground point (x, z) at `timeOfDay_h` (see above).
ShRgb oracleSh(CubeCapture& capture, const ProbeEnvironment& environment,
               const MeasureSettings& settings, double x_m, double z_m, double timeOfDay_h);
// The same for a capture at `position_m` itself (an object witness: not moved).
ShRgb oracleShAt(CubeCapture& capture, const glm::dvec3& position_m, double timeOfDay_h);

// Which oracle the headline error (errors(), ringErrors()) is taken against.
enum class OracleKind { Self, Reference };
OracleKind parseOracleKind(const std::string& text, const std::string& where);
const char* toString(OracleKind kind);

// The error at the drawn normal of one terrain witness, split into a budget that closes: each
// step makes one more stage of the draw's path ideal, and each term is what the step takes off
// the error, so over any set of witnesses the means add up to the drawn error exactly:
//   drawn = farField + patch + model + truncation, where
//   farField    drawn - freshFar: the far field as interpolated from the method's probes
//               (spacing, staleness, blending, holes) against fresh captures of the far scene at
//               the patch's four corners (placed as probes are, the plants the method's captures
//               leave out left out), the rest of the draw's path (near field, patch mean) kept;
//               on a patch lit per vertex (AmbienceMethod::terrainVertexRange_m), at the four
//               vertices of the grid cell holding the witness instead;
//   patch       freshFar - atPoint: the patch's bilinear blend of its four corners (and the near
//               field's patch mean) against the same path evaluated at the witness' own point and
//               surface normal with a fresh far capture there (per vertex: the cell's triangle
//               interpolation of its vertices, each averaged over the vertex spacing);
//   model       atPoint - truncation: what the ambience model itself misses at a point (the
//               coarse capture scene, its surfaces lit by the hemisphere model, the near field's
//               spheres and ground) against the reference;
//   truncation  the reference cube's own order-2 SH at the normal against the reference.
// A term can be negative (an ideal stage that removes errors which cancelled others).
struct DrawnBudget {
    double drawn = std::numeric_limits<double>::quiet_NaN();       // = ReferenceWitness::drawnError
    double freshFar = std::numeric_limits<double>::quiet_NaN();    // error with fresh far captures
    double atPoint = std::numeric_limits<double>::quiet_NaN();     // ... at the witness' point
    double truncation = std::numeric_limits<double>::quiet_NaN();  // P2 of the reference
    // Beside the chain, not in it: the method's own answer (its interpolated far field, the near
    // field) at the witness' point and surface normal, with no patch to blend across: what a
    // draw that evaluated the ambient per pixel would show, so drawn - perPoint is what such a
    // draw could gain. Taken with the rest of the budget.
    double perPoint = std::numeric_limits<double>::quiet_NaN();
    // Signed, beside the chain (irradianceBias: lum / lum_ref - 1): the drawn answer's and the
    // answer at the point with fresh far captures (the model step's start), so the budget says
    // whether what is left is too bright or too dark.
    double drawnBias = std::numeric_limits<double>::quiet_NaN();
    double atPointBias = std::numeric_limits<double>::quiet_NaN();
    // Signed, beside the chain, splitting the model step where its light comes from: the coarse
    // capture scene with every plant, unlit by the near field, read through its order-2 SH at
    // the surface normal, captured (scene) at the reference's own point and (placed) where the
    // method's probes stand there (placeProbe: up and out of solids). scene says what the
    // capture scene and its surface light give; placed - scene what the probes' height adds;
    // atPoint - placed what the near field (plants left out of the capture and put back as
    // spheres, the terrain's horizon, the ground) adds.
    double sceneBias = std::numeric_limits<double>::quiet_NaN();
    double placedBias = std::numeric_limits<double>::quiet_NaN();
    bool complete() const {
        return std::isfinite(drawn) && std::isfinite(freshFar) && std::isfinite(atPoint) &&
               std::isfinite(truncation);
    }
};
// Means of the terms over the witnesses with a complete budget.
struct DrawnBudgetSummary {
    std::size_t count = 0;
    double drawn = 0.0, farField = 0.0, patch = 0.0, model = 0.0, truncation = 0.0;
    double perPoint = 0.0;  // the mean of DrawnBudget::perPoint (NaN when one lacks it)
    double drawnBias = 0.0, atPointBias = 0.0;  // the means of DrawnBudget's (NaN as perPoint)
    double sceneBias = 0.0, placedBias = 0.0;   // the same
    // (farField + patch + model + truncation) / drawn: 1 up to rounding, by construction.
    double closure() const;
};
DrawnBudgetSummary summarizeDrawnBudget(const std::vector<DrawnBudget>& budgets);

// One witness of a reference frame (lighting/ReferenceOracle.h): a terrain corner (ring >= 0,
// as the measured frame's witnesses) or an object (ring -1, `object`).
struct ReferenceWitness {
    int frame = 0;
    int ring = -1;
    ObjectKind object = ObjectKind::Car;
    glm::dvec3 position_m{0.0};  // where the reference and the coarse capture look from
    BudgetTerms terms;
    // An object witness at its drawn normal (ObjectWitness::normal): the object's SH through
    // that normal against the reference captured at the witness through the same normal.
    // A terrain witness as the screen shows it (NaN when not taken: no patch known):
    // the ambient the draw applies at the ground point, read as the draw reads it (the
    // corners of the terrain patch drawn there, each at its point and normal through
    // cornerIrradianceAtPoints, interpolated bilinearly; on a patch lit per vertex, the vertices
    // of its grid cell, interpolated as its triangles), against the reference irradiance at
    // that surface point and its normal: |E_drawn(n) - E_ref(n)| / |E_ref(n)|, luminance-weighted
    // channels, E_ref from a reference capture kScreenProbeOffset_m along the normal.
    // A witness on ground a bush, a rock or a trunk stands on is not seen: it gets none.
    double drawnError = std::numeric_limits<double>::quiet_NaN();
    // The same error split into its budget (DrawnBudget; incomplete without the ideal volume,
    // ReferenceSettings::idealVolume, which its fresh captures go with).
    DrawnBudget drawnBudget;
    GroundCover cover = GroundCover::Open;  // at the witness' ground point
    // How the sphere figure's capture point (position_m) was placed: a terrain witness in a
    // plant's footprint is moved aside or lifted, as probes are (the drawn-normal figure reads
    // the witness at its own ground point, under a crown or not). Objects: AtPoint.
    ProbePlacement placement = ProbePlacement::AtPoint;
};

// A screen witness (opt-in, on reference frames): a random pixel of the rendered main view, its
// surface point and normal, and the ambient irradiance the draw applied there. Its error is
// |E_applied(n) - E_ref(n)| / |E_ref(n)| (luminance-weighted channels), E_ref from a reference
// capture probeOffset_m along the normal from the surface. A terrain or road pixel whose
// reference would stand inside a plant or the terrain (the view left out a plant the full scene
// has: too few pixels or beyond its range) is left out and counted (ErrorMeter::screenLeftOut).
enum class SurfaceKind { Terrain = 1, Road = 2, Object = 3 };
inline constexpr int kSurfaceKinds = 3;
const char* toString(SurfaceKind kind);
struct ScreenWitness {
    SurfaceKind kind = SurfaceKind::Terrain;
    glm::dvec3 position_m{0.0};
    glm::dvec3 normal{0.0, 1.0, 0.0};
    glm::dvec3 applied{0.0};  // irradiance as drawn
};
struct ScreenResult {
    int frame = 0;
    SurfaceKind kind = SurfaceKind::Terrain;
    double error = 0.0;
    double bias = 0.0;  // irradianceBias: > 0 too bright
    glm::dvec3 position_m{0.0}, normal{0.0, 1.0, 0.0};
};

// ---- Error meter -----------------------------------------------------------------------------
// Drives the measurement along a run: call frame() once per frame after the method's store
// stage. Oracle values come from the cache when present (loadOracle) and are captured otherwise.
class ErrorMeter {
  public:
    ErrorMeter(CubeCapture& capture, const ProbeEnvironment& environment,
               const MeasureSettings& settings);

    void frame(int index, double time_s, double timeOfDay_h, const glm::dvec3& camera_m,
               double speed_mps, const AmbienceMethod& method);

    struct MeasuredFrame {
        int index = 0;
        double time_s = 0.0, timeOfDay_h = 0.0, speed_mps = 0.0;
        std::vector<Witness> witnesses;
        std::vector<double> errors;  // per witness
        double mean() const;
        double max() const;
        double ringMean(int ring) const;  // NaN when the ring has no witness
    };
    const std::vector<MeasuredFrame>& measured() const { return measured_; }
    // The headline error: every terrain witness of every measured frame against the oracle of
    // oracleKind() (with the reference, the reference frames' witnesses: their `total`).
    std::vector<double> errors() const;
    std::vector<double> ringErrors(int ring) const;

    // The reference oracle (lighting/ReferenceOracle.h) on every settings.every-th measured
    // frame, captured with `reference` (a full-scene capture; it must outlive the meter). With
    // `headline` the headline error is taken against it. Each reference frame adds the terrain
    // witnesses and the object witnesses of the environment, with their budget terms.
    void attachReference(CubeCapture& reference, const ReferenceSettings& settings,
                         bool headline);
    OracleKind oracleKind() const { return headline_; }
    bool hasReference() const { return reference_ != nullptr; }
    const ReferenceSettings& referenceSettings() const { return referenceSettings_; }
    const std::vector<ReferenceWitness>& referenceWitnesses() const { return referenceWitnesses_; }
    // Budget terms of the terrain witnesses (ring >= 0, or one ring), or of one object kind.
    std::vector<BudgetTerms> terrainBudget(int ring = -1) const;
    std::vector<BudgetTerms> objectBudget(ObjectKind kind) const;
    // The object witnesses of a kind at their drawn normal (ReferenceWitness::drawnError), or
    // their signed bias there.
    std::vector<double> objectDrawnErrors(ObjectKind kind, bool bias = false) const;
    // True when the latest frame() was a reference frame (screen witnesses are taken then).
    bool referenceFrameNow() const { return referenceNow_; }
    void screenFrame(int frameIndex, double timeOfDay_h, const std::vector<ScreenWitness>& pixels);
    // E_ref at a surface point and normal (a capture kScreenProbeOffset_m along the normal),
    // cached with the screen witnesses' references.
    glm::dvec3 surfaceReference(int frameIndex, const glm::dvec3& surface_m,
                                const glm::dvec3& normal, double timeOfDay_h);
    const std::vector<ScreenResult>& screenResults() const { return screenResults_; }
    std::vector<double> screenErrors(int kind = 0) const;  // kind 0: every surface
    // Screen witnesses left out: their reference would stand inside a plant or the terrain
    // (ProbeEnvironment::inTheOpen).
    std::size_t screenLeftOut() const { return screenLeftOut_; }
    // The terrain witnesses' errors at the drawn normal (ReferenceWitness::drawnError), of one
    // ring or (ring < 0) all; witnesses without one are left out.
    // `underCrown` 0: open ground only, 1: under crowns only, -1: both.
    std::vector<double> drawnErrors(int ring = -1, int underCrown = -1) const;
    // The budgets of the same witnesses (only those complete).
    std::vector<DrawnBudget> drawnBudgets(int ring = -1, int underCrown = -1) const;
    // Terrain witnesses on hidden ground (GroundCover::Hidden), left out of drawnErrors.
    std::size_t hiddenWitnesses() const;
    // Terrain witnesses whose sphere-figure capture was placed so (ReferenceWitness::placement).
    std::size_t placedWitnesses(ProbePlacement placement) const;
    static constexpr double kScreenProbeOffset_m = 0.25;
    double referenceSeconds() const { return reference_s_; }
    std::int64_t referenceCaptures() const { return referenceCaptures_; }
    std::int64_t referenceCacheHits() const { return referenceHits_; }
    // Reference cache, as the oracle cache but keyed by (frame, x, y, z):
    //   {"format": "ambience-reference", "version": 1, "signature": string,
    //    "entries": [{"frame", "x", "y", "z", "sh": [27 numbers], "e": [3 x rule size]}, ...]}
    void loadReference(const std::string& path, const std::string& signature);
    void loadReferenceText(const std::string& text, const std::string& where,
                           const std::string& signature);
    void saveReference(const std::string& path, const std::string& signature) const;
    const std::vector<double>& pops() const { return pops_; }
    // Pop along the camera's ground point, one per frame from the third on (see above).
    const std::vector<double>& movingPops() const { return movingPops_; }
    // The pop along the camera's ground point of the latest frame() (NaN on a frame without
    // one: the first two after the start or a cut, or with measurement off).
    double lastMovingPop() const { return lastMovingPop_; }
    static constexpr double kMoveCut_m = 100.0;
    const MeasureSettings& settings() const { return settings_; }
    double oracleSeconds() const { return oracle_s_; }  // wall time spent capturing the oracle
    std::int64_t oracleCaptures() const { return oracleCaptures_; }
    std::int64_t oracleCacheHits() const { return oracleHits_; }

    // Oracle cache: JSON keyed by (frame index, x, z) with the settings it was made with:
    //   {"format": "ambience-oracle", "version": 1, "signature": string,
    //    "entries": [{"frame": int >= 0, "x": number, "z": number, "sh": [27 numbers]}, ...]}
    // (`signature` names the replay, stride and capture settings). loadOracle reads the file
    // (at most kMaxOracleFileBytes, world/TextFile.h) and parses it with loadOracleText, which
    // throws InputError(where, ...) naming the field for anything else: malformed JSON, a wrong
    // type anywhere, a missing field, other settings, a repeated entry, or a coefficient beyond
    // +-kMaxOracleCoefficient. Only InputError, and the cache is unchanged on error.
    void loadOracle(const std::string& path, const std::string& signature);
    void loadOracleText(const std::string& text, const std::string& where,
                        const std::string& signature);
    // Largest oracle coefficient accepted: above anything a capture gives (the sun's radiance,
    // 2e7, over the whole sphere is ~7e7 per coefficient), far inside float, and small enough
    // that the error's squared sums stay finite.
    static constexpr double kMaxOracleCoefficient = 1.0e9;
    void saveOracle(const std::string& path, const std::string& signature) const;

  private:
    // Where the oracle looks from for a terrain witness (the probe placement).
    glm::dvec3 witnessPoint(const Witness& w) const;
    ShRgb oracle(int frameIndex, double x_m, double z_m, double timeOfDay_h);
    void movingPop(const glm::dvec3& camera_m, const AmbienceMethod& method);
    void parseOracle(const nlohmann::json& j, const std::string& where,
                     const std::string& signature);

    CubeCapture& capture_;
    const ProbeEnvironment& environment_;
    MeasureSettings settings_;
    std::vector<MeasuredFrame> measured_;
    std::vector<double> pops_;
    std::vector<double> movingPops_;
    double lastMovingPop_ = std::numeric_limits<double>::quiet_NaN();
    // The last two values along the moving point (newest first), and where it was.
    ShRgb movingPrevious_[2];
    double movingX_m_ = 0.0, movingZ_m_ = 0.0;
    int movingSeen_ = 0;
    ShRgb oracleAt(int frameIndex, const glm::dvec3& position_m, double timeOfDay_h);
    // The drawn-normal error of a terrain witness (budget.drawn), with the rest of its budget
    // when `budget` (fresh captures).
    DrawnBudget drawnTerrainError(int index, double timeOfDay_h, const glm::dvec3& camera_m,
                                  const Witness& w, const AmbienceMethod& method, bool budget,
                                  GroundCover& cover);
    void referenceFrame(int index, double timeOfDay_h, const glm::dvec3& camera_m,
                        const std::vector<Witness>& witnesses, const std::vector<ShRgb>& oracles,
                        const AmbienceMethod& method, int measuredIndex);
    const ReferenceSample& reference(int frameIndex, const glm::dvec3& position_m,
                                     double timeOfDay_h);
    // Oracle values by (frame, x, z) (the cache); y is kPlaced for a probe placed as the
    // volume's, or the explicit height of an object witness.
    static constexpr double kPlaced = -1e300;
    struct Key {
        int frame;
        double x, z;
        double y = kPlaced;
        bool operator<(const Key& o) const;
    };
    std::map<Key, ShRgb> oracleCache_;
    // The cache entry of `key`, captured at position() when missing.
    ShRgb cachedOracle(const Key& key, double timeOfDay_h,
                       const std::function<glm::dvec3()>& position);
    // The reference.
    CubeCapture* reference_ = nullptr;
    ReferenceSettings referenceSettings_;
    SphereRule rule_;
    OracleKind headline_ = OracleKind::Self;
    std::map<Key, ReferenceSample> referenceCache_;
    struct ScreenEntry {
        glm::vec3 normal, irradiance;
        // The reference cube's order-2 SH evaluated at the normal (the budget's truncation);
        // NaN when read from a file that has none.
        glm::vec3 truncated{std::numeric_limits<float>::quiet_NaN()};
    };
    // The entry of surfaceReference (captured when missing).
    const ScreenEntry& surfaceEntry(int frameIndex, const glm::dvec3& surface_m,
                                    const glm::dvec3& normal, double timeOfDay_h);
    // Fresh captures of the far scene (the plants within `radius_m` left out) placed as probes
    // are at ground point (x, z): the ideal far field of DrawnBudget (radius 0 and no light:
    // oracle()). Their surfaces lit by `light` (the method's own, captureSurfaceLight) when
    // not null.
    ShRgb farOracle(int frameIndex, double x_m, double z_m, double timeOfDay_h, double radius_m,
                    const SurfaceLight* light);
    std::map<std::pair<const SurfaceLight*, Key>, ShRgb> farCache_;
    // The coarse capture scene with every plant at position() (the entry of `key`), its
    // surfaces lit by `light` as the method's captures light theirs (captureSurfaceLight): the
    // split of DrawnBudget's model step. Without a light, cachedOracle.
    ShRgb litOracle(const Key& key, double timeOfDay_h,
                    const std::function<glm::dvec3()>& position, const SurfaceLight* light);
    std::map<std::pair<const SurfaceLight*, Key>, ShRgb> litCache_;
    std::map<Key, ScreenEntry> screenCache_;
    std::vector<ScreenResult> screenResults_;
    std::size_t screenLeftOut_ = 0;
    bool referenceNow_ = false;
    std::vector<ReferenceWitness> referenceWitnesses_;
    double reference_s_ = 0.0;
    std::int64_t referenceCaptures_ = 0, referenceHits_ = 0;
    double oracle_s_ = 0.0;
    std::int64_t oracleCaptures_ = 0, oracleHits_ = 0;
    // Pop tracking between measured frames.
    std::vector<Witness> popPoints_;
    std::vector<ShRgb> popOracleStart_;
    std::vector<ShRgb> popPrevious_;  // applied at the previous frame
    std::vector<glm::dvec3> popAt_;   // where each pop point's oracle looks from (placed once)
    struct PendingPop {
        std::size_t point;
        ShRgb delta;  // A_t - A_{t-1}
    };
    std::vector<PendingPop> pending_;
    int framesSinceMeasure_ = 0;
    int measuredCount_ = 0;
    int frameCounter_ = 0;
};

}  // namespace amb
