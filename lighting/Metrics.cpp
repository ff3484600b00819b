// Metrics.cpp — irradiance distance, summaries, witnesses, oracle and the error meter
// (see Metrics.h).
#include "lighting/Metrics.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <climits>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include <unistd.h>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "lighting/AmbienceMethod.h"
#include "lighting/CubeCapture.h"
#include "lighting/CubeMapProjector.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/ReferenceIrradiance.h"
#include "world/Error.h"
#include "world/JsonText.h"
#include "world/TextFile.h"

namespace amb {

namespace {

constexpr double kBandWeight[kShCoefficients] = {kShA0, kShA1, kShA1, kShA1, kShA2,
                                                 kShA2, kShA2, kShA2, kShA2};

double normSquared(const ShRgb& d) {
    double total = 0.0;
    for (int k = 0; k < kShCoefficients; ++k) {
        const double a2 = kBandWeight[k] * kBandWeight[k];
        for (int c = 0; c < 3; ++c) {
            const double v = d.c[k][c];
            total += kLuminanceWeights[c] * a2 * v * v;
        }
    }
    return total;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

constexpr double kGoldenAngle = 2.39996322972865332;  // pi (3 - sqrt 5)

}  // namespace

// ---- Irradiance distance ---------------------------------------------------------------------

double irradianceDistance(const ShRgb& a, const ShRgb& b) {
    return std::sqrt(normSquared(a - b));
}

double irradianceNorm(const ShRgb& a) {
    return std::sqrt(normSquared(a));
}

double relativeIrradianceError(const ShRgb& applied, const ShRgb& oracle, double floor) {
    return irradianceDistance(applied, oracle) / std::max(irradianceNorm(oracle), floor);
}

double popValue(const ShRgb& appliedChange, const ShRgb& oracleChange, const ShRgb& oracle,
                double floor) {
    return irradianceDistance(appliedChange, oracleChange) /
           std::max(irradianceNorm(oracle), floor);
}

// ---- Statistics ------------------------------------------------------------------------------

Summary summarize(std::vector<double> values) {
    Summary s;
    s.count = values.size();
    if (values.empty()) return s;
    bool finite = true;
    double total = 0.0;
    for (double v : values) {
        finite &= std::isfinite(v);
        total += v;
    }
    if (!finite) {
        const double inf = std::numeric_limits<double>::infinity();
        s.mean = s.p50 = s.p95 = s.p99 = s.max = inf;
        return s;
    }
    std::sort(values.begin(), values.end());
    auto quantile = [&](double q) {
        const double at = q * double(values.size() - 1);
        const std::size_t i = std::size_t(std::floor(at));
        const std::size_t j = std::min(i + 1, values.size() - 1);
        return values[i] + (values[j] - values[i]) * (at - double(i));
    };
    s.mean = total / double(values.size());
    s.p50 = quantile(0.50);
    s.p95 = quantile(0.95);
    s.p99 = quantile(0.99);
    s.max = values.back();
    return s;
}

// ---- Witness points --------------------------------------------------------------------------

std::vector<Witness> witnessPoints(const MeasureSettings& settings, double cameraX_m,
                                   double cameraZ_m, int measuredIndex) {
    std::vector<Witness> out;
    out.push_back({cameraX_m, cameraZ_m, 0});
    const double s = settings.cornerSpacing_m;
    const double turn = kGoldenAngle * measuredIndex;
    for (int r = 1; r < settings.rings(); ++r) {
        const double radius =
            0.5 * (settings.ringRadii[std::size_t(r - 1)] + settings.ringRadii[std::size_t(r)]);
        for (int j = 0; j < settings.perRing; ++j) {
            // Rings are offset by half a step from each other, so no two rings share a bearing.
            const double angle = turn + 2.0 * kPi * (j + 0.5 * (r % 2)) / settings.perRing;
            const double x = cameraX_m + radius * std::cos(angle);
            const double z = cameraZ_m + radius * std::sin(angle);
            // Nearest corner of the patch lattice (exact: integer multiples of the spacing).
            out.push_back({std::round(x / s) * s, std::round(z / s) * s, r});
        }
    }
    return out;
}

ShRgb oracleSh(CubeCapture& capture, const ProbeEnvironment& environment,
               const MeasureSettings& settings, double x_m, double z_m, double timeOfDay_h) {
    return oracleShAt(capture, environment.placeProbe(x_m, z_m, settings.maxAside_m), timeOfDay_h);
}

ShRgb oracleShAt(CubeCapture& capture, const glm::dvec3& position_m, double timeOfDay_h) {
    // Bad texels are zeroed and counted by the projection; the coefficients stay finite. The
    // sun's texel is left out by its direction, as the methods leave it out (CaptureCore).
    const std::vector<float> cube = capture.captureAll(position_m, timeOfDay_h);
    return toFloat(
        projectCubeMap(capture.faceSize(), cube, {}, capture.sunDirection(timeOfDay_h)).sh);
}

OracleKind parseOracleKind(const std::string& text, const std::string& where) {
    if (text == "self") return OracleKind::Self;
    if (text == "reference") return OracleKind::Reference;
    throw InputError(where, "expected self or reference, got '" + text + "'");
}

const char* toString(OracleKind kind) {
    return kind == OracleKind::Reference ? "reference" : "self";
}

// ---- Error meter -----------------------------------------------------------------------------

bool ErrorMeter::Key::operator<(const Key& o) const {
    if (frame != o.frame) return frame < o.frame;
    if (x != o.x) return x < o.x;
    if (z != o.z) return z < o.z;
    return y < o.y;
}

ErrorMeter::ErrorMeter(CubeCapture& capture, const ProbeEnvironment& environment,
                       const MeasureSettings& settings)
    : capture_(capture), environment_(environment), settings_(settings) {
    if (settings.every < 0) throw InputError("--measure-every", "must be >= 0");
    if (settings.ringRadii.empty() || settings.perRing < 0 || settings.popPoints < 1 ||
        settings.cornerSpacing_m <= 0.0)
        throw InputError("measure settings", "need rings, perRing >= 0, popPoints >= 1");
}

ShRgb ErrorMeter::oracle(int frameIndex, double x_m, double z_m, double timeOfDay_h) {
    return cachedOracle({frameIndex, x_m, z_m}, timeOfDay_h, [&] {
        return environment_.placeProbe(x_m, z_m, settings_.maxAside_m);
    });
}

ShRgb ErrorMeter::oracleAt(int frameIndex, const glm::dvec3& position_m, double timeOfDay_h) {
    return cachedOracle({frameIndex, position_m.x, position_m.z, position_m.y}, timeOfDay_h,
                        [&] { return position_m; });
}

ShRgb ErrorMeter::cachedOracle(const Key& key, double timeOfDay_h,
                               const std::function<glm::dvec3()>& position) {
    const auto it = oracleCache_.find(key);
    if (it != oracleCache_.end()) {
        ++oracleHits_;
        return it->second;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const ShRgb sh = oracleShAt(capture_, position(), timeOfDay_h);
    oracle_s_ += secondsSince(t0);
    ++oracleCaptures_;
    oracleCache_.emplace(key, sh);
    return sh;
}

void ErrorMeter::attachReference(CubeCapture& reference, const ReferenceSettings& settings,
                                 bool headline) {
    if (settings.faceSize < 1 || settings.faceSize > 2048)
        throw InputError("--reference-size", "face size must be in [1, 2048]");
    if (settings.every < 1) throw InputError("--reference-every", "must be >= 1");
    if (settings.legendreNodes < 3 || settings.legendreNodes > 8)
        throw InputError("reference rule", "Legendre nodes must be in [3, 8]");
    if (settings.objectTrees < 0 || !(settings.objectNear_m >= 0.0) ||
        !(settings.objectFar_m >= settings.objectNear_m) || !(settings.carHeight_m >= 0.0))
        throw InputError("reference objects", "need trees >= 0 and 0 <= near <= far");
    reference_ = &reference;
    referenceSettings_ = settings;
    rule_ = sphereProductRule(settings.legendreNodes);
    headline_ = headline ? OracleKind::Reference : OracleKind::Self;
}

const ReferenceSample& ErrorMeter::reference(int frameIndex, const glm::dvec3& position_m,
                                             double timeOfDay_h) {
    const Key key{frameIndex, position_m.x, position_m.z, position_m.y};
    const auto it = referenceCache_.find(key);
    if (it != referenceCache_.end()) {
        ++referenceHits_;
        return it->second;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<float> cube = reference_->captureAll(position_m, timeOfDay_h);
    ReferenceSample sample =
        referenceSample(reference_->faceSize(), cube, reference_->sunDirection(timeOfDay_h), rule_);
    reference_s_ += secondsSince(t0);
    ++referenceCaptures_;
    return referenceCache_.emplace(key, std::move(sample)).first->second;
}

DrawnBudget ErrorMeter::drawnTerrainError(int index, double timeOfDay_h,
                                          const glm::dvec3& camera_m, const Witness& w,
                                          const AmbienceMethod& method, bool budget,
                                          GroundCover& cover) {
    DrawnBudget b;
    const DrawnPatch p = environment_.drawnPatch(w.x_m, w.z_m, camera_m);
    cover = p.cover;
    if (!(p.size_m > 0.0) || p.cover == GroundCover::Hidden) return b;
    // The four points whose values the draw interpolates at the witness, asked as the draw asks
    // them (MethodAmbient::cornerIrradianceBatch: each kShadingHeight_m up, its normal, and the
    // size the near field's patch mean averages over), with the weights of the interpolation.
    // A patch nearer the camera than the method's terrainVertexRange_m (horizontally, to its
    // bounds; RendererScene::buildView's rule) is lit per mesh vertex: the vertices of the
    // grid cell holding the witness, each at its own point (no patch mean), interpolated as the
    // cell's triangles interpolate them. Else the patch's corners, averaged over the patch,
    // blended bilinearly.
    std::array<glm::dvec3, 4> ground, normal;
    std::array<double, 4> weight;
    double patch_m = p.size_m;
    const double range = method.terrainVertexRange_m();
    const double dx = std::max({p.x0_m - camera_m.x, 0.0, camera_m.x - p.x0_m - p.size_m});
    const double dz = std::max({p.z0_m - camera_m.z, 0.0, camera_m.z - p.z0_m - p.size_m});
    if (range > 0.0 && std::hypot(dx, dz) < range) {
        const DrawnCell cell = environment_.drawnCell(w.x_m, w.z_m, camera_m);
        if (!cell.known || p.quads <= 0) return b;  // not known as drawn: not graded
        ground = cell.vertex_m, normal = cell.normal, weight = cell.weight;
        patch_m = 0.0;
    } else {
        const double u = (w.x_m - p.x0_m) / p.size_m, v = (w.z_m - p.z0_m) / p.size_m;
        ground = p.corner_m, normal = p.cornerNormal;
        weight = {(1.0 - u) * (1.0 - v), u * (1.0 - v), (1.0 - u) * v, u * v};
    }
    std::array<glm::dvec3, 4> at;
    std::array<double, 4> patch;
    std::array<glm::vec3, 4> e;
    for (std::size_t c = 0; c < 4; ++c) {
        at[c] = ground[c] + glm::dvec3(0.0, kShadingHeight_m, 0.0);
        patch[c] = patch_m;
    }
    const auto blend = [&] {
        return glm::dvec3(e[0]) * weight[0] + glm::dvec3(e[1]) * weight[1] +
               glm::dvec3(e[2]) * weight[2] + glm::dvec3(e[3]) * weight[3];
    };
    const ScreenEntry& ref = surfaceEntry(index, p.surface_m, p.surfaceNormal, timeOfDay_h);
    const glm::dvec3 eRef(ref.irradiance);
    method.cornerIrradianceAtPoints(4, at.data(), normal.data(), e.data(), patch.data());
    b.drawn = irradianceRelativeError(blend(), eRef);
    b.drawnBias = irradianceBias(blend(), eRef);
    if (!budget) return b;
    // The same path with the far field from fresh captures at those points' ground points.
    const double radius = method.farCaptureRadius_m();
    const SurfaceLight* light = method.captureSurfaceLight();
    std::array<ShRgb, 4> far;
    for (std::size_t c = 0; c < 4; ++c)
        far[c] = farOracle(index, ground[c].x, ground[c].z, timeOfDay_h, radius, light);
    method.irradianceFromFar(4, at.data(), normal.data(), far.data(), e.data(), patch.data());
    b.freshFar = irradianceRelativeError(blend(), eRef);
    // ... and at the witness' own point and surface normal: no blend across the patch.
    const glm::dvec3 point = p.surface_m + glm::dvec3(0.0, kShadingHeight_m, 0.0);
    const ShRgb farHere = farOracle(index, w.x_m, w.z_m, timeOfDay_h, radius, light);
    const double noPatch = 0.0;
    glm::vec3 here;
    method.irradianceFromFar(1, &point, &p.surfaceNormal, &farHere, &here, &noPatch);
    b.atPoint = irradianceRelativeError(glm::dvec3(here), eRef);
    b.atPointBias = irradianceBias(glm::dvec3(here), eRef);
    b.truncation = irradianceRelativeError(glm::dvec3(ref.truncated), eRef);
    const auto plain = [&](const ShRgb& sh) {
        return glm::dvec3(glm::max(shIrradiance(sh, glm::vec3(p.surfaceNormal)), glm::vec3(0.0f)));
    };
    const glm::dvec3 refPoint =
        p.surface_m + kScreenProbeOffset_m * glm::normalize(p.surfaceNormal);
    // The split's captures light their surfaces as the method's own captures do.
    b.sceneBias = irradianceBias(
        plain(litOracle({index, refPoint.x, refPoint.z, refPoint.y}, timeOfDay_h,
                        [&] { return refPoint; }, light)),
        eRef);
    b.placedBias = irradianceBias(
        plain(litOracle({index, w.x_m, w.z_m}, timeOfDay_h,
                        [&] { return environment_.placeProbe(w.x_m, w.z_m, settings_.maxAside_m); },
                        light)),
        eRef);
    method.cornerIrradianceAtPoints(1, &point, &p.surfaceNormal, &here, &noPatch);
    b.perPoint = irradianceRelativeError(glm::dvec3(here), eRef);
    return b;
}

ShRgb ErrorMeter::litOracle(const Key& key, double timeOfDay_h,
                             const std::function<glm::dvec3()>& position,
                             const SurfaceLight* light) {
    if (!light) return cachedOracle(key, timeOfDay_h, position);
    const auto it = litCache_.find({light, key});
    if (it != litCache_.end()) {
        ++oracleHits_;
        return it->second;
    }
    const auto t0 = std::chrono::steady_clock::now();
    capture_.setSurfaceLight(light);
    const ShRgb sh = oracleShAt(capture_, position(), timeOfDay_h);
    capture_.setSurfaceLight(nullptr);
    oracle_s_ += secondsSince(t0);
    ++oracleCaptures_;
    return litCache_.emplace(std::make_pair(light, key), sh).first->second;
}

ShRgb ErrorMeter::farOracle(int frameIndex, double x_m, double z_m, double timeOfDay_h,
                            double radius_m, const SurfaceLight* light) {
    if (!(radius_m > 0.0) && !light) return oracle(frameIndex, x_m, z_m, timeOfDay_h);
    const std::pair<const SurfaceLight*, Key> key{light, Key{frameIndex, x_m, z_m, radius_m}};
    const auto it = farCache_.find(key);
    if (it != farCache_.end()) {
        ++oracleHits_;
        return it->second;
    }
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<float> cube;
    capture_.setSurfaceLight(light);
    capture_.captureFar(environment_.placeProbe(x_m, z_m, settings_.maxAside_m), timeOfDay_h,
                        kAllCubeFaces, cube, radius_m);
    capture_.setSurfaceLight(nullptr);
    const ShRgb sh = toFloat(
        projectCubeMap(capture_.faceSize(), cube, {}, capture_.sunDirection(timeOfDay_h)).sh);
    oracle_s_ += secondsSince(t0);
    ++oracleCaptures_;
    return farCache_.emplace(key, sh).first->second;
}

DrawnBudgetSummary summarizeDrawnBudget(const std::vector<DrawnBudget>& budgets) {
    DrawnBudgetSummary s;
    for (const DrawnBudget& b : budgets) {
        if (!b.complete()) continue;
        ++s.count;
        s.drawn += b.drawn;
        s.farField += b.drawn - b.freshFar;
        s.patch += b.freshFar - b.atPoint;
        s.model += b.atPoint - b.truncation;
        s.truncation += b.truncation;
        s.perPoint += b.perPoint;  // NaN spreads: a budget without it says so
        s.drawnBias += b.drawnBias, s.atPointBias += b.atPointBias;
        s.sceneBias += b.sceneBias, s.placedBias += b.placedBias;
    }
    if (s.count > 0) {
        const double n = double(s.count);
        s.drawn /= n, s.farField /= n, s.patch /= n, s.model /= n, s.truncation /= n;
        s.perPoint /= n, s.drawnBias /= n, s.atPointBias /= n;
        s.sceneBias /= n, s.placedBias /= n;
    }
    return s;
}

double DrawnBudgetSummary::closure() const {
    return drawn > 0.0 ? (farField + patch + model + truncation) / drawn : 0.0;
}

void ErrorMeter::referenceFrame(int index, double timeOfDay_h, const glm::dvec3& camera_m,
                                const std::vector<Witness>& witnesses,
                                const std::vector<ShRgb>& oracles, const AmbienceMethod& method,
                                int measuredIndex) {
    // The ideal volume at a ground point: fresh coarse captures (placed as the volume places
    // its probes) at the lattice points the method reads there, with its weights.
    const auto ideal = [&](double x, double z) -> std::optional<ShRgb> {
        if (!referenceSettings_.idealVolume) return std::nullopt;
        const IdealSupport support = method.idealSupport(x, z);
        if (support.count == 0) return std::nullopt;
        ShRgb sum;
        for (int c = 0; c < support.count; ++c) {
            if (!(support.weight[c] > 0.0)) continue;
            sum += oracle(index, support.x_m[c], support.z_m[c], timeOfDay_h) *
                   float(support.weight[c]);
        }
        return sum;
    };
    for (std::size_t i = 0; i < witnesses.size(); ++i) {
        const Witness& w = witnesses[i];
        ReferenceWitness r;
        r.frame = index;
        r.ring = w.ring;
        r.position_m = environment_.placeProbe(w.x_m, w.z_m, settings_.maxAside_m);
        r.placement = environment_.placement(w.x_m, w.z_m, settings_.maxAside_m);
        const ReferenceSample& ref = reference(index, r.position_m, timeOfDay_h);
        r.terms = budgetTerms(ref, oracles[i], ideal(w.x_m, w.z_m),
                              appliedAt(method, w, r.position_m), rule_);
        r.drawnBudget = drawnTerrainError(index, timeOfDay_h, camera_m, w, method,
                                          referenceSettings_.idealVolume, r.cover);
        r.drawnError = r.drawnBudget.drawn;
        referenceWitnesses_.push_back(r);
    }
    const ReferenceSettings& rs = referenceSettings_;
    for (const ObjectWitness& o :
         environment_.objectWitnesses(camera_m.x, camera_m.z, rs.objectTrees, rs.objectNear_m,
                                      rs.objectFar_m, rs.carHeight_m, measuredIndex)) {
        ReferenceWitness r;
        r.frame = index;
        r.object = o.kind;
        r.position_m = o.position_m;
        const ReferenceSample& ref = reference(index, o.position_m, timeOfDay_h);
        const ShRgb coarse = oracleAt(index, o.position_m, timeOfDay_h);
        const ShRgb applied = method.shAt(o.groundX_m, o.groundZ_m);
        r.terms = budgetTerms(ref, coarse, ideal(o.groundX_m, o.groundZ_m), applied, rule_);
        // At the drawn normal: the object's SH through the normal of the surface the witness
        // stands for, as much of it as the draw gives that surface (a trunk's share under its
        // crown), against the reference captured at the witness (kScreenProbeOffset_m out from
        // that surface) through the same normal.
        const glm::dvec3 n = glm::normalize(o.normal);
        const glm::dvec3 eRef(
            surfaceEntry(index, o.position_m - kScreenProbeOffset_m * n, n, timeOfDay_h)
                .irradiance);
        const glm::dvec3 e =
            glm::max(glm::dvec3(shIrradiance(applied, glm::vec3(n))), glm::dvec3(0.0)) *
            o.ambientShare;
        r.drawnError = irradianceRelativeError(e, eRef);
        r.drawnBudget.drawn = r.drawnError;
        r.drawnBudget.drawnBias = irradianceBias(e, eRef);
        referenceWitnesses_.push_back(r);
    }
}

const char* toString(SurfaceKind kind) {
    switch (kind) {
        case SurfaceKind::Terrain:
            return "terrain";
        case SurfaceKind::Road:
            return "road";
        case SurfaceKind::Object:
            return "object";
    }
    return "?";
}

void ErrorMeter::screenFrame(int frameIndex, double timeOfDay_h,
                             const std::vector<ScreenWitness>& pixels) {
    if (!reference_) throw InputError("--screen-witnesses", "needs the reference oracle");
    for (const ScreenWitness& p : pixels) {
        // A reference inside a plant or the terrain sees nothing the pixel does: there the main
        // view left out a plant the full scene has (too few pixels, or beyond its range) or
        // drew coarser terrain. Such pixels grade the view's simplification, not the ambience.
        // (A plant's own pixels stand on its spheres' rim: they are not asked.)
        const glm::dvec3 probe = p.position_m + kScreenProbeOffset_m * glm::normalize(p.normal);
        if (p.kind != SurfaceKind::Object && !environment_.inTheOpen(probe, 0.0)) {
            ++screenLeftOut_;
            continue;
        }
        const glm::dvec3 eRef = surfaceReference(frameIndex, p.position_m, p.normal, timeOfDay_h);
        screenResults_.push_back({frameIndex, p.kind, irradianceRelativeError(p.applied, eRef),
                                  irradianceBias(p.applied, eRef), p.position_m, p.normal});
    }
}

glm::dvec3 ErrorMeter::surfaceReference(int frameIndex, const glm::dvec3& surface_m,
                                        const glm::dvec3& normal, double timeOfDay_h) {
    return glm::dvec3(surfaceEntry(frameIndex, surface_m, normal, timeOfDay_h).irradiance);
}

const ErrorMeter::ScreenEntry& ErrorMeter::surfaceEntry(int frameIndex,
                                                        const glm::dvec3& surface_m,
                                                        const glm::dvec3& normal,
                                                        double timeOfDay_h) {
    const glm::dvec3 n = glm::normalize(normal);
    const glm::dvec3 probe = surface_m + kScreenProbeOffset_m * n;
    const Key key{frameIndex, probe.x, probe.z, probe.y};
    auto it = screenCache_.find(key);
    if (it == screenCache_.end()) {
        const auto t0 = std::chrono::steady_clock::now();
        const std::optional<glm::dvec3> sun = reference_->sunDirection(timeOfDay_h);
        std::vector<float> cube = reference_->captureAll(probe, timeOfDay_h);
        const int size = reference_->faceSize();
        // The cube's own order-2 SH at the normal, the sun's texel left out as everywhere.
        const glm::dvec3 truncated =
            glm::max(shIrradiance(projectCubeMap(size, cube, {}, sun).sh, n), glm::dvec3(0.0));
        const glm::dvec3 e = referenceIrradianceAt(size, std::move(cube), sun, n);
        it = screenCache_
                 .emplace(key, ScreenEntry{glm::vec3(n), glm::vec3(e), glm::vec3(truncated)})
                 .first;
        reference_s_ += secondsSince(t0);
        ++referenceCaptures_;
    } else {
        ++referenceHits_;
    }
    return it->second;
}

std::vector<double> ErrorMeter::drawnErrors(int ring, int underCrown) const {
    std::vector<double> out;
    for (const ReferenceWitness& r : referenceWitnesses_) {
        const int crown = r.cover == GroundCover::UnderCrown ? 1 : 0;
        if (r.ring >= 0 && (ring < 0 || r.ring == ring) && std::isfinite(r.drawnError) &&
            (underCrown < 0 || underCrown == crown))
            out.push_back(r.drawnError);
    }
    return out;
}

std::vector<DrawnBudget> ErrorMeter::drawnBudgets(int ring, int underCrown) const {
    std::vector<DrawnBudget> out;
    for (const ReferenceWitness& r : referenceWitnesses_) {
        const int crown = r.cover == GroundCover::UnderCrown ? 1 : 0;
        if (r.ring >= 0 && (ring < 0 || r.ring == ring) && r.drawnBudget.complete() &&
            (underCrown < 0 || underCrown == crown))
            out.push_back(r.drawnBudget);
    }
    return out;
}

std::size_t ErrorMeter::hiddenWitnesses() const {
    std::size_t n = 0;
    for (const ReferenceWitness& r : referenceWitnesses_)
        n += r.ring >= 0 && r.cover == GroundCover::Hidden;
    return n;
}

std::size_t ErrorMeter::placedWitnesses(ProbePlacement placement) const {
    std::size_t n = 0;
    for (const ReferenceWitness& r : referenceWitnesses_)
        n += r.ring >= 0 && r.placement == placement;
    return n;
}

std::vector<double> ErrorMeter::screenErrors(int kind) const {
    std::vector<double> out;
    for (const ScreenResult& r : screenResults_)
        if (kind == 0 || int(r.kind) == kind) out.push_back(r.error);
    return out;
}

std::vector<BudgetTerms> ErrorMeter::terrainBudget(int ring) const {
    std::vector<BudgetTerms> out;
    for (const ReferenceWitness& r : referenceWitnesses_)
        if (r.ring >= 0 && (ring < 0 || r.ring == ring)) out.push_back(r.terms);
    return out;
}

std::vector<BudgetTerms> ErrorMeter::objectBudget(ObjectKind kind) const {
    std::vector<BudgetTerms> out;
    for (const ReferenceWitness& r : referenceWitnesses_)
        if (r.ring < 0 && r.object == kind) out.push_back(r.terms);
    return out;
}

std::vector<double> ErrorMeter::objectDrawnErrors(ObjectKind kind, bool bias) const {
    std::vector<double> out;
    for (const ReferenceWitness& r : referenceWitnesses_) {
        const double v = bias ? r.drawnBudget.drawnBias : r.drawnError;
        if (r.ring < 0 && r.object == kind && std::isfinite(v)) out.push_back(v);
    }
    return out;
}

// What the draw applies at a witness: the object path at the camera's ground point (ring 0: the
// car on drives), the terrain-corner path at the rings' patch corners; each at the witness's
// point, where the reference looks (a ground point inside a plant's footprint is moved out of
// it, as probes are: the low flight's passes through crowns; a car on the road stays put).
ShRgb appliedAt(const AmbienceMethod& method, const Witness& w, const glm::dvec3& point_m) {
    return w.ring == 0 ? method.shAt(point_m.x, point_m.z) : method.cornerShAtPoint(point_m);
}

glm::dvec3 ErrorMeter::witnessPoint(const Witness& w) const {
    return environment_.placeProbe(w.x_m, w.z_m, settings_.maxAside_m);
}

void ErrorMeter::frame(int index, double time_s, double timeOfDay_h, const glm::dvec3& camera_m,
                       double speed_mps, const AmbienceMethod& method) {
    if (settings_.every <= 0) return;
    movingPop(camera_m, method);
    // Pop: this frame's change at the held points.
    if (!popPoints_.empty()) {
        for (std::size_t i = 0; i < popPoints_.size(); ++i) {
            const ShRgb now = appliedAt(method, popPoints_[i], popAt_[i]);
            pending_.push_back({i, now - popPrevious_[i]});
            popPrevious_[i] = now;
        }
        ++framesSinceMeasure_;
    }
    const bool measure = frameCounter_++ % settings_.every == 0;
    referenceNow_ = false;
    if (!measure) return;

    // Close the pops since the last measured frame against the oracle's change there.
    if (!popPoints_.empty() && framesSinceMeasure_ > 0) {
        std::vector<ShRgb> oracleEnd;
        for (const Witness& p : popPoints_)
            oracleEnd.push_back(oracle(index, p.x_m, p.z_m, timeOfDay_h));
        const float perFrame = 1.0f / float(framesSinceMeasure_);
        for (const PendingPop& pp : pending_) {
            const ShRgb oracleStep = (oracleEnd[pp.point] - popOracleStart_[pp.point]) * perFrame;
            pops_.push_back(popValue(pp.delta, oracleStep, popOracleStart_[pp.point]));
        }
    }
    pending_.clear();
    framesSinceMeasure_ = 0;

    MeasuredFrame mf;
    mf.index = index;
    mf.time_s = time_s;
    mf.timeOfDay_h = timeOfDay_h;
    mf.speed_mps = speed_mps;
    const int measuredIndex = measuredCount_++;
    mf.witnesses = witnessPoints(settings_, camera_m.x, camera_m.z, measuredIndex);
    std::vector<ShRgb> oracles;
    for (const Witness& w : mf.witnesses) {
        const ShRgb o = oracle(index, w.x_m, w.z_m, timeOfDay_h);
        oracles.push_back(o);
        mf.errors.push_back(relativeIrradianceError(appliedAt(method, w, witnessPoint(w)), o));
    }
    referenceNow_ = reference_ && measuredIndex % referenceSettings_.every == 0;
    if (referenceNow_)
        referenceFrame(index, timeOfDay_h, camera_m, mf.witnesses, oracles, method, measuredIndex);
    // New pop points: the camera's ground point and the first ring-1 witnesses.
    popPoints_.clear();
    popOracleStart_.clear();
    popPrevious_.clear();
    popAt_.clear();
    for (std::size_t i = 0; i < mf.witnesses.size() && int(popPoints_.size()) < settings_.popPoints;
         ++i) {
        if (mf.witnesses[i].ring > 1) break;
        popPoints_.push_back(mf.witnesses[i]);
        popOracleStart_.push_back(oracles[i]);
        popAt_.push_back(witnessPoint(mf.witnesses[i]));
        popPrevious_.push_back(appliedAt(method, mf.witnesses[i], popAt_.back()));
    }
    measured_.push_back(std::move(mf));
}

void ErrorMeter::movingPop(const glm::dvec3& camera_m, const AmbienceMethod& method) {
    const ShRgb here = method.shAt(camera_m.x, camera_m.z);
    lastMovingPop_ = std::numeric_limits<double>::quiet_NaN();
    if (movingSeen_ > 0 &&
        std::hypot(camera_m.x - movingX_m_, camera_m.z - movingZ_m_) > kMoveCut_m) {
        movingSeen_ = 0;  // a cut: the path starts again
    }
    if (movingSeen_ >= 2) {
        lastMovingPop_ = popValue(here - movingPrevious_[0], movingPrevious_[0] - movingPrevious_[1],
                                  movingPrevious_[0]);
        movingPops_.push_back(lastMovingPop_);
    }
    movingPrevious_[1] = movingPrevious_[0];
    movingPrevious_[0] = here;
    movingX_m_ = camera_m.x, movingZ_m_ = camera_m.z;
    movingSeen_ = std::min(movingSeen_ + 1, 2);
}

double ErrorMeter::MeasuredFrame::mean() const {
    if (errors.empty()) return 0.0;
    double total = 0.0;
    for (double e : errors) total += e;
    return total / double(errors.size());
}

double ErrorMeter::MeasuredFrame::max() const {
    double m = 0.0;
    for (double e : errors) m = std::max(m, e);
    return m;
}

double ErrorMeter::MeasuredFrame::ringMean(int ring) const {
    double total = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < witnesses.size(); ++i)
        if (witnesses[i].ring == ring) total += errors[i], ++n;
    return n ? total / n : std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> ErrorMeter::errors() const {
    std::vector<double> out;
    if (headline_ == OracleKind::Reference) {
        for (const BudgetTerms& t : terrainBudget()) out.push_back(t.total);
        return out;
    }
    for (const auto& m : measured_) out.insert(out.end(), m.errors.begin(), m.errors.end());
    return out;
}

std::vector<double> ErrorMeter::ringErrors(int ring) const {
    std::vector<double> out;
    if (headline_ == OracleKind::Reference) {
        for (const BudgetTerms& t : terrainBudget(ring)) out.push_back(t.total);
        return out;
    }
    for (const auto& m : measured_)
        for (std::size_t i = 0; i < m.witnesses.size(); ++i)
            if (m.witnesses[i].ring == ring) out.push_back(m.errors[i]);
    return out;
}

// ---- Oracle cache ----------------------------------------------------------------------------

namespace {

// Writes `j` to `path` through a temporary beside it, so a reader never sees half a file. The
// temporary is the process's own: a bench's runs of one replay may save its caches at once
// (each a whole cache; the last rename wins).
void writeJsonFile(const std::string& path, const nlohmann::json& j, const std::string& what) {
    const std::string tmp = path + "." + std::to_string(::getpid()) + ".part";
    {
        std::ofstream out(tmp);
        if (!out) throw InputError(path, "cannot write the " + what);
        out << j.dump() << "\n";
        if (!out) throw InputError(path, "cannot write the " + what);
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
        throw InputError(path, "cannot write the " + what);
}

}  // namespace

void ErrorMeter::saveOracle(const std::string& path, const std::string& signature) const {
    nlohmann::json j;
    j["format"] = "ambience-oracle";
    j["version"] = 1;
    j["signature"] = signature;
    nlohmann::json entries = nlohmann::json::array();
    for (const auto& [key, sh] : oracleCache_) {
        nlohmann::json coefficients = nlohmann::json::array();
        for (int k = 0; k < kShCoefficients; ++k)
            for (int c = 0; c < 3; ++c) coefficients.push_back(sh.c[k][c]);
        nlohmann::json entry{{"frame", key.frame}, {"x", key.x}, {"z", key.z}, {"sh", coefficients}};
        if (key.y != kPlaced) entry["y"] = key.y;
        entries.push_back(std::move(entry));
    }
    j["entries"] = std::move(entries);
    writeJsonFile(path, j, "oracle file");
}

void ErrorMeter::loadOracle(const std::string& path, const std::string& signature) {
    loadOracleText(readTextFile(path, "oracle file", kMaxOracleFileBytes), path, signature);
}

namespace {

const nlohmann::json& requireField(const nlohmann::json& object, const char* key,
                                   const std::string& where) {
    const auto it = object.find(key);
    if (it == object.end()) throw InputError(where, std::string("'") + key + "' is missing");
    return *it;
}

double oracleNumber(const nlohmann::json& v, const std::string& where, const std::string& field) {
    if (!v.is_number()) throw InputError(where, field + ": expected a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) throw InputError(where, field + ": not finite");
    return x;
}

// One cache entry: {"frame": int >= 0, "x": number, "z": number, "sh": 27 numbers}.
std::pair<int, std::array<double, 2>> oracleKey(const nlohmann::json& item,
                                                const std::string& where) {
    if (!item.is_object()) throw InputError(where, "expected an object");
    const nlohmann::json& frame = requireField(item, "frame", where);
    if (!frame.is_number_integer() ||
        (frame.is_number_unsigned()
             ? frame.get<std::uint64_t>() > std::uint64_t(INT_MAX)
             : (frame.get<std::int64_t>() < 0 || frame.get<std::int64_t>() > INT_MAX))) {
        throw InputError(where, "frame: expected an integer from 0 to " + std::to_string(INT_MAX));
    }
    return {int(frame.get<std::int64_t>()),
            {oracleNumber(requireField(item, "x", where), where, "x"),
             oracleNumber(requireField(item, "z", where), where, "z")}};
}

ShRgb oracleCoefficients(const nlohmann::json& item, const std::string& where) {
    const nlohmann::json& coefficients = requireField(item, "sh", where);
    if (!coefficients.is_array() || coefficients.size() != 3 * kShCoefficients)
        throw InputError(where, "sh: expected 27 numbers");
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k) {
        for (int c = 0; c < 3; ++c) {
            const std::string field = "sh[" + std::to_string(3 * k + c) + "]";
            const double v = oracleNumber(coefficients[std::size_t(3 * k + c)], where, field);
            if (!(std::fabs(v) <= ErrorMeter::kMaxOracleCoefficient)) {
                throw InputError(where, field + ": " + std::to_string(v) + " is beyond +-" +
                                            std::to_string(ErrorMeter::kMaxOracleCoefficient));
            }
            sh.c[k][c] = float(v);
        }
    }
    return sh;
}

}  // namespace

void ErrorMeter::loadOracleText(const std::string& text, const std::string& where,
                                const std::string& signature) {
    nlohmann::json j;
    try {
        j = parseJsonText(text, where);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(where, std::string("malformed oracle file: ") + e.what());
    }
    try {
        parseOracle(j, where, signature);
    } catch (const nlohmann::json::exception& e) {  // not expected: every access is checked
        throw InputError(where, std::string("malformed oracle file: ") + e.what());
    }
}

void ErrorMeter::parseOracle(const nlohmann::json& j, const std::string& where,
                             const std::string& signature) {
    const auto stringField = [&](const char* key) -> std::string {
        const auto it = j.find(key);
        if (it == j.end() || !it->is_string())
            throw InputError(where, std::string("'") + key + "' must be a string");
        return it->get<std::string>();
    };
    if (!j.is_object()) throw InputError(where, "not an ambience oracle file (not a JSON object)");
    const auto version = j.find("version");
    if (stringField("format") != "ambience-oracle" || version == j.end() ||
        !version->is_number_integer() || version->get<std::int64_t>() != 1) {
        throw InputError(where, "not an ambience oracle file (format/version)");
    }
    const std::string fileSignature = stringField("signature");
    if (fileSignature != signature) {
        throw InputError(where, "oracle made for other settings: '" + fileSignature +
                                    "', this run is '" + signature + "'");
    }
    const nlohmann::json& entries = requireField(j, "entries", where);
    if (!entries.is_array()) throw InputError(where, "'entries' must be an array");
    std::map<Key, ShRgb> loaded;
    for (std::size_t e = 0; e < entries.size(); ++e) {
        const std::string at = where + ": entries[" + std::to_string(e) + "]";
        const auto [frame, xz] = oracleKey(entries[e], at);
        Key key{frame, xz[0], xz[1]};
        if (entries[e].contains("y")) key.y = oracleNumber(entries[e]["y"], at, "y");
        if (!loaded.emplace(key, oracleCoefficients(entries[e], at)).second)
            throw InputError(at, "repeats an earlier entry's frame, x, y and z");
    }
    oracleCache_ = std::move(loaded);
}

// ---- Reference cache -------------------------------------------------------------------------

void ErrorMeter::saveReference(const std::string& path, const std::string& signature) const {
    nlohmann::json j;
    j["format"] = "ambience-reference";
    j["version"] = 1;
    j["signature"] = signature;
    nlohmann::json entries = nlohmann::json::array();
    for (const auto& [key, sample] : referenceCache_) {
        nlohmann::json coefficients = nlohmann::json::array(), e = nlohmann::json::array();
        for (int k = 0; k < kShCoefficients; ++k)
            for (int c = 0; c < 3; ++c) coefficients.push_back(sample.sh.c[k][c]);
        for (const glm::vec3& v : sample.irradiance)
            for (int c = 0; c < 3; ++c) e.push_back(v[c]);
        entries.push_back({{"frame", key.frame},
                           {"x", key.x},
                           {"y", key.y},
                           {"z", key.z},
                           {"sh", coefficients},
                           {"e", e}});
    }
    j["entries"] = std::move(entries);
    nlohmann::json screen = nlohmann::json::array();
    for (const auto& [key, entry] : screenCache_) {
        nlohmann::json e = {{"frame", key.frame},
                            {"x", key.x},
                            {"y", key.y},
                            {"z", key.z},
                            {"n", {entry.normal.x, entry.normal.y, entry.normal.z}},
                            {"e", {entry.irradiance.x, entry.irradiance.y, entry.irradiance.z}}};
        if (std::isfinite(entry.truncated.x))
            e["t"] = {entry.truncated.x, entry.truncated.y, entry.truncated.z};
        screen.push_back(std::move(e));
    }
    j["screen"] = std::move(screen);
    writeJsonFile(path, j, "reference file");
}

void ErrorMeter::loadReference(const std::string& path, const std::string& signature) {
    loadReferenceText(readTextFile(path, "reference file", kMaxOracleFileBytes), path, signature);
}

void ErrorMeter::loadReferenceText(const std::string& text, const std::string& where,
                                   const std::string& signature) {
    if (!reference_) throw InputError(where, "no reference oracle attached");
    nlohmann::json j;
    try {
        j = parseJsonText(text, where);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(where, std::string("malformed reference file: ") + e.what());
    }
    if (!j.is_object() || !j.contains("format") || j["format"] != "ambience-reference" ||
        !j.contains("version") || j["version"] != 1)
        throw InputError(where, "not an ambience reference file (format/version)");
    if (!j.contains("signature") || !j["signature"].is_string())
        throw InputError(where, "'signature' must be a string");
    const std::string fileSignature = j["signature"].get<std::string>();
    if (fileSignature != signature) {
        throw InputError(where, "reference made for other settings: '" + fileSignature +
                                    "', this run is '" + signature + "'");
    }
    const nlohmann::json& entries = requireField(j, "entries", where);
    if (!entries.is_array()) throw InputError(where, "'entries' must be an array");
    std::map<Key, ReferenceSample> loaded;
    const std::size_t values = 3 * rule_.directions.size();
    for (std::size_t n = 0; n < entries.size(); ++n) {
        const std::string at = where + ": entries[" + std::to_string(n) + "]";
        const auto [frame, xz] = oracleKey(entries[n], at);
        const Key key{frame, xz[0], xz[1], oracleNumber(requireField(entries[n], "y", at), at, "y")};
        ReferenceSample sample;
        sample.sh = oracleCoefficients(entries[n], at);
        const nlohmann::json& e = requireField(entries[n], "e", at);
        if (!e.is_array() || e.size() != values)
            throw InputError(at, "e: expected " + std::to_string(values) + " numbers");
        for (std::size_t k = 0; k < values; k += 3) {
            glm::vec3 v;
            for (int c = 0; c < 3; ++c) {
                const std::string field = "e[" + std::to_string(k + c) + "]";
                const double x = oracleNumber(e[k + c], at, field);
                if (!(std::fabs(x) <= kMaxOracleCoefficient))
                    throw InputError(at, field + ": beyond +-" +
                                             std::to_string(kMaxOracleCoefficient));
                v[c] = float(x);
            }
            sample.irradiance.push_back(v);
        }
        if (!loaded.emplace(key, std::move(sample)).second)
            throw InputError(at, "repeats an earlier entry's frame, x, y and z");
    }
    // Screen witnesses' references (optional): {"frame", "x", "y", "z", "n": [3], "e": [3],
    // "t": [3] (optional)}.
    std::map<Key, ScreenEntry> screen;
    if (j.contains("screen")) {
        const nlohmann::json& list = j["screen"];
        if (!list.is_array()) throw InputError(where, "'screen' must be an array");
        for (std::size_t n = 0; n < list.size(); ++n) {
            const std::string at = where + ": screen[" + std::to_string(n) + "]";
            const auto [frame, xz] = oracleKey(list[n], at);
            const Key key{frame, xz[0], xz[1],
                          oracleNumber(requireField(list[n], "y", at), at, "y")};
            ScreenEntry entry{};
            // "t" (the truncated reference) is optional: files written before it have none.
            for (const char* field : {"n", "e", "t"}) {
                if (field[0] == 't' && !list[n].contains("t")) continue;
                const nlohmann::json& v = requireField(list[n], field, at);
                if (!v.is_array() || v.size() != 3)
                    throw InputError(at, std::string(field) + ": expected 3 numbers");
                glm::vec3& out = field[0] == 'n'   ? entry.normal
                                 : field[0] == 'e' ? entry.irradiance
                                                   : entry.truncated;
                for (int c = 0; c < 3; ++c) {
                    const double x = oracleNumber(v[std::size_t(c)], at, field);
                    if (!(std::fabs(x) <= kMaxOracleCoefficient))
                        throw InputError(at, std::string(field) + ": out of range");
                    out[c] = float(x);
                }
            }
            if (!screen.emplace(key, entry).second)
                throw InputError(at, "repeats an earlier entry's frame, x, y and z");
        }
    }
    referenceCache_ = std::move(loaded);
    screenCache_ = std::move(screen);
}

}  // namespace amb
