// NearField.cpp — the near field's closed forms, its transfer and its cache (NearField.h).
#include "lighting/NearField.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>

#include "lighting/JsonFields.h"
#include "world/Conventions.h"
#include "world/Error.h"
#include "world/Sky.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {

void readNearFieldSettings(JsonFields& f, NearFieldSettings& s) {
    f.boolean("enabled", s.enabled);
    f.number("radius_m", s.radius_m, 0.0, 200.0);
    f.boolean("plants", s.plants);
    f.integer("cacheEntries", s.cacheEntries, 1, 1 << 24);
}

// ---- [SECTION] Closed forms --------------------------------------------------------------------

namespace {

constexpr double kAhatBand[3] = {kShA0, kShA1, kShA2};
// Projected-area mean over a visible disc of the normals' irradiance, per band (NearField.h).
constexpr double kDiscMean[3] = {1.0, 2.0 / 3.0, 0.25};
// An occluder that holds the point counts as a cap of this half-angle.
const double kMaxCosHalfAngle = std::cos(80.0 * kPi / 180.0);

double capSolidAngle(double cosHalfAngle) {
    return 2.0 * kPi * (1.0 - cosHalfAngle);
}

}  // namespace

std::array<double, 3> capZonal(double c) {
    const double s2 = std::max(0.0, 1.0 - c * c);
    return {std::sqrt(kPi) * (1.0 - c), 0.5 * std::sqrt(3.0 * kPi) * s2,
            0.5 * std::sqrt(5.0 * kPi) * c * s2};
}

std::array<double, kShCoefficients> capSh(const glm::dvec3& direction, double cosHalfAngle) {
    const auto z = capZonal(cosHalfAngle);
    const auto y = shBasis(direction);
    std::array<double, kShCoefficients> out{};
    for (int k = 0; k < kShCoefficients; ++k) {
        const int l = shBand(k);
        out[k] = std::sqrt(4.0 * kPi / (2 * l + 1)) * z[l] * y[k];
    }
    return out;
}

double capOverlap(double a, double b, double d) {
    const double small = std::min(a, b), apart = std::fabs(a - b);
    if (d >= a + b) return 0.0;
    const double whole = capSolidAngle(std::cos(small));
    if (d <= apart) return whole;
    const double x = (a + b - d) / (a + b - apart);
    return whole * x * x * (3.0 - 2.0 * x);
}

double lambertSpherePhase(double alpha) {
    alpha = std::clamp(alpha, 0.0, kPi);
    return (std::sin(alpha) + (kPi - alpha) * std::cos(alpha)) / kPi;
}

// ---- [SECTION] Caps and their transfer ---------------------------------------------------------

std::vector<OccluderCap> occluderCaps(const glm::dvec3& point_m,
                                      const std::vector<SphereOccluder>& occluders) {
    std::vector<OccluderCap> caps;
    caps.reserve(occluders.size());
    for (const SphereOccluder& o : occluders) {
        const glm::dvec3 to = o.centre_m - point_m;
        const double d = glm::length(to);
        if (!(o.radius_m > 0.0) || !std::isfinite(d) || d <= 0.0) continue;
        const double sinT = std::min(1.0, o.radius_m / d);
        OccluderCap c;
        c.direction = to / d;
        c.cosHalfAngle = std::max(kMaxCosHalfAngle, std::sqrt(1.0 - sinT * sinT));
        c.albedo = o.albedo;
        caps.push_back(c);
    }
    // Largest first; each keeps what earlier ones leave of it.
    std::sort(caps.begin(), caps.end(), [](const OccluderCap& a, const OccluderCap& b) {
        return a.cosHalfAngle < b.cosHalfAngle;
    });
    std::vector<double> halfAngle(caps.size());
    for (std::size_t i = 0; i < caps.size(); ++i) halfAngle[i] = std::acos(caps[i].cosHalfAngle);
    for (std::size_t i = 0; i < caps.size(); ++i) {
        const double omega = capSolidAngle(caps[i].cosHalfAngle);
        double w = 1.0;
        for (std::size_t j = 0; j < i && w > 0.0; ++j) {
            const double cosD = std::clamp(glm::dot(caps[i].direction, caps[j].direction), -1.0, 1.0);
            const double d = std::acos(cosD);
            if (d >= halfAngle[i] + halfAngle[j]) continue;
            w *= std::max(0.0, 1.0 - capOverlap(halfAngle[i], halfAngle[j], d) / omega);
        }
        caps[i].weight = w;
    }
    caps.erase(std::remove_if(caps.begin(), caps.end(),
                              [](const OccluderCap& c) { return c.weight <= 0.0; }),
               caps.end());
    return caps;
}

NearFieldTransfer nearFieldTransfer(std::vector<OccluderCap> caps) {
    NearFieldTransfer t;
    for (const OccluderCap& cap : caps) {
        const auto c = capSh(cap.direction, cap.cosHalfAngle);
        const auto y = shBasis(-cap.direction);
        const double omega = capSolidAngle(cap.cosHalfAngle);
        std::array<double, kShCoefficients> g{};
        for (int k = 0; k < kShCoefficients; ++k)
            g[k] = kAhatBand[shBand(k)] * kDiscMean[shBand(k)] * y[k];
        for (int j = 0; j < kShCoefficients; ++j)
            for (int k = 0; k < kShCoefficients; ++k)
                t.hide[j * kShCoefficients + k] -= float(cap.weight * c[j] * c[k] / omega);
        for (int ch = 0; ch < 3; ++ch) {
            const double own = cap.albedo[ch] / kPi;
            for (int j = 0; j < kShCoefficients; ++j)
                for (int k = 0; k < kShCoefficients; ++k)
                    t.show[ch][j * kShCoefficients + k] += float(cap.weight * c[j] * own * g[k]);
        }
    }
    t.caps = std::move(caps);
    return t;
}

void updateLightTerm(NearFieldTransfer& t, const glm::dvec3& lightDirection) {
    t.lightDirection = lightDirection;
    for (auto& s : t.s) s.fill(0.0f);
    for (const OccluderCap& cap : t.caps) {
        const double cosA = std::clamp(glm::dot(lightDirection, -cap.direction), -1.0, 1.0);
        const double phase = (2.0 / 3.0) * lambertSpherePhase(std::acos(cosA)) / kPi;
        if (phase <= 0.0) continue;
        const auto c = capSh(cap.direction, cap.cosHalfAngle);
        for (int ch = 0; ch < 3; ++ch)
            for (int j = 0; j < kShCoefficients; ++j)
                t.s[ch][j] += float(cap.weight * cap.albedo[ch] * phase * c[j]);
    }
}

namespace {

// A lower bound of min_n E(n) per channel: E_00 - |E_1| - |E_2| by the addition theorem.
double irradianceLowerBound(const ShRgbD& sh, int ch) {
    double b1 = 0.0, b2 = 0.0;
    for (int k = 1; k < 4; ++k) b1 += sh.c[k][ch] * sh.c[k][ch];
    for (int k = 4; k < 9; ++k) b2 += sh.c[k][ch] * sh.c[k][ch];
    return kShA0 * kShY00 * sh.c[0][ch] - kShA1 * kShY1 * std::sqrt(b1) -
           kShA2 * std::sqrt(5.0 / (4.0 * kPi)) * std::sqrt(b2);
}

// far + s (near - far) with the largest s in [0, 1] whose irradiance is nowhere below min(0, the
// far field's minimum), per channel.
ShRgbD guarded(const ShRgbD& far, const ShRgbD& near) {
    bool safe = true;
    for (int ch = 0; ch < 3; ++ch) safe = safe && irradianceLowerBound(near, ch) >= 0.0;
    if (safe) return near;
    const glm::dvec3 nearMin = shMinIrradiance(near);
    if (nearMin.x >= 0.0 && nearMin.y >= 0.0 && nearMin.z >= 0.0) return near;
    const glm::dvec3 floor = glm::min(shMinIrradiance(far), glm::dvec3(0.0));
    ShRgbD out = near;
    for (int ch = 0; ch < 3; ++ch) {
        if (nearMin[ch] >= floor[ch]) continue;
        const auto mix = [&](double s) {
            ShRgbD m = far;
            for (int k = 0; k < kShCoefficients; ++k)
                m.c[k][ch] = far.c[k][ch] + s * (near.c[k][ch] - far.c[k][ch]);
            return m;
        };
        double lo = 0.0, hi = 1.0;
        for (int it = 0; it < 12; ++it) {
            const double mid = 0.5 * (lo + hi);
            (shMinIrradiance(mix(mid))[ch] >= floor[ch] ? lo : hi) = mid;
        }
        const ShRgbD m = mix(lo);
        for (int k = 0; k < kShCoefficients; ++k) out.c[k][ch] = m.c[k][ch];
    }
    return out;
}

}  // namespace

ShRgbD applyTransfer(const NearFieldTransfer& t, const ShRgbD& far, const DirectionalLight& light) {
    if (t.empty()) return far;
    ShRgbD hidden = far;
    for (int j = 0; j < kShCoefficients; ++j) {
        glm::dvec3 sum(0.0);
        for (int k = 0; k < kShCoefficients; ++k)
            sum += double(t.hide[j * kShCoefficients + k]) * far.c[k];
        hidden.c[j] += sum;
    }
    ShRgbD out = guarded(far, hidden);
    for (int ch = 0; ch < 3; ++ch) {
        const auto& m = t.show[ch];
        for (int j = 0; j < kShCoefficients; ++j) {
            double sum = 0.0;
            for (int k = 0; k < kShCoefficients; ++k) sum += m[j * kShCoefficients + k] * far.c[k][ch];
            out.c[j][ch] += sum + double(t.s[ch][j]) * light.irradiance[ch];
        }
    }
    return out;
}

ShRgbD applyNearField(const ShRgbD& far, const glm::dvec3& point_m,
                      const std::vector<SphereOccluder>& occluders, const DirectionalLight& light) {
    NearFieldTransfer t = nearFieldTransfer(occluderCaps(point_m, occluders));
    updateLightTerm(t, light.direction);
    return applyTransfer(t, far, light);
}

// ---- [SECTION] The world's occluders -----------------------------------------------------------

void WorldNearFieldScene::occludersNear(const glm::dvec3& point_m, double radius_m,
                                        std::vector<SphereOccluder>& out) const {
    for (const Plant& p : world_.vegetation().inDisc(point_m.x, point_m.z, radius_m)) {
        for (const PlantSphere& s : Vegetation::spheres(p.kind)) {
            out.push_back({p.position_m + double(p.scale) * s.centre_m,
                           double(p.scale) * s.radius_m, s.albedo});
        }
    }
}

DirectionalLight WorldNearFieldScene::mainLight(double timeOfDay_h) const {
    return world_.sky().mainLight(timeOfDay_h);
}

double WorldNearFieldScene::groundHeight(double x_m, double z_m) const {
    return world_.height(x_m, z_m);
}

// ---- [SECTION] Cache ---------------------------------------------------------------------------

std::size_t NearField::KeyHash::operator()(const std::array<float, 3>& k) const {
    std::uint32_t b[3];
    std::memcpy(b, k.data(), sizeof b);
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint32_t v : b) h = (h ^ v) * 1099511628211ull;
    return std::size_t(h);
}

NearField::NearField(const NearFieldScene& scene, const NearFieldSettings& settings)
    : scene_(scene), settings_(settings) {}

void NearField::setTimeOfDay(double timeOfDay_h) {
    const DirectionalLight l = scene_.mainLight(timeOfDay_h);
    std::lock_guard<std::mutex> lock(mutex_);
    light_ = l;
}

std::vector<SphereOccluder> NearField::occluders(const glm::dvec3& p, double selfRadius_m) const {
    std::vector<SphereOccluder> out;
    if (!settings_.plants) return out;
    scene_.occludersNear(p, settings_.radius_m, out);
    if (selfRadius_m > 0.0) {
        // An object's own spheres sit on its axis, straight above its base.
        out.erase(std::remove_if(out.begin(), out.end(),
                                 [&](const SphereOccluder& o) {
                                     return std::hypot(o.centre_m.x - p.x, o.centre_m.z - p.z) <
                                            selfRadius_m;
                                 }),
                  out.end());
    }
    return out;
}

const NearFieldTransfer* NearField::transferAt(const glm::dvec3& p) const {
    const std::array<float, 3> key{float(p.x), float(p.y), float(p.z)};
    auto it = cache_.find(key);
    if (it == cache_.end()) {
        if (cache_.size() >= std::size_t(settings_.cacheEntries)) cache_.clear();
        std::vector<OccluderCap> caps = occluderCaps(p, occluders(p, 0.0));
        std::unique_ptr<NearFieldTransfer> t;
        if (!caps.empty())
            t = std::make_unique<NearFieldTransfer>(nearFieldTransfer(std::move(caps)));
        it = cache_.emplace(key, std::move(t)).first;
    }
    NearFieldTransfer* t = it->second.get();
    // The light term follows the light to within half a degree (the phase law is smooth).
    if (t && glm::dot(t->lightDirection, light_.direction) < 0.99996)
        updateLightTerm(*t, light_.direction);
    return t;
}

ShRgb NearField::apply(const ShRgb& far, const glm::dvec3& point_m) const {
    if (!settings_.enabled) return far;
    std::lock_guard<std::mutex> lock(mutex_);
    const NearFieldTransfer* t = transferAt(point_m);
    if (!t) return far;
    return toFloat(applyTransfer(*t, toDouble(far), light_));
}

ShRgb NearField::applyUncached(const ShRgb& far, const glm::dvec3& point_m,
                               double selfRadius_m) const {
    if (!settings_.enabled) return far;
    DirectionalLight light;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        light = light_;
    }
    return toFloat(applyNearField(toDouble(far), point_m, occluders(point_m, selfRadius_m), light));
}

std::size_t NearField::cachedPoints() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cache_.size();
}

double NearField::cacheBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    double bytes = 0.0;
    for (const auto& [k, t] : cache_) {
        bytes += sizeof(k) + sizeof(t) + 2 * sizeof(void*);  // key, pointer, node links
        if (t) bytes += sizeof(*t) + double(t->caps.capacity()) * sizeof(OccluderCap);
    }
    return bytes;
}

}  // namespace amb
