// BounceField.cpp — the bounce lattice: lay-out, the bounce iteration, interpolation.
#include "lighting/BounceField.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <set>
#include <stdexcept>
#include <utility>

#include "lighting/Metrics.h"
#include "world/Error.h"

namespace amb {

void checkBounceSettings(const BounceSettings& s) {
    if (!(s.spacing_m >= 8.0 && s.spacing_m <= 4096.0))
        throw InputError("--bounce-spacing", "expected 8 to 4096 m");
    if (!(s.reach_m >= 0.0 && s.reach_m <= 20000.0))
        throw InputError("--bounce-reach", "expected 0 to 20000 m");
    if (s.faceSize < 4 || s.faceSize > 256) throw InputError("--bounce-face", "expected 4 to 256");
    if (!(s.tolerance > 0.0 && s.tolerance < 1.0))
        throw InputError("bounce tolerance", "expected (0, 1)");
    if (s.maxBounces < 1 || s.maxBounces > 64) throw InputError("bounce passes", "expected 1 to 64");
    if (!(s.epoch_h > 0.0 && s.epoch_h <= 24.0))
        throw InputError("bounce epoch", "expected (0, 24] hours");
    if (!(s.canopy_m == 0.0 || (s.canopy_m >= 1.0 && s.canopy_m <= 100.0)))
        throw InputError("--bounce-canopy", "expected 0 (one layer) or 1 to 100 m");
}

std::string describeBounceSettings(const BounceSettings& s) {
    char text[160];
    std::snprintf(text, sizeof text, "spacing=%g reach=%g face=%d tolerance=%g passes=%d epoch=%g",
                  s.spacing_m, s.reach_m, s.faceSize, s.tolerance, s.maxBounces, s.epoch_h);
    // One layer keeps the key it always had (caches made before the layers stay valid).
    if (s.canopy_m > 0.0) return std::string(text) + " canopy=" + std::to_string(s.canopy_m);
    return text;
}

ReferenceLight parseReferenceLight(const std::string& text, const std::string& where) {
    if (text == "bounce") return ReferenceLight::Bounce;
    if (text == "hemisphere") return ReferenceLight::Hemisphere;
    throw InputError(where, "expected bounce or hemisphere, got '" + text + "'");
}

const char* toString(ReferenceLight light) {
    return light == ReferenceLight::Bounce ? "bounce" : "hemisphere";
}

// ---- BounceField -----------------------------------------------------------------------------

BounceField::BounceField(const BounceSettings& settings) : settings_(settings) {
    checkBounceSettings(settings_);
}

void BounceField::layOut(const std::vector<glm::dvec2>& path,
                         const std::function<glm::dvec3(double, double)>& place) {
    const double s = settings_.spacing_m, reach = settings_.reach_m;
    std::set<std::pair<std::int64_t, std::int64_t>> nodes;
    for (const glm::dvec2& p : path) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
        const auto i0 = std::int64_t(std::ceil((p.x - reach) / s));
        const auto i1 = std::int64_t(std::floor((p.x + reach) / s));
        const auto k0 = std::int64_t(std::ceil((p.y - reach) / s));
        const auto k1 = std::int64_t(std::floor((p.y + reach) / s));
        for (std::int64_t i = i0; i <= i1; ++i)
            for (std::int64_t k = k0; k <= k1; ++k)
                if (std::hypot(double(i) * s - p.x, double(k) * s - p.y) <= reach)
                    nodes.insert({i, k});
    }
    // A path shorter than the reach from every node (reach below half a spacing) still gets
    // the node nearest to its start: the field is never empty.
    if (nodes.empty() && !path.empty())
        nodes.insert({std::int64_t(std::llround(path.front().x / s)),
                      std::int64_t(std::llround(path.front().y / s))});
    points_.clear();
    for (const auto& [i, k] : nodes) {
        Point pt;
        pt.i = i, pt.k = k;
        pt.position_m = place(double(i) * s, double(k) * s);
        points_.push_back(pt);
    }
    layerSize_ = points_.size();
    if (settings_.canopy_m > 0.0)
        for (std::size_t n = 0; n < layerSize_; ++n) {
            Point up = points_[n];
            up.position_m.y += settings_.canopy_m;
            points_.push_back(up);
        }
    fillGrid();
}

void BounceField::fillGrid() {
    nearest_.clear();
    width_ = height_ = 0;
    if (points_.empty()) return;
    std::int64_t i1 = points_[0].i, k1 = points_[0].k;
    i0_ = i1, k0_ = k1;
    for (const Point& p : points_) {
        i0_ = std::min(i0_, p.i), i1 = std::max(i1, p.i);
        k0_ = std::min(k0_, p.k), k1 = std::max(k1, p.k);
    }
    if (i1 - i0_ >= 4096 || k1 - k0_ >= 4096)
        throw InputError("--bounce-spacing", "the path's bounce lattice spans over 4096 nodes");
    width_ = int(i1 - i0_ + 1), height_ = int(k1 - k0_ + 1);
    nearest_.assign(std::size_t(width_) * std::size_t(height_), -1);
    // Multi-source breadth-first fill over the 8-neighbourhood: each empty node takes the
    // point nearest in chessboard distance (the first reached on ties, points in lattice order).
    std::deque<int> queue;
    for (std::size_t n = 0; n < layerSize_; ++n) {
        const int cell = int((points_[n].k - k0_) * width_ + (points_[n].i - i0_));
        nearest_[std::size_t(cell)] = int(n);
        queue.push_back(cell);
    }
    while (!queue.empty()) {
        const int cell = queue.front();
        queue.pop_front();
        const int ci = cell % width_, ck = cell / width_;
        for (int dk = -1; dk <= 1; ++dk)
            for (int di = -1; di <= 1; ++di) {
                const int ni = ci + di, nk = ck + dk;
                if (ni < 0 || nk < 0 || ni >= width_ || nk >= height_) continue;
                const int next = nk * width_ + ni;
                if (nearest_[std::size_t(next)] >= 0) continue;
                nearest_[std::size_t(next)] = nearest_[std::size_t(cell)];
                queue.push_back(next);
            }
    }
}

template <typename T, typename Get>
T BounceField::bilinear(const glm::dvec3& position_m, std::size_t offset, Get get) const {
    const double s = settings_.spacing_m;
    const double u = std::clamp(position_m.x / s - double(i0_), 0.0, double(width_ - 1));
    const double v = std::clamp(position_m.z / s - double(k0_), 0.0, double(height_ - 1));
    const int a = std::min(int(u), std::max(width_ - 2, 0));
    const int b = std::min(int(v), std::max(height_ - 2, 0));
    const int a1 = std::min(a + 1, width_ - 1), b1 = std::min(b + 1, height_ - 1);
    const float fu = float(u - a), fv = float(v - b);
    const auto at = [&](int i, int k) {
        return get(points_[offset + std::size_t(nearest_[std::size_t(k * width_ + i)])]);
    };
    return at(a, b) * ((1.0f - fu) * (1.0f - fv)) + at(a1, b) * (fu * (1.0f - fv)) +
           at(a, b1) * ((1.0f - fu) * fv) + at(a1, b1) * (fu * fv);
}

ShRgb BounceField::shAt(const glm::dvec3& position_m) const {
    if (nearest_.empty()) return ShRgb{};
    if (!std::isfinite(position_m.x) || !std::isfinite(position_m.z)) return ShRgb{};
    const auto sh = [](const Point& p) { return p.sh; };
    const ShRgb low = bilinear<ShRgb>(position_m, 0, sh);
    if (points_.size() == layerSize_) return low;
    const auto height = [](const Point& p) { return float(p.position_m.y); };
    const double yLow = bilinear<float>(position_m, 0, height);
    const double yHigh = bilinear<float>(position_m, layerSize_, height);
    const double t = std::isfinite(position_m.y) && yHigh > yLow
                         ? std::clamp((position_m.y - yLow) / (yHigh - yLow), 0.0, 1.0)
                         : 0.0;
    if (t <= 0.0) return low;
    return low * float(1.0 - t) + bilinear<ShRgb>(position_m, layerSize_, sh) * float(t);
}

const BounceSolve& BounceField::solve(CubeCapture& capture, double timeOfDay_h) {
    const auto t0 = std::chrono::steady_clock::now();
    solve_ = BounceSolve{};
    solve_.timeOfDay_h = timeOfDay_h;
    solve_.points = points_.size();
    for (Point& p : points_) p.sh = ShRgb{};  // pass 1: no ambient
    capture.setSurfaceLight(this);
    std::vector<ShRgb> next(points_.size());
    try {
        for (int pass = 1; pass <= settings_.maxBounces; ++pass) {
            // Jacobi: every capture of a pass reads the previous pass's field.
            for (std::size_t n = 0; n < points_.size(); ++n) {
                next[n] = oracleShAt(capture, points_[n].position_m, timeOfDay_h);
                ++solve_.captures;
                for (const glm::vec3& c : next[n].c)
                    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
                        throw std::runtime_error("bounce field: a capture gave non-finite SH");
            }
            double diff2 = 0.0, norm2 = 0.0, maxPoint = 0.0;
            for (std::size_t n = 0; n < points_.size(); ++n) {
                const double d = irradianceDistance(next[n], points_[n].sh);
                const double e = irradianceNorm(next[n]);
                diff2 += d * d, norm2 += e * e;
                maxPoint = std::max(maxPoint, e > 0.0 ? d / e : (d > 0.0 ? 1.0 : 0.0));
                points_[n].sh = next[n];
            }
            const double change = norm2 > 0.0 ? std::sqrt(diff2 / norm2) : 0.0;
            solve_.changes.push_back(change);
            solve_.maxPointChanges.push_back(maxPoint);
            solve_.bounces = pass;
            if (change < settings_.tolerance) {
                solve_.converged = true;
                break;
            }
        }
    } catch (...) {
        capture.setSurfaceLight(nullptr);
        throw;
    }
    capture.setSurfaceLight(nullptr);
    solve_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return solve_;
}

// ---- BounceLitCapture ------------------------------------------------------------------------

BounceLitCapture::BounceLitCapture(CubeCapture& reference, CubeCapture& lattice,
                                   const BounceSettings& settings, std::vector<glm::dvec2> path,
                                   std::function<glm::dvec3(double, double)> place,
                                   double timeOrigin_h)
    : reference_(reference),
      lattice_(lattice),
      settings_(settings),
      path_(std::move(path)),
      place_(std::move(place)),
      timeOrigin_h_(timeOrigin_h) {
    checkBounceSettings(settings_);
}

const BounceField& BounceLitCapture::field(double timeOfDay_h) {
    const auto epoch = std::int64_t(std::floor((timeOfDay_h - timeOrigin_h_) / settings_.epoch_h));
    auto it = fields_.find(epoch);
    if (it == fields_.end()) {
        auto f = std::make_unique<BounceField>(settings_);
        f->layOut(path_, place_);
        double t = std::fmod(timeOrigin_h_ + double(epoch) * settings_.epoch_h, 24.0);
        if (t < 0.0) t += 24.0;
        f->solve(lattice_, t);
        it = fields_.emplace(epoch, std::move(f)).first;
        order_.push_back(epoch);
    }
    return *it->second;
}

CubeCaptureStats BounceLitCapture::capture(const glm::dvec3& position_m, double timeOfDay_h,
                                           CubeFaceMask faces, std::vector<float>& cube) {
    const BounceField& f = field(timeOfDay_h);
    reference_.setSurfaceLight(&f);
    const CubeCaptureStats s = reference_.capture(position_m, timeOfDay_h, faces, cube);
    reference_.setSurfaceLight(nullptr);
    return s;
}

std::vector<BounceSolve> BounceLitCapture::solves() const {
    std::vector<BounceSolve> out;
    for (std::int64_t e : order_) out.push_back(fields_.at(e)->lastSolve());
    return out;
}

}  // namespace amb
