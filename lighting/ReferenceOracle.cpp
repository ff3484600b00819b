// ReferenceOracle.cpp — reference samples, errors on them and the error budget (see the header).
#include "lighting/ReferenceOracle.h"

#include <cmath>
#include <limits>

#include "lighting/CubeMapProjector.h"
#include "lighting/Metrics.h"
#include "lighting/SunTexel.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

ReferenceSample referenceSample(int faceSize, const std::vector<float>& cube,
                                const std::optional<glm::dvec3>& sunDirection,
                                const SphereRule& rule) {
    AMB_CHECK(faceSize >= 1 && cube.size() == std::size_t(kCubeFaces) * faceSize * faceSize * 3);
    ReferenceSample out;
    out.sh = toFloat(projectCubeMap(faceSize, cube, {}, sunDirection).sh);
    // The texels the projection leaves out (the sun's, bad ones) are left out here too.
    std::vector<float> kept(cube);
    dropSunTexel(kept, faceSize, sunDirection);
    const CubeIrradiance irradiance(faceSize, kept);
    out.irradiance.reserve(rule.directions.size());
    for (const glm::dvec3& d : rule.directions) out.irradiance.emplace_back(irradiance.at(d));
    return out;
}

void dropSunTexel(std::vector<float>& cube, int faceSize,
                  const std::optional<glm::dvec3>& sunDirection) {
    AMB_CHECK(faceSize >= 1 && cube.size() == std::size_t(kCubeFaces) * faceSize * faceSize * 3);
    // First the sun (it skips bad neighbours, as the projector's fill does), then the bad texels.
    if (sunDirection) fillSunTexel(cube.data(), faceSize, *sunDirection);
    for (std::size_t t = 0; t + 2 < cube.size(); t += 3) {
        const float r = cube[t], g = cube[t + 1], b = cube[t + 2];
        const bool bad = !(std::isfinite(r) && std::isfinite(g) && std::isfinite(b)) || r < 0.0f ||
                         g < 0.0f || b < 0.0f;
        if (bad) cube[t] = cube[t + 1] = cube[t + 2] = 0.0f;
    }
}

glm::dvec3 referenceIrradianceAt(int faceSize, std::vector<float> cube,
                                 const std::optional<glm::dvec3>& sunDirection,
                                 const glm::dvec3& normal) {
    dropSunTexel(cube, faceSize, sunDirection);
    return CubeIrradiance(faceSize, cube).at(normal);
}

namespace {

double weightedSquare(const glm::dvec3& d) {
    return kLuminanceWeights[0] * d.x * d.x + kLuminanceWeights[1] * d.y * d.y +
           kLuminanceWeights[2] * d.z * d.z;
}

}  // namespace

double irradianceRelativeError(const glm::dvec3& applied, const glm::dvec3& ref) {
    return std::sqrt(weightedSquare(applied - ref) / std::max(weightedSquare(ref), 1e-18));
}

double irradianceBias(const glm::dvec3& applied, const glm::dvec3& ref) {
    const auto lum = [](const glm::dvec3& e) {
        return kLuminanceWeights[0] * e.x + kLuminanceWeights[1] * e.y + kLuminanceWeights[2] * e.z;
    };
    return lum(applied) / std::max(lum(ref), 1e-18) - 1.0;
}

double referenceDistance(const ReferenceSample& ref, const ShRgb& sh, const SphereRule& rule) {
    AMB_CHECK(ref.irradiance.size() == rule.directions.size());
    const ShRgbD d = toDouble(sh);
    double sum = 0.0;
    for (std::size_t k = 0; k < rule.directions.size(); ++k)
        sum += rule.weights[k] *
               weightedSquare(shIrradiance(d, rule.directions[k]) - glm::dvec3(ref.irradiance[k]));
    return std::sqrt(std::max(sum, 0.0));
}

double referenceNorm(const ReferenceSample& ref, const SphereRule& rule) {
    AMB_CHECK(ref.irradiance.size() == rule.directions.size());
    double sum = 0.0;
    for (std::size_t k = 0; k < rule.directions.size(); ++k)
        sum += rule.weights[k] * weightedSquare(glm::dvec3(ref.irradiance[k]));
    return std::sqrt(std::max(sum, 0.0));
}

BudgetTerms budgetTerms(const ReferenceSample& ref, const ShRgb& coarse,
                        const std::optional<ShRgb>& ideal, const ShRgb& applied,
                        const SphereRule& rule) {
    const double scale = 1.0 / std::max(referenceNorm(ref, rule), 1e-9);
    BudgetTerms t;
    t.total = referenceDistance(ref, applied, rule) * scale;
    t.truncation = referenceDistance(ref, ref.sh, rule) * scale;
    // The order-2 parts by the closed form (Metrics.h): the rule is exact for them.
    t.capture = irradianceDistance(ref.sh, coarse) * scale;
    if (ideal) {
        t.spacing = irradianceDistance(coarse, *ideal) * scale;
        t.schedule = irradianceDistance(*ideal, applied) * scale;
    } else {
        t.spacing = std::numeric_limits<double>::quiet_NaN();
        t.schedule = irradianceDistance(coarse, applied) * scale;
    }
    t.self = relativeIrradianceError(applied, coarse);
    return t;
}

double BudgetSummary::closure() const {
    const double s = truncation * truncation + capture * capture +
                     (hasSpacing ? spacing * spacing : 0.0) + schedule * schedule;
    return total > 0.0 ? s / (total * total) : 0.0;
}

BudgetSummary summarizeBudget(const std::vector<BudgetTerms>& terms) {
    BudgetSummary s;
    s.count = terms.size();
    if (terms.empty()) return s;
    s.hasSpacing = true;
    double total = 0, a = 0, b = 0, c = 0, d = 0, mean = 0;
    for (const BudgetTerms& t : terms) s.hasSpacing &= std::isfinite(t.spacing);
    for (const BudgetTerms& t : terms) {
        total += t.total * t.total;
        mean += t.total;
        a += t.truncation * t.truncation;
        b += t.capture * t.capture;
        if (s.hasSpacing) {
            c += t.spacing * t.spacing;
            d += t.schedule * t.schedule;
        } else {
            // c and d as one: the coarse capture against the applied value.
            const double cd = std::isfinite(t.spacing)
                                  ? std::sqrt(t.spacing * t.spacing + t.schedule * t.schedule)
                                  : t.schedule;
            d += cd * cd;
        }
    }
    const double n = double(terms.size());
    s.total = std::sqrt(total / n);
    s.meanTotal = mean / n;
    s.truncation = std::sqrt(a / n);
    s.capture = std::sqrt(b / n);
    s.spacing = s.hasSpacing ? std::sqrt(c / n) : std::numeric_limits<double>::quiet_NaN();
    s.schedule = std::sqrt(d / n);
    return s;
}

}  // namespace amb
