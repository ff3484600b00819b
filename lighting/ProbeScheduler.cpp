// ProbeScheduler.cpp — motion prediction and probe choice (see ProbeScheduler.h).
//
// [SECTION] Motion model (observe, road following, prediction)
// [SECTION] Resolution against speed
// [SECTION] Candidates and cost
#include "lighting/ProbeScheduler.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_set>

#include <glm/geometric.hpp>

#include "lighting/Metrics.h"
#include "world/Error.h"
#include "world/Road.h"

namespace amb {

namespace {

double horizontalLength(const glm::dvec3& v) {
    return std::hypot(v.x, v.z);
}
double horizontalDistance(const glm::dvec3& a, const glm::dvec3& b) {
    return std::hypot(a.x - b.x, a.z - b.z);
}
bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::uint64_t packKey(const LatticeKey& key) {
    return (std::uint64_t(std::uint32_t(key.i)) << 32 | std::uint64_t(std::uint32_t(key.k))) ^
           (std::uint64_t(key.level) << 61);
}

}  // namespace

ProbeScheduler::ProbeScheduler(const ProbeSchedulerSettings& settings) : settings_(settings) {
    AMB_CHECK(settings.pathStep_s > 0.0 && settings.horizon_s >= 0.0);
    AMB_CHECK(settings.corridorCells > 0.0 && settings.minReachSpeed_mps > 0.0);
}

// ---- Motion model -------------------------------------------------------------------------------

void ProbeScheduler::reset() {
    ++motion_;
    history_.clear();
    velocity_ = glm::dvec3(0.0);
    initialised_ = false;
    onRoad_ = false;
    roadIndex_ = -1;
}

double ProbeScheduler::speed_mps() const {
    return horizontalLength(velocity_);
}

void ProbeScheduler::observe(const glm::dvec3& position_m, const glm::dvec3& velocity_mps,
                             double now_s) {
    if (!finite(position_m) || !std::isfinite(now_s)) return;
    ++motion_;
    const double dt = initialised_ ? std::max(0.0, now_s - now_) : 0.0;
    // Velocity: as reported, else from the position history.
    glm::dvec3 measured = velocity_mps;
    if (!finite(measured)) {
        measured = velocity_;
        if (!history_.empty() && now_s > history_.front().t_s) {
            measured = (position_m - history_.front().position_m) / (now_s - history_.front().t_s);
        }
    }
    if (!initialised_) {
        velocity_ = measured;
    } else if (dt > 0.0) {
        // Inertia: first-order low-pass with time constant velocityTimeConstant_s.
        const double tau = settings_.velocityTimeConstant_s;
        const double a = tau > 0.0 ? 1.0 - std::exp(-dt / tau) : 1.0;
        velocity_ += a * (measured - velocity_);
    }
    position_ = position_m;
    now_ = now_s;
    initialised_ = true;
    history_.push_back({now_s, position_m});
    while (history_.size() > 2 && history_.front().t_s < now_s - settings_.historyLength_s) {
        history_.pop_front();
    }

    // Road following: on a road and moving along it, the prediction follows the road ahead.
    onRoad_ = false;
    if (roads_ && speed_mps() > 1.0) {
        const auto q = roads_->nearest(position_m.x, position_m.z, 50.0 + settings_.roadSnap_m);
        if (q && q->distance_m <= q->halfWidth_m + settings_.roadSnap_m) {
            const Road& road = roads_->roads()[std::size_t(q->roadIndex)];
            const glm::dvec3 t = road.tangentAt(q->along_m);
            const double tl = horizontalLength(t);
            if (tl > 0.0) {
                const double c = (t.x * velocity_.x + t.z * velocity_.z) / (tl * speed_mps());
                if (std::fabs(c) >= settings_.roadAlignment) {
                    onRoad_ = true;
                    roadIndex_ = q->roadIndex;
                    roadAlong_m_ = q->along_m;
                    roadDirection_ = c >= 0.0 ? 1.0 : -1.0;
                }
            }
        }
    }
}

glm::dvec3 ProbeScheduler::predict(double ahead_s) const {
    if (onRoad_ && roads_) {
        const Road& road = roads_->roads()[std::size_t(roadIndex_)];
        const glm::dvec3 p = road.pointAt(roadAlong_m_ + roadDirection_ * speed_mps() * ahead_s);
        return {p.x, position_.y + velocity_.y * ahead_s, p.z};
    }
    return position_ + velocity_ * ahead_s;
}

std::vector<ProbeScheduler::PathSample> ProbeScheduler::predictedPath() const {
    std::vector<PathSample> path;
    const int n = int(std::floor(settings_.horizon_s / settings_.pathStep_s + 1e-9));
    for (int s = 0; s <= n; ++s) {
        const double tau = s * settings_.pathStep_s;
        path.push_back({tau, predict(tau)});
    }
    return path;
}

// ---- Resolution against speed -------------------------------------------------------------------

int ProbeScheduler::finestLevel(const AnchorStore& store, double probesPerSecond) const {
    const int top = std::min(store.levels() - 1, settings_.maxLevel);
    if (!(probesPerSecond > 0.0)) return 0;
    // Spacing needed to keep a corridor corridorCells wide populated at this speed.
    const double needed = speed_mps() * settings_.corridorCells / probesPerSecond;
    int level = 0;
    for (int L = 0; L <= top; ++L) {
        if (store.spacing_m(L) >= needed) level = L;
    }
    return level;
}

// ---- Candidates and cost ------------------------------------------------------------------------

bool ProbeScheduler::coarseIsUniform(const AnchorStore& store, const LatticeKey& key) const {
    if (!(settings_.adaptiveThreshold > 0.0) || key.level < 1) return false;
    const int coarse = key.level - 1;
    const double s = store.spacing_m(coarse);
    const double i0 = std::floor(store.keyX_m(key) / s), k0 = std::floor(store.keyZ_m(key) / s);
    std::array<const Anchor*, 4> corner{};
    ShRgb mean;
    for (int c = 0; c < 4; ++c) {
        const LatticeKey k =
            store.canonical({coarse, std::int32_t(i0 + (c & 1)), std::int32_t(k0 + (c >> 1))});
        corner[c] = store.find(k);
        if (!corner[c] || corner[c]->expired) return false;
        mean += corner[c]->current * 0.25f;
    }
    for (const Anchor* a : corner)
        if (relativeIrradianceError(a->current, mean) > settings_.adaptiveThreshold) return false;
    return true;
}

ProbeScheduler::Candidates& ProbeScheduler::candidates(const AnchorStore& store, int finest,
                                                       double reachSpeed, int widen) const {
    if (candidates_.size() <= std::size_t(widen)) candidates_.resize(std::size_t(widen) + 1);
    Candidates& c = candidates_[std::size_t(widen)];
    if (c.motion == motion_ && c.store == &store && c.coarsestSpacing_m == store.spacing_m(0) &&
        c.levels == store.levels() && c.finest == finest && c.reachSpeed == reachSpeed &&
        c.widen == widen) {
        return c;
    }
    c = Candidates{};
    c.motion = motion_;
    c.store = &store;
    c.coarsestSpacing_m = store.spacing_m(0);
    c.levels = store.levels();
    c.finest = finest;
    c.reachSpeed = reachSpeed;
    c.widen = widen;
    c.path = predictedPath();
    const double grow = double(1 << widen);
    // Points of every level up to `finest` within the level's ring around the path.
    std::unordered_set<std::uint64_t> seen;
    for (int L = finest; L >= 0; --L) {
        const double s = store.spacing_m(L);
        const double ring =
            (L == finest ? settings_.finestRingCells : settings_.coarseRingCells) * grow * s;
        for (const PathSample& p : c.path) {
            const double i0 = std::ceil((p.position_m.x - ring) / s);
            const double i1 = std::floor((p.position_m.x + ring) / s);
            const double k0 = std::ceil((p.position_m.z - ring) / s);
            const double k1 = std::floor((p.position_m.z + ring) / s);
            for (double di = i0; di <= i1; di += 1.0) {
                for (double dk = k0; dk <= k1; dk += 1.0) {
                    const LatticeKey key = store.canonical({L, std::int32_t(di), std::int32_t(dk)});
                    const double d = std::hypot(store.keyX_m(key) - p.position_m.x,
                                                store.keyZ_m(key) - p.position_m.z);
                    if (d > ring) continue;
                    if (seen.insert(packKey(key)).second) c.keys.push_back(key);
                }
            }
        }
    }
    c.reach_s.assign(c.keys.size(), std::numeric_limits<double>::quiet_NaN());
    return c;
}

double ProbeScheduler::timeToReach(Candidates& c, std::size_t index,
                                   const AnchorStore& store) const {
    double& reach = c.reach_s[index];
    if (!std::isnan(reach)) return reach;
    const LatticeKey& key = c.keys[index];
    const glm::dvec3 x{store.keyX_m(key), 0.0, store.keyZ_m(key)};
    reach = std::numeric_limits<double>::infinity();
    for (const PathSample& p : c.path) {
        // tau grows along the path: from here on no sample comes sooner.
        if (p.tau_s >= reach) break;
        reach = std::min(reach, p.tau_s + horizontalDistance(x, p.position_m) / c.reachSpeed);
    }
    return reach;
}

std::optional<ProbeChoice> ProbeScheduler::choose(const AnchorStore& store, double probesPerSecond,
                                                  const std::vector<LatticeKey>& busy) const {
    if (!initialised_) return std::nullopt;
    const int finest = finestLevel(store, probesPerSecond);
    const double reachSpeed = std::max(speed_mps(), settings_.minReachSpeed_mps);
    const double regen = store.settings().regenerateFraction;
    std::unordered_set<std::uint64_t> busyKeys;
    for (const LatticeKey& b : busy) busyKeys.insert(packKey(store.canonical(b)));

    for (int widen = 0; widen <= settings_.maxWiden; ++widen) {
        Candidates& candidates = this->candidates(store, finest, reachSpeed, widen);
        std::optional<ProbeChoice> best;
        for (std::size_t i = 0; i < candidates.keys.size(); ++i) {
            const LatticeKey& key = candidates.keys[i];
            if (busyKeys.count(packKey(key))) continue;
            const Anchor* anchor = store.find(key);
            if (anchor && !anchor->regenerationRequested && !anchor->expired) continue;  // fresh
            if (!anchor && coarseIsUniform(store, key)) continue;
            const double reach = timeToReach(candidates, i, store);
            ProbeChoice c;
            c.key = key;
            c.timeToReach_s = reach;
            c.cost_s = reach;
            if (anchor) {
                c.refresh = true;
                const double ageFraction = anchor->age_s(store.now_s()) / anchor->lifetime_s;
                const double urgency =
                    regen < 1.0 ? std::clamp((ageFraction - regen) / (1.0 - regen), 0.0, 1.0) : 1.0;
                c.cost_s += settings_.staleBias_s * (1.0 - urgency);
            } else {
                // Coverage gap: no anchor at the neighbouring points of its level.
                bool gap = true;
                for (int a = -1; a <= 1 && gap; ++a) {
                    for (int b = -1; b <= 1 && gap; ++b) {
                        if ((a || b) && store.find({key.level, key.i + a, key.k + b})) gap = false;
                    }
                }
                if (gap) c.cost_s -= settings_.gapBonus_s;
                c.cost_s -= settings_.coarseFirst_s * store.spacing_m(key.level) /
                            candidates.coarsestSpacing_m;
            }
            const bool better = !best || c.cost_s < best->cost_s ||
                                (c.cost_s == best->cost_s && packKey(c.key) < packKey(best->key));
            if (better) best = c;
        }
        if (best) return best;
    }
    return std::nullopt;
}

}  // namespace amb
