// NearFieldScene.cpp — the world as the near field sees it: its occluders near a point and the
// ground around it (NearField.h, WorldNearFieldScene).
#include "lighting/NearField.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Sky.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {

// ---- [SECTION] The world's occluders -----------------------------------------------------------

void WorldNearFieldScene::occludersNear(const glm::dvec3& point_m, double radius_m,
                                        double smallRadius_m,
                                        std::vector<SphereOccluder>& out) const {
    const double reach = std::max(radius_m, smallRadius_m);
    for (const Plant& p : world_.vegetation().inDisc(point_m.x, point_m.z, reach)) {
        const bool small = p.kind == PlantKind::Bush || p.kind == PlantKind::Rock;
        const double d = std::hypot(p.position_m.x - point_m.x, p.position_m.z - point_m.z);
        const double r = small ? smallRadius_m : radius_m;
        if (d >= r) continue;
        // Faded out over the last quarter of the radius: a moving point gains and loses plants
        // smoothly (see Radii).
        const double x = std::clamp((r - d) / (kNearFade * r), 0.0, 1.0);
        const double weight = x * x * (3.0 - 2.0 * x);
        for (const PlantSphere& s : Vegetation::spheres(p.kind)) {
            out.push_back({p.position_m + double(p.scale) * s.centre_m,
                           double(p.scale) * s.radius_m, s.albedo, weight});
        }
    }
}

void WorldNearFieldScene::terrainNear(const glm::dvec3& p, double radius_m,
                                      std::vector<HorizonWedge>& out) const {
    // With no road near the disc, its heights are the heightfield's (one road query, not one a
    // sample: World::roadWithin).
    const bool roads = world_.roadWithin(p.x, p.z, radius_m);
    const auto heightAt = [&](double x, double z, double* road) {
        return roads ? world_.heightAndRoad(x, z, road) : world_.heightfield().height(x, z);
    };
    // The broad slope: the plane through the heights radius_m away.
    const double gx = (heightAt(p.x + radius_m, p.z, nullptr) - heightAt(p.x - radius_m, p.z, nullptr)) /
                      (2.0 * radius_m);
    const double gz = (heightAt(p.x, p.z + radius_m, nullptr) - heightAt(p.x, p.z - radius_m, nullptr)) /
                      (2.0 * radius_m);
    // Samples along each wedge's middle, denser near the point.
    constexpr int kSteps = 7;
    for (int w = 0; w < kWedges; ++w) {
        const double phi0 = 2.0 * kPi * w / kWedges, phi1 = 2.0 * kPi * (w + 1) / kWedges;
        const double phi = 0.5 * (phi0 + phi1);
        const glm::dvec2 dir(std::cos(phi), std::sin(phi));
        // The highest sample, and the slope along the wedge there (from the sample before).
        const double broadAlong = gx * dir.x + gz * dir.y;
        double best = -0.5 * kPi, bestX = p.x, bestZ = p.z, bestH = 0.0, bestRoad = 0.0;
        double bestSlope = broadAlong, lastD = 0.0, lastH = 0.0;
        bool first = true;
        for (int i = 1; i <= kSteps; ++i) {
            const double t = double(i) / kSteps, d = radius_m * t * t;
            if (d < 1.0) continue;
            const double x = p.x + d * dir.x, z = p.z + d * dir.y;
            double road = 0.0;
            const double height = heightAt(x, z, &road);
            const double e = std::atan2(height - p.y, d);
            if (e > best) {
                best = e, bestX = x, bestZ = z, bestH = height, bestRoad = road;
                bestSlope = first ? broadAlong : (height - lastH) / (d - lastD);
            }
            first = false, lastD = d, lastH = height;
        }
        HorizonWedge h;
        h.azimuth0 = phi0, h.azimuth1 = phi1;
        h.lower = std::atan(broadAlong);
        h.upper = best;
        if (h.upper > h.lower) {
            // The wall's albedo as the patches draw it: the broad slope across the wedge, the
            // sampled one along it.
            const glm::dvec2 g = glm::dvec2(gx, gz) + (bestSlope - broadAlong) * dir;
            const glm::dvec3 normal = glm::normalize(glm::dvec3(-g.x, 1.0, -g.y));
            h.albedo = glm::dvec3(albedo_.at(bestX, bestZ, bestH, bestRoad, normal,
                                             TerrainPatch::kFinestSpacing_m));
            out.push_back(h);
        }
    }
}

DirectionalLight WorldNearFieldScene::mainLight(double timeOfDay_h) const {
    return world_.sky().mainLight(timeOfDay_h);
}

HemisphereAmbient WorldNearFieldScene::ambient(double timeOfDay_h) const {
    return hemisphereAmbient(world_.sky(), timeOfDay_h);
}

double WorldNearFieldScene::groundHeight(double x_m, double z_m) const {
    return world_.height(x_m, z_m);
}

// ---- [SECTION] Ground --------------------------------------------------------------------------

namespace {

constexpr int kGroundRings = 4, kGroundAzimuths = 8;  // 32 directions (see Ground)

// The rim of a sphere in the ground's ray tests: a ray that passes within (1 - kRim) r of the
// centre is blocked, one that passes beyond (1 + kRim) r is not, and between the two the block
// falls off smoothly, so a moving point's rays cross a plant's edge without a step.
constexpr double kRim = 0.2;

// How much the spheres block the segment from `origin` along unit `dir` for `length`: 1 - the
// product of (1 - weight x coverage) over the spheres it passes (a faded plant blocks in part).
double sphereBlock(const glm::dvec3& origin, const glm::dvec3& dir, double length,
                   const std::vector<SphereOccluder>& occluders) {
    double open = 1.0;
    for (const SphereOccluder& o : occluders) {
        const glm::dvec3 d = o.centre_m - origin;
        const double outer = (1.0 + kRim) * o.radius_m;
        // The ray's nearest approach to the centre, within the segment.
        const double tc = std::clamp(glm::dot(d, dir), 0.0, length);
        const glm::dvec3 miss = d - dir * tc;
        const double q2 = glm::dot(miss, miss);
        if (q2 >= outer * outer) continue;
        const double x = std::clamp((outer - std::sqrt(q2)) / (2.0 * kRim * o.radius_m), 0.0, 1.0);
        open *= 1.0 - std::clamp(o.weight, 0.0, 1.0) * x * x * (3.0 - 2.0 * x);
        if (open <= 0.0) break;
    }
    return 1.0 - open;
}

}  // namespace

void belowTangentPlaneOut(const glm::dvec3& n, std::vector<HorizonWedge>& horizon) {
    std::size_t kept = 0;
    for (HorizonWedge& h : horizon) {
        const double phi = 0.5 * (h.azimuth0 + h.azimuth1);
        // The tangent plane's rise along (cos phi, sin phi) in (x, z).
        const double rise = -(n.x * std::cos(phi) + n.z * std::sin(phi)) / n.y;
        h.lower = std::max(h.lower, std::atan(rise));
        if (h.upper > h.lower) horizon[kept++] = h;
    }
    horizon.resize(kept);
}

GroundTerm groundTerm(const glm::dvec3& p, const NearFieldScene& scene,
                      const std::vector<SphereOccluder>& seen,
                      const std::vector<SphereOccluder>& shading, double radius_m,
                      const glm::dvec3& lightDirection, const glm::dvec3* drawnNormal) {
    GroundTerm out;
    GroundPoint foot;
    if (!scene.groundAt(p.x, p.z, foot)) return out;
    const glm::dvec3 n = foot.normal;
    // Seen only through (nearly) the ground's own normal: the region lies below its horizon.
    static const double kOwnGroundCos = std::cos(kOwnGroundDeg * kPi / 180.0);
    if (drawnNormal && glm::dot(*drawnNormal, n) > kOwnGroundCos) return out;
    const double h = glm::dot(p - glm::dvec3(p.x, foot.height_m, p.z), n);
    if (!(h > 1e-3) || !(radius_m > 0.0) || !std::isfinite(h + n.x + n.y + n.z)) return out;
    const double cosMax = h / std::sqrt(h * h + radius_m * radius_m);
    const glm::dvec3 t = glm::normalize(
        glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0)));
    const glm::dvec3 b = glm::cross(n, t);
    const double w = 2.0 * kPi * (1.0 - cosMax) / double(kGroundRings * kGroundAzimuths);
    // The terrain's shadow, once for the foot (the region is small beside a hill's shadow).
    const bool lightAbove = glm::dot(lightDirection, n) > 0.0 && lightDirection.y > 0.0;
    const double terrainLit =
        lightAbove ? scene.terrainLightVisibility(p - n * (h - 0.5), lightDirection) : 0.0;
    // Only spheres that reach below the point can stand between it and the ground, and only
    // those that reach into the ball about the foot that holds every ray to the region (of
    // radius max(h, R): the rays run from the point to the region's disc).
    const glm::dvec3 base = p - n * h;  // the foot on the tangent plane
    const double ball = std::max(h, radius_m);
    std::vector<SphereOccluder> below;
    for (const SphereOccluder& o : seen) {
        const double outer = (1.0 + kRim) * o.radius_m;
        const glm::dvec3 q = o.centre_m - base;
        if (o.centre_m.y - outer < p.y && glm::dot(q, q) < (ball + outer) * (ball + outer))
            below.push_back(o);
    }
    // The directions that meet the ground, and where.
    struct Sample {
        glm::dvec3 direction, at;
        double weight;
        GroundPoint ground;
    };
    std::vector<Sample> samples;
    samples.reserve(kGroundRings * kGroundAzimuths);
    const bool roads = scene.roadNear(base.x, base.z, radius_m);  // the samples lie within it
    double spread = 0.0;  // the samples' farthest from the foot
    for (int ring = 0; ring < kGroundRings; ++ring) {
        const double c = cosMax + (1.0 - cosMax) * (ring + 0.5) / kGroundRings;  // cos from -n
        const double sn = std::sqrt(std::max(0.0, 1.0 - c * c));
        for (int az = 0; az < kGroundAzimuths; ++az) {
            const double phi = 2.0 * kPi * (az + 0.5 + 0.5 * (ring % 2)) / kGroundAzimuths;
            const glm::dvec3 d = -n * c + (t * std::cos(phi) + b * std::sin(phi)) * sn;
            const double reach = h / c;
            // A plant in front: its cap shows there, not the ground (in part at its rim).
            const double ws = w * (1.0 - sphereBlock(p, d, reach, below));
            if (ws <= 0.0) continue;
            const glm::dvec3 x = p + d * reach;
            Sample sample{d, x, ws, {}};
            GroundPoint plane;
            plane.height_m = x.y, plane.normal = n, plane.roadNear = roads;
            if (!scene.groundAt(x.x, x.z, sample.ground, &plane)) continue;
            spread = std::max(spread, glm::length(sample.at - base));
            samples.push_back(sample);
        }
    }
    // Only spheres that pass within their outer rim of the light's line through the foot, give
    // or take the samples' spread, can shade a sample.
    std::vector<SphereOccluder> shades;
    if (terrainLit > 0.0)
        for (const SphereOccluder& o : shading) {
            const glm::dvec3 q = o.centre_m - base;
            const glm::dvec3 across = q - lightDirection * glm::dot(q, lightDirection);
            const double reach = (1.0 + kRim) * o.radius_m + spread;
            if (glm::dot(across, across) < reach * reach) shades.push_back(o);
        }
    constexpr int K = kShCoefficients;
    for (const Sample& sample : samples) {
        const double lit =
            terrainLit > 0.0
                ? terrainLit * (1.0 - sphereBlock(sample.at, lightDirection, 1e30, shades))
                : 0.0;
        const auto y = shBasis(sample.direction);
        const double ws = sample.weight;
        for (int j = 0; j < K; ++j) {
            for (int k = 0; k < K; ++k) out.hide[std::size_t(j * K + k)] -= float(ws * y[j] * y[k]);
            for (int ch = 0; ch < 3; ++ch) {
                const double shown = ws * sample.ground.albedo[ch] / kPi * y[j];
                out.show[ch][j] += float(shown);
                out.lit[ch][j] += float(shown * lit);
            }
        }
        ++out.samples;
    }
    out.normal = n;
    out.any = out.samples > 0;
    return out;
}

GroundTerm blendGroundTerms(const GroundTerm* const* terms, const double* weights, int count) {
    GroundTerm out;
    glm::dvec3 normal(0.0);
    for (int i = 0; i < count; ++i) {
        const GroundTerm& t = *terms[i];
        if (!t.any) continue;
        const float w = float(weights[i]);
        for (std::size_t j = 0; j < out.hide.size(); ++j) out.hide[j] += w * t.hide[j];
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < kShCoefficients; ++k) {
                out.show[ch][k] += w * t.show[ch][k];
                out.lit[ch][k] += w * t.lit[ch][k];
            }
        normal += weights[i] * t.normal;
        out.samples += t.samples;
        out.any = true;
    }
    const double length = glm::length(normal);
    out.normal = length > 0.0 ? normal / length : glm::dvec3(0.0, 1.0, 0.0);
    return out;
}

bool WorldNearFieldScene::groundAt(double x_m, double z_m, GroundPoint& out,
                                   const GroundPoint* plane) const {
    double road = 0.0;
    if (plane) {
        out.height_m = plane->height_m, out.normal = plane->normal;
        road = plane->roadNear ? world_.roadWeight(x_m, z_m) : 0.0;
    } else {
        out.height_m = world_.heightAndRoad(x_m, z_m, &road);
        out.normal = world_.normal(x_m, z_m);
    }
    out.albedo = glm::dvec3(
        albedo_.at(x_m, z_m, out.height_m, road, out.normal, TerrainPatch::kFinestSpacing_m));
    return std::isfinite(out.height_m);
}

bool WorldNearFieldScene::roadNear(double x_m, double z_m, double radius_m) const {
    return world_.roadWithin(x_m, z_m, radius_m);
}

double WorldNearFieldScene::terrainLightVisibility(const glm::dvec3& from,
                                                   const glm::dvec3& l) const {
    const double horizontal = std::hypot(l.x, l.z);
    if (l.y <= 0.0) return 0.0;
    if (horizontal < 1e-6) return 1.0;
    // Steps doubling from 2 m, the last at kShadowReach_m. The terrain's highest elevation
    // above the light's, seen from `from`, fades the light over kPenumbra_rad (the sun's disc
    // and then some), so a moving point meets no step.
    constexpr double kPenumbra_rad = 0.02;
    double above = -kPi;
    for (double d = 2.0;; d = std::min(2.0 * d, kShadowReach_m)) {
        const glm::dvec3 q = from + l * (d / horizontal);
        above = std::max(above, std::atan2(world_.height(q.x, q.z) - from.y, d) -
                                    std::atan2(q.y - from.y, d));
        if (d >= kShadowReach_m) break;
    }
    return std::clamp(0.5 - above / kPenumbra_rad, 0.0, 1.0);
}

double WorldNearFieldScene::sphereSkyVisibility(const glm::dvec3& c, double r) const {
    if (!(r > 0.0)) return 1.0;
    // The other spheres within reach (its own plant's too: a crown's upper tiers over its lower
    // ones, the crown over the trunk).
    std::vector<SphereOccluder> casters;
    for (const Plant& p : world_.vegetation().inDisc(c.x, c.z, kSkyReach_m))
        for (const PlantSphere& s : Vegetation::spheres(p.kind)) {
            const glm::dvec3 centre = p.position_m + double(p.scale) * s.centre_m;
            const double radius = double(p.scale) * s.radius_m;
            if (glm::length(centre - c) < 1e-6 && std::fabs(radius - r) < 1e-6) continue;  // itself
            casters.push_back({centre, radius, s.albedo, 1.0, 1.0});
        }
    if (casters.empty()) return 1.0;
    // 24 directions of the upper hemisphere (a Fibonacci spiral, equal solid angles).
    static const std::array<glm::dvec3, 24> sky = [] {
        std::array<glm::dvec3, 24> d{};
        for (std::size_t k = 0; k < d.size(); ++k) {
            const double y = 1.0 - (double(k) + 0.5) / double(d.size()), q = std::sqrt(1.0 - y * y);
            const double phi = 2.39996322972865332 * double(k);
            d[k] = {q * std::cos(phi), y, q * std::sin(phi)};
        }
        return d;
    }();
    // Nine points: the top, four 30 degrees above the equator, four 30 degrees below.
    double seen = 0.0, all = 0.0;
    for (int k = 0; k < 9; ++k) {
        const double e = k == 0 ? 0.5 * kPi : (k <= 4 ? 1.0 : -1.0) * kPi / 6.0;
        const double phi = 0.5 * kPi * (k - 1) + (k > 4 ? 0.25 * kPi : 0.0);
        const glm::dvec3 n(std::cos(e) * std::cos(phi), std::sin(e), std::cos(e) * std::sin(phi));
        const glm::dvec3 x = c + n * (r * 1.001);
        // A point inside another sphere of the plant is no surface.
        const bool inside = std::any_of(casters.begin(), casters.end(), [&](const SphereOccluder& o) {
            return glm::dot(x - o.centre_m, x - o.centre_m) < o.radius_m * o.radius_m;
        });
        if (inside) continue;
        for (const glm::dvec3& d : sky) {
            const double w = glm::dot(d, n);
            if (!(w > 0.0)) continue;
            all += w;
            seen += w * (1.0 - sphereBlock(x, d, kSkyReach_m + kPlantTop_m, casters));
        }
    }
    return all > 0.0 ? std::max(seen / all, kMinSkyVisibility) : 1.0;
}

double WorldNearFieldScene::sphereLightVisibility(const glm::dvec3& c, double r,
                                                  const glm::dvec3& l) const {
    const double horizontal = std::hypot(l.x, l.z);
    if (!(l.y > 0.0) || !(r > 0.0)) return 0.0;
    // The terrain's shadow is wide beside a plant: once, at the point facing the light.
    const double terrain = terrainLightVisibility(c + l * r, l);
    if (terrain <= 0.0) return 0.0;
    // The plants whose spheres may stand in the light's way: those within a crown's reach of
    // its line's foot, out to where the line is kPlantTop_m above the ground here.
    std::vector<SphereOccluder> casters;
    if (horizontal > 1e-6) {
        const glm::dvec2 along(l.x / horizontal, l.z / horizontal);
        const double rise = l.y / horizontal;  // per metre along
        const double above = c.y + r - world_.height(c.x, c.z);
        const double reach = std::clamp((kPlantTop_m - above) / rise, 0.0, kMaxCasterReach_m);
        constexpr double kStep = 16.0;
        std::vector<Plant> plants;
        for (double s = 0.0;; s = std::min(s + kStep, reach)) {
            for (const Plant& p : world_.vegetation().inDisc(c.x + along.x * s, c.z + along.y * s, kStep)) {
                const bool seen = std::any_of(plants.begin(), plants.end(), [&](const Plant& q) {
                    return q.position_m == p.position_m;
                });
                if (!seen) plants.push_back(p);
            }
            if (s >= reach) break;
        }
        for (const Plant& p : plants)
            for (const PlantSphere& s : Vegetation::spheres(p.kind)) {
                const glm::dvec3 centre = p.position_m + double(p.scale) * s.centre_m;
                const double radius = double(p.scale) * s.radius_m;
                if (glm::length(centre - c) < 1e-6 && std::fabs(radius - r) < 1e-6) continue;  // itself
                casters.push_back({centre, radius, s.albedo, 1.0, 1.0});
            }
    }
    // Five points of the lit side: facing the light (weight 1) and 60 degrees from it (cos 60
    // each).
    const glm::dvec3 t = glm::normalize(
        glm::cross(l, std::abs(l.y) < 0.9 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(1.0, 0.0, 0.0)));
    const glm::dvec3 b = glm::cross(l, t);
    double lit = 1.0 - sphereBlock(c + l * r, l, 1e30, casters);
    const double s60 = std::sqrt(3.0) / 2.0;
    for (int k = 0; k < 4; ++k) {
        const double phi = 0.5 * kPi * k;
        const glm::dvec3 d = 0.5 * l + s60 * (std::cos(phi) * t + std::sin(phi) * b);
        lit += 0.5 * (1.0 - sphereBlock(c + d * r, l, 1e30, casters));
    }
    return terrain * lit / 3.0;
}

}  // namespace amb
