// CameraPath.cpp — drive, fly and static camera paths (see CameraPath.h).
//
// [SECTION] Index
//   Checks of the settings
//   Polyline walking with exact chords
//   Drive: eye line over the road, curve speed profile
//   Fly: turns at waypoints, smoothed flight level above the terrain, procedural plans
//   Static
#include "world/CameraPath.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {

namespace {

// ---- Checks of the settings -----------------------------------------------------------------

constexpr double kMaxSamples = 2.0e7;

void require(bool ok, const std::string& where, const std::string& what) {
    if (!ok) throw InputError(where, what);
}

std::string str(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Number of samples at t = 0, step, 2 step, ... <= duration.
std::size_t sampleCount(const std::string& where, double duration_s, double step_s) {
    require(std::isfinite(step_s) && step_s > 0.0, where + " step_s",
            "expected a positive finite step, got " + str(step_s));
    require(std::isfinite(duration_s) && duration_s >= 0.0, where + " duration_s",
            "expected a finite duration >= 0, got " + str(duration_s));
    const double n = std::floor(duration_s / step_s + 1e-9) + 1.0;
    require(n <= kMaxSamples, where + " duration_s",
            "expected at most " + str(kMaxSamples) + " samples, got " + str(n));
    return std::size_t(n);
}

void requireSpeed(const std::string& where, double speed_mps) {
    require(std::isfinite(speed_mps) && speed_mps > 0.0 && speed_mps < 1.0e5, where + " speed_mps",
            "expected a speed in (0, 1e5) m/s, got " + str(speed_mps));
}

// Up: world +Y made orthogonal to forward (forward straight up or down falls back to -Z/+Z).
CameraSample orient(double time_s, const glm::dvec3& position, glm::dvec3 forward) {
    CameraSample s;
    s.time_s = time_s;
    s.position_m = position;
    const double len = glm::length(forward);
    forward = len > 0.0 ? forward / len : glm::dvec3(0.0, 0.0, -1.0);
    glm::dvec3 up = glm::dvec3(0.0, 1.0, 0.0) - forward.y * forward;
    if (glm::length(up) < 1e-6) up = glm::dvec3(0.0, 0.0, forward.y > 0.0 ? 1.0 : -1.0);
    s.forward = forward;
    s.up = glm::normalize(up);
    return s;
}

// ---- Polyline walking with exact chords -----------------------------------------------------

struct Polyline {
    std::vector<glm::dvec3> p;
    std::vector<double> s;  // cumulative 3-D arc length at the vertices

    void finish() {
        s.assign(p.size(), 0.0);
        for (std::size_t i = 1; i < p.size(); ++i) s[i] = s[i - 1] + glm::length(p[i] - p[i - 1]);
    }
    double length() const { return s.empty() ? 0.0 : s.back(); }
    std::size_t segmentAt(double arc) const {
        const auto it = std::upper_bound(s.begin(), s.end(), arc);
        const std::size_t i = it == s.begin() ? 0 : std::size_t(it - s.begin()) - 1;
        return std::min(i, p.size() - 2);
    }
    glm::dvec3 at(double arc) const {
        arc = std::clamp(arc, 0.0, length());
        const std::size_t i = segmentAt(arc);
        const double len = s[i + 1] - s[i];
        return len > 0.0 ? glm::mix(p[i], p[i + 1], (arc - s[i]) / len) : p[i];
    }
    glm::dvec3 direction(std::size_t segment) const {
        for (std::size_t i = std::min(segment, p.size() - 2) + 1; i-- > 0;) {
            const glm::dvec3 d = p[i + 1] - p[i];
            if (glm::length(d) > 0.0) return glm::normalize(d);
        }
        return {0.0, 0.0, -1.0};
    }
};

// A point moving along a polyline by chords of a given length: the next position is the first
// point after the current one, along the line, at exactly that straight distance.
struct Walker {
    const Polyline* line = nullptr;
    std::size_t seg = 0;
    glm::dvec3 pos{0.0};

    Walker(const Polyline& l, double arc) : line(&l) {
        seg = l.segmentAt(std::clamp(arc, 0.0, l.length()));
        pos = l.at(arc);
    }
    double arc() const { return line->s[seg] + glm::length(pos - line->p[seg]); }
    // False if the line ends less than `chord` away; the walker does not move then.
    bool advance(double chord) {
        const double c2 = chord * chord;
        for (std::size_t k = seg; k + 1 < line->p.size(); ++k) {
            const glm::dvec3 a = k == seg ? pos : line->p[k];
            const glm::dvec3 b = line->p[k + 1];
            if (glm::dot(b - pos, b - pos) < c2) continue;
            // |a + t (b - a) - pos| = chord has one root in [0, 1]: |a - pos| < chord <= |b - pos|.
            const glm::dvec3 d = b - a, f = a - pos;
            const double A = glm::dot(d, d), B = glm::dot(f, d), C = glm::dot(f, f) - c2;
            const double t = (-B + std::sqrt(std::max(B * B - A * C, 0.0))) / A;
            pos = a + std::clamp(t, 0.0, 1.0) * d;
            seg = k;
            return true;
        }
        return false;
    }
    // View direction towards the point `ahead_m` further along the line.
    glm::dvec3 lookDirection(double ahead_m) const {
        const glm::dvec3 target = line->at(arc() + ahead_m);
        const glm::dvec3 d = target - pos;
        return glm::length(d) > 1e-6 ? glm::normalize(d) : line->direction(seg);
    }
};

// Moving average over +-w samples, ends padded with the end values (keeps a Lipschitz bound).
std::vector<double> movingAverage(const std::vector<double>& v, int w) {
    const long n = long(v.size());
    std::vector<double> prefix(v.size() + 1, 0.0);
    for (long i = 0; i < n; ++i)
        prefix[std::size_t(i + 1)] = prefix[std::size_t(i)] + v[std::size_t(i)];
    std::vector<double> out(v.size());
    for (long i = 0; i < n; ++i) {
        const long lo = i - w, hi = i + w;
        const long clo = std::max(lo, 0L), chi = std::min(hi, n - 1);
        double sum = prefix[std::size_t(chi + 1)] - prefix[std::size_t(clo)];
        sum += double(clo - lo) * v.front() + double(hi - chi) * v.back();
        out[std::size_t(i)] = sum / double(2 * w + 1);
    }
    return out;
}

}  // namespace

// ---- Drive ----------------------------------------------------------------------------------

std::vector<CameraSample> makeDrivePath(const World& world, const DriveSettings& settings) {
    const std::size_t count = sampleCount("drive", settings.duration_s, settings.step_s);
    requireSpeed("drive", settings.speed_mps);
    const Road* road = world.roads().find(settings.road);
    if (!road) {
        std::string names;
        for (const Road& r : world.roads().roads()) names += (names.empty() ? "" : ", ") + r.name;
        throw InputError("drive road",
                         "no road named '" + settings.road + "' (roads: " + names + ")");
    }
    require(road->centreline.size() >= 2, "drive road", "road '" + road->name + "' is empty");
    require(
        std::isfinite(settings.laneOffset_m) && std::abs(settings.laneOffset_m) < road->halfWidth_m,
        "drive laneOffset_m",
        "expected |offset| < the road's half width " + str(road->halfWidth_m) + " m");
    require(std::isfinite(settings.eyeHeight_m) && std::abs(settings.eyeHeight_m) < 1e4,
            "drive eyeHeight_m", "expected a finite eye height");
    require(std::isfinite(settings.lookAhead_m) && settings.lookAhead_m >= 0.0, "drive lookAhead_m",
            "expected a finite look-ahead >= 0");
    require(std::isfinite(settings.maxLateralAccel_mps2) && settings.maxLateralAccel_mps2 >= 0.0,
            "drive maxLateralAccel_mps2", "expected a finite value >= 0 (0 = constant speed)");
    require(std::isfinite(settings.startDistance_m) && settings.startDistance_m >= 0.0 &&
                settings.startDistance_m < road->length_m,
            "drive startDistance_m",
            "expected a distance in [0, " + str(road->length_m) + ") m along '" + road->name + "'");

    // Eye line: the centreline in the direction of travel, offset into the lane, raised.
    std::vector<glm::dvec3> centre = road->centreline;
    if (settings.reverse) std::reverse(centre.begin(), centre.end());
    const std::size_t n = centre.size();
    Polyline eye;
    eye.p.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 t = centre[std::min(i + 1, n - 1)] - centre[i == 0 ? 0 : i - 1];
        glm::dvec3 right(-t.z, 0.0, t.x);  // forward x up
        const double len = glm::length(right);
        right = len > 0.0 ? right / len : glm::dvec3(0.0);
        eye.p[i] =
            centre[i] + settings.laneOffset_m * right + glm::dvec3(0.0, settings.eyeHeight_m, 0.0);
    }
    eye.finish();

    // Speed per eye-line vertex: the cruise speed, or the curve limit sqrt(a_lat / curvature)
    // with speed changes bounded by maxSpeedChange (forward and backward passes).
    std::vector<double> speed(n, settings.speed_mps);
    if (settings.maxLateralAccel_mps2 > 0.0 && n >= 3) {
        std::vector<double> curvature(n, 0.0);
        for (std::size_t i = 1; i + 1 < n; ++i) {
            const glm::dvec3 a = eye.p[i] - eye.p[i - 1], b = eye.p[i + 1] - eye.p[i];
            const double la = std::hypot(a.x, a.z), lb = std::hypot(b.x, b.z);
            if (la <= 0.0 || lb <= 0.0) continue;
            const double angle = std::atan2(std::abs(a.x * b.z - a.z * b.x), a.x * b.x + a.z * b.z);
            curvature[i] = angle / (0.5 * (la + lb));
        }
        curvature = movingAverage(curvature, 5);
        for (std::size_t i = 0; i < n; ++i)
            if (curvature[i] > 0.0)
                speed[i] =
                    std::min(speed[i], std::sqrt(settings.maxLateralAccel_mps2 / curvature[i]));
        const double acc = std::max(settings.maxSpeedChange_mps2, 1e-3);
        for (std::size_t i = 1; i < n; ++i)
            speed[i] = std::min(speed[i], std::sqrt(speed[i - 1] * speed[i - 1] +
                                                    2.0 * acc * (eye.s[i] - eye.s[i - 1])));
        for (std::size_t i = n - 1; i-- > 0;)
            speed[i] = std::min(speed[i], std::sqrt(speed[i + 1] * speed[i + 1] +
                                                    2.0 * acc * (eye.s[i + 1] - eye.s[i])));
        for (double& v : speed) v = std::max(v, std::min(1.0, settings.speed_mps));
    }
    auto speedAt = [&](const Walker& w) {
        const std::size_t i = w.seg;
        const double len = eye.s[i + 1] - eye.s[i];
        const double t = len > 0.0 ? std::clamp((w.arc() - eye.s[i]) / len, 0.0, 1.0) : 0.0;
        return speed[i] + t * (speed[i + 1] - speed[i]);
    };

    // The start: startDistance_m of centreline arc length, mapped to the eye line by vertex.
    const double u = settings.startDistance_m / road->length_m * double(n - 1);
    const std::size_t i0 = std::min<std::size_t>(std::size_t(u), n - 2);
    Walker walker(eye, eye.s[i0] + (u - double(i0)) * (eye.s[i0 + 1] - eye.s[i0]));

    std::vector<CameraSample> samples;
    samples.reserve(count);
    for (std::size_t k = 0; k < count; ++k) {
        if (k > 0 && !walker.advance(speedAt(walker) * settings.step_s)) {
            throw InputError("drive duration_s", "road '" + road->name + "' ends after " +
                                                     str(settings.step_s * double(k - 1)) +
                                                     " s; shorten the drive or start earlier");
        }
        samples.push_back(orient(double(k) * settings.step_s, walker.pos,
                                 walker.lookDirection(settings.lookAhead_m)));
    }
    return samples;
}

// ---- Fly ------------------------------------------------------------------------------------

double FlightPlan::length_m() const {
    double total = 0.0;
    for (const auto& leg : legs)
        for (std::size_t i = 1; i < leg.size(); ++i) total += glm::length(leg[i] - leg[i - 1]);
    return total;
}

namespace {

// Ground track of one leg, a vertex every ~spacing_m: straight pieces joined by circular arcs
// tangent to both pieces at each interior waypoint (radius reduced where the pieces are short).
std::vector<glm::dvec2> groundTrack(const std::vector<glm::dvec2>& waypoints, double radius_m,
                                    double spacing_m) {
    std::vector<glm::dvec2> w;
    for (const glm::dvec2& p : waypoints)
        if (w.empty() || glm::length(p - w.back()) > 1e-6) w.push_back(p);
    std::vector<glm::dvec2> out;
    if (w.size() < 2) return w;
    auto line = [&](const glm::dvec2& a, const glm::dvec2& b) {  // appends (a, b]
        const int steps = std::max(1, int(std::ceil(glm::length(b - a) / spacing_m)));
        for (int k = 1; k <= steps; ++k) out.push_back(glm::mix(a, b, double(k) / steps));
    };
    out.push_back(w.front());
    glm::dvec2 from = w.front();
    for (std::size_t i = 1; i + 1 < w.size(); ++i) {
        const glm::dvec2 din = glm::normalize(w[i] - w[i - 1]);
        const glm::dvec2 dout = glm::normalize(w[i + 1] - w[i]);
        const double turn = std::atan2(din.x * dout.y - din.y * dout.x, glm::dot(din, dout));
        const double half = 0.5 * std::abs(turn);
        if (half < 1e-4 || half > 0.5 * kPi - 1e-3) continue;  // straight on, or a U-turn point
        double tangent = radius_m * std::tan(half);
        tangent = std::min(
            {tangent, 0.5 * glm::length(w[i] - w[i - 1]), 0.5 * glm::length(w[i + 1] - w[i])});
        const double r = tangent / std::tan(half);
        const glm::dvec2 a = w[i] - tangent * din, b = w[i] + tangent * dout;
        line(from, a);
        // Centre on the inside of the turn; sweep `turn` radians from a to b.
        const double side = turn > 0.0 ? 1.0 : -1.0;
        const glm::dvec2 normal = side * glm::dvec2(-din.y, din.x);
        const glm::dvec2 c = a + r * normal;
        const glm::dvec2 ra = a - c;
        const int steps = std::max(2, int(std::ceil(r * std::abs(turn) / spacing_m)));
        for (int k = 1; k <= steps; ++k) {
            const double ang = turn * double(k) / steps;
            const double cs = std::cos(ang), sn = std::sin(ang);
            out.push_back(c + glm::dvec2(cs * ra.x - sn * ra.y, sn * ra.x + cs * ra.y));
        }
        from = b;
    }
    line(from, w.back());
    return out;
}

// Flight level over a ground track: terrain + altitude, then a running maximum over the
// smoothing window (anticipate hills), the smallest maxClimb-Lipschitz majorant (bounded climb),
// and a moving average over the window. Each step keeps y >= terrain + altitude at the vertices
// (every average window of the running maximum contains the vertex itself).
Polyline flightLine(const World& world, const std::vector<glm::dvec2>& track, const FlySettings& s,
                    double spacing_m) {
    const std::size_t n = track.size();
    const double above = std::max(s.altitude_m, s.clearance_m + 1.0);
    std::vector<double> f(n);
    for (std::size_t i = 0; i < n; ++i) f[i] = world.height(track[i].x, track[i].y) + above;
    const int w = std::max(1, int(std::lround(0.5 * s.smoothing_m / spacing_m)));
    std::vector<double> m(n);
    for (std::size_t i = 0; i < n; ++i) {
        double v = -std::numeric_limits<double>::infinity();
        const std::size_t lo = i >= std::size_t(w) ? i - std::size_t(w) : 0;
        for (std::size_t j = lo; j <= std::min(n - 1, i + std::size_t(w)); ++j)
            v = std::max(v, f[j]);
        m[i] = v;
    }
    std::vector<double> dist(n, 0.0);
    for (std::size_t i = 1; i < n; ++i)
        dist[i] = dist[i - 1] + glm::length(track[i] - track[i - 1]);
    for (std::size_t i = 1; i < n; ++i)
        m[i] = std::max(m[i], m[i - 1] - s.maxClimb * (dist[i] - dist[i - 1]));
    for (std::size_t i = n - 1; i-- > 0;)
        m[i] = std::max(m[i], m[i + 1] - s.maxClimb * (dist[i + 1] - dist[i]));
    const std::vector<double> y = movingAverage(m, w);
    Polyline line;
    line.p.resize(n);
    for (std::size_t i = 0; i < n; ++i) line.p[i] = {track[i].x, std::max(y[i], f[i]), track[i].y};
    line.finish();
    return line;
}

}  // namespace

std::vector<CameraSample> makeFlyPath(const World& world, const FlySettings& settings) {
    const std::size_t count = sampleCount("fly", settings.duration_s, settings.step_s);
    requireSpeed("fly", settings.speed_mps);
    require(std::isfinite(settings.clearance_m) && settings.clearance_m >= 0.0 &&
                std::isfinite(settings.altitude_m) && settings.altitude_m >= settings.clearance_m &&
                settings.altitude_m < 1e5,
            "fly altitude_m", "expected 0 <= clearance_m <= altitude_m < 1e5");
    require(std::isfinite(settings.turnRadius_m) && settings.turnRadius_m >= 0.0,
            "fly turnRadius_m", "expected a finite radius >= 0");
    require(std::isfinite(settings.maxClimb) && settings.maxClimb > 0.0, "fly maxClimb",
            "expected a positive climb bound");
    require(std::isfinite(settings.smoothing_m) && settings.smoothing_m >= 0.0 &&
                settings.smoothing_m < 1e5,
            "fly smoothing_m", "expected a smoothing length in [0, 1e5) m");
    require(std::isfinite(settings.lookAhead_s) && settings.lookAhead_s >= 0.0, "fly lookAhead_s",
            "expected a finite look-ahead >= 0");
    require(!settings.plan.legs.empty(), "fly plan", "expected at least one leg");
    for (std::size_t l = 0; l < settings.plan.legs.size(); ++l) {
        require(settings.plan.legs[l].size() >= 2, "fly plan leg " + std::to_string(l),
                "expected at least two waypoints");
        for (const glm::dvec2& p : settings.plan.legs[l])
            require(std::isfinite(p.x) && std::isfinite(p.y) && std::abs(p.x) < 1e9 &&
                        std::abs(p.y) < 1e9,
                    "fly plan leg " + std::to_string(l), "expected finite waypoints");
    }

    constexpr double kSpacing_m = 2.0;
    const double chord = settings.speed_mps * settings.step_s;
    const double ahead = settings.speed_mps * settings.lookAhead_s;
    std::vector<CameraSample> samples;
    samples.reserve(count);
    std::size_t leg = 0;
    Polyline line =
        flightLine(world, groundTrack(settings.plan.legs[0], settings.turnRadius_m, kSpacing_m),
                   settings, kSpacing_m);
    Walker walker(line, 0.0);
    for (std::size_t k = 0; k < count; ++k) {
        bool cut = false;
        if (k > 0 && !walker.advance(chord)) {
            // The leg is over: cut to the next one (a teleport between two samples).
            if (++leg >= settings.plan.legs.size())
                throw InputError("fly plan", "the flight plan ends after " +
                                                 str(settings.step_s * double(k - 1)) +
                                                 " s; give a longer plan or a shorter duration");
            line = flightLine(
                world, groundTrack(settings.plan.legs[leg], settings.turnRadius_m, kSpacing_m),
                settings, kSpacing_m);
            walker = Walker(line, 0.0);
            cut = true;
        }
        CameraSample s =
            orient(double(k) * settings.step_s, walker.pos, walker.lookDirection(ahead));
        s.cut = cut;
        samples.push_back(s);
    }
    return samples;
}

FlightPlan makeFlightPlan(const ProceduralFlight& s) {
    require(std::isfinite(s.length_m) && s.length_m > 0.0 && s.length_m < 1e8, "flight length_m",
            "expected a length in (0, 1e8) m");
    require(std::isfinite(s.segmentMin_m) && s.segmentMin_m > 0.0 &&
                s.segmentMax_m >= s.segmentMin_m && std::isfinite(s.segmentMax_m),
            "flight segmentMin_m", "expected 0 < segmentMin_m <= segmentMax_m");
    require(s.cuts >= 0 && s.cuts < 10000, "flight cuts", "expected 0 <= cuts < 10000");
    require(std::isfinite(s.region_m) && s.region_m > 0.0, "flight region_m",
            "expected a positive region");
    std::uint64_t state = s.seed ^ 0x466C696768745061ull;  // "FlightPa"
    auto uniform = [&]() {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return double((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    };
    auto direction = [](double heading) {
        return glm::dvec2(std::sin(heading), -std::cos(heading));
    };
    // The flight stays within region_m of its start (for a start at the origin, the world's
    // road region), so a flight that starts far away stays there, cuts included.
    const glm::dvec2 centre = s.start_m;
    auto towardStart = [&centre](const glm::dvec2& p) {
        return std::atan2(-(p.x - centre.x), p.y - centre.y);
    };
    FlightPlan plan;
    plan.legs.push_back({s.start_m});
    glm::dvec2 pos = s.start_m;
    double heading = s.heading_rad, flown = 0.0;
    int cutsDone = 0;
    while (flown < s.length_m) {
        double segment = s.segmentMin_m + (s.segmentMax_m - s.segmentMin_m) * uniform();
        const double nextCut = s.length_m * double(cutsDone + 1) / double(s.cuts + 1);
        const bool cutHere = cutsDone < s.cuts && flown + segment >= nextCut;
        if (cutHere) segment = std::max(nextCut - flown, 1.0);
        pos += segment * direction(heading);
        flown += segment;
        plan.legs.back().push_back(pos);
        if (cutHere) {
            // Teleport: a jump in a random direction, then a new heading.
            ++cutsDone;
            pos += s.cutJump_m * direction(2.0 * kPi * uniform());
            pos = glm::clamp(pos, centre - glm::dvec2(s.region_m), centre + glm::dvec2(s.region_m));
            heading = towardStart(pos) + (uniform() - 0.5) * kPi;
            plan.legs.push_back({pos});
            continue;
        }
        const glm::dvec2 ahead = pos + s.segmentMax_m * direction(heading);
        if (std::abs(ahead.x - centre.x) > s.region_m || std::abs(ahead.y - centre.y) > s.region_m)
            heading = towardStart(pos) + (uniform() - 0.5) * 0.6;  // steer back inside
        else
            heading += (2.0 * uniform() - 1.0) * s.maxTurn_rad;
    }
    return plan;
}

// ---- Static ---------------------------------------------------------------------------------

std::vector<CameraSample> makeStaticPath(const World& world, const StaticSettings& s) {
    const std::size_t count = sampleCount("static", s.duration_s, s.step_s);
    require(std::isfinite(s.position_m.x) && std::isfinite(s.position_m.y) &&
                std::isfinite(s.heightAboveTerrain_m) && std::isfinite(s.heading_rad) &&
                std::isfinite(s.pitch_rad) && std::abs(s.pitch_rad) < 0.5 * kPi,
            "static", "expected a finite position, height, heading and |pitch| < pi/2");
    const glm::dvec3 position(s.position_m.x,
                              world.height(s.position_m.x, s.position_m.y) + s.heightAboveTerrain_m,
                              s.position_m.y);
    const glm::dvec3 forward(std::cos(s.pitch_rad) * std::sin(s.heading_rad), std::sin(s.pitch_rad),
                             -std::cos(s.pitch_rad) * std::cos(s.heading_rad));
    std::vector<CameraSample> samples;
    samples.reserve(count);
    for (std::size_t k = 0; k < count; ++k)
        samples.push_back(orient(double(k) * s.step_s, position, forward));
    return samples;
}

}  // namespace amb
