// Road.cpp — routing, spline smoothing, grade-bounded profile and the spatial index of roads.
//
// [SECTION] Index
//   Road queries (pointAt, tangentAt), the ribbon mesh to draw
//   Routing grid and Dijkstra
//   Endpoints of the highway and the mountain road
//   Smoothing (Laplacian relaxation + cubic B-spline) and resampling
//   Grade-bounded surface profile
//   RoadNetwork: construction (with a per-settings cache), spatial hash, nearest()
#include "world/Road.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <queue>
#include <tuple>
#include <utility>

#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "world/Error.h"
#include "world/Heightfield.h"

namespace amb {

// ---- Road queries ---------------------------------------------------------------------------

namespace {

double vertexSpacing(const Road& road) {
    return road.centreline.size() > 1 ? road.length_m / double(road.centreline.size() - 1) : 1.0;
}

}  // namespace

double Road::vertexDistance_m(std::size_t i) const {
    return double(i) * vertexSpacing(*this);
}

glm::dvec3 Road::pointAt(double s_m) const {
    AMB_CHECK(!centreline.empty());
    if (centreline.size() == 1 || s_m <= 0.0) return centreline.front();
    if (s_m >= length_m) return centreline.back();
    const double u = std::clamp(s_m, 0.0, length_m) / vertexSpacing(*this);
    const std::size_t i = std::min<std::size_t>(std::size_t(u), centreline.size() - 2);
    const double t = u - double(i);
    return glm::mix(centreline[i], centreline[i + 1], t);
}

glm::dvec3 Road::tangentAt(double s_m) const {
    AMB_CHECK(centreline.size() >= 2);
    // Central-difference tangents at the vertices, interpolated linearly: continuous along s.
    const std::size_t n = centreline.size();
    auto vertexTangent = [&](std::size_t i) {
        const std::size_t a = i == 0 ? 0 : i - 1;
        const std::size_t b = std::min(i + 1, n - 1);
        return centreline[b] - centreline[a];
    };
    const double u = std::clamp(s_m, 0.0, length_m) / vertexSpacing(*this);
    const std::size_t i = std::min<std::size_t>(std::size_t(u), n - 2);
    const double t = u - double(i);
    const glm::dvec3 d = glm::mix(vertexTangent(i), vertexTangent(i + 1), t);
    return glm::normalize(d);
}

WorldMesh roadRibbon(const Road& road, std::size_t first, std::size_t last, double lift_m,
                     const glm::vec3& albedo) {
    const auto& c = road.centreline;
    AMB_CHECK(first < last && last < c.size());
    WorldMesh m;
    for (std::size_t i = first; i <= last; ++i) {
        const glm::dvec3 along = c[std::min(i + 1, c.size() - 1)] - c[i > 0 ? i - 1 : i];
        const glm::dvec3 side = glm::normalize(glm::dvec3(-along.z, 0.0, along.x));
        glm::dvec3 n = glm::normalize(glm::cross(side, along));
        if (n.y < 0.0) n = -n;
        for (int s = -1; s <= 1; s += 2) {
            glm::dvec3 p = c[i] + side * (s * road.halfWidth_m);
            p.y = c[i].y + lift_m;
            const glm::dvec3 rel = p - c[first];
            m.positions.insert(m.positions.end(), {float(rel.x), float(rel.y), float(rel.z)});
            m.normals.insert(m.normals.end(), {float(n.x), float(n.y), float(n.z)});
            m.albedo.insert(m.albedo.end(), {albedo.r, albedo.g, albedo.b});
        }
    }
    for (std::uint32_t q = 0; q < std::uint32_t(last - first); ++q) {
        const std::uint32_t l0 = 2 * q, r0 = l0 + 1, l1 = l0 + 2, r1 = l0 + 3;
        m.indices.insert(m.indices.end(), {l0, r0, l1, r0, r1, l1});
    }
    // Make every triangle face up (counter-clockwise seen from above), whichever way the side
    // vector points.
    const auto P = [&](std::uint32_t v) {
        return glm::vec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
    };
    for (std::size_t t = 0; t < m.indices.size(); t += 3) {
        const glm::vec3 n = glm::cross(P(m.indices[t + 1]) - P(m.indices[t]),
                                       P(m.indices[t + 2]) - P(m.indices[t]));
        if (n.y < 0.0f) std::swap(m.indices[t + 1], m.indices[t + 2]);
    }
    return m;
}

// ---- Routing grid and Dijkstra --------------------------------------------------------------

namespace {

std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double uniform01(std::uint64_t& state) {
    return double(splitmix64(state) >> 11) * 0x1.0p-53;
}

// A rectangular grid of natural terrain heights (a part of the routing region).
struct RouteGrid {
    int nx = 0, nz = 0;                       // nodes per side
    double originX_m = 0.0, originZ_m = 0.0;  // position of node (0, 0)
    double cell_m = 0.0;
    std::vector<double> height_m;

    int size() const { return nx * nz; }
    int index(int i, int j) const { return j * nx + i; }
    glm::dvec2 position(int node) const {
        return {originX_m + (node % nx) * cell_m, originZ_m + (node / nx) * cell_m};
    }
    int nodeAt(double x_m, double z_m) const {
        const int i = std::clamp(int(std::lround((x_m - originX_m) / cell_m)), 0, nx - 1);
        const int j = std::clamp(int(std::lround((z_m - originZ_m) / cell_m)), 0, nz - 1);
        return index(i, j);
    }
};

// Nodes every cell_m over [x0, x1] x [z0, z1], heights sampled in parallel.
RouteGrid makeRouteGrid(const Heightfield& heightfield, double cell_m, double x0, double x1,
                        double z0, double z1) {
    RouteGrid grid;
    grid.cell_m = cell_m;
    grid.nx = std::max(2, int(std::floor((x1 - x0) / cell_m)) + 1);
    grid.nz = std::max(2, int(std::floor((z1 - z0) / cell_m)) + 1);
    grid.originX_m = x0;
    grid.originZ_m = z0;
    grid.height_m.resize(std::size_t(grid.size()));
    tbb::parallel_for(0, grid.nz, [&](int j) {
        for (int i = 0; i < grid.nx; ++i) {
            const glm::dvec2 p = grid.position(grid.index(i, j));
            grid.height_m[std::size_t(grid.index(i, j))] = heightfield.broadHeight(p.x, p.y);
        }
    });
    return grid;
}

// Cost model of one road class (Road.h, step 1).
struct RouteCost {
    double slopeWeight;  // k in length * (1 + k slope^2)
    double gradeLimit;   // grades above this pay overGradeWeight * (slope / limit - 1)
    double overGradeWeight;
    double waterFactor;    // multiplies the cost of edges touching water
    double lowlandWeight;  // per 100 m above lowlandRef_m
    double lowlandRef_m;
    int maxTurnSteps;   // largest heading change per move, in steps of the 16 headings
    double turnWeight;  // extra cost per heading step turned, in cell lengths
};

// The 16 moves (axis, diagonal and knight moves: 18-27 degree heading resolution), sorted by
// heading so that neighbouring indices are neighbouring headings.
constexpr int kHeadings = 16;
constexpr int kMoves[kHeadings][2] = {{1, 0},  {2, 1},  {1, 1},  {1, 2},   {0, 1},   {-1, 2},
                                      {-1, 1}, {-2, 1}, {-1, 0}, {-2, -1}, {-1, -1}, {-1, -2},
                                      {0, -1}, {1, -2}, {1, -1}, {2, -1}};

// Dijkstra (A* when a goal is given) over (node, heading) states: a move may turn by at most
// maxTurnSteps headings, so the path has no hairpin tighter than a few cells and the spline
// through it no cusp. The first move may take any heading; any heading may arrive.
struct RouteSearch {
    std::vector<double> cost;      // per state
    std::vector<double> length_m;  // horizontal path length per state
    std::vector<std::int32_t> previous;
    int from = -1;

    // Cheapest arrival state at a node, or -1.
    std::int64_t bestState(int node) const {
        std::int64_t best = -1;
        for (int k = 0; k < kHeadings; ++k) {
            const std::int64_t s = std::int64_t(node) * kHeadings + k;
            if (std::isfinite(cost[std::size_t(s)]) &&
                (best < 0 || cost[std::size_t(s)] < cost[std::size_t(best)]))
                best = s;
        }
        return best;
    }
    std::vector<int> path(std::int64_t state) const {
        std::vector<int> nodes;
        for (; state >= 0; state = previous[std::size_t(state)])
            nodes.push_back(int(state / kHeadings));
        nodes.push_back(from);
        std::reverse(nodes.begin(), nodes.end());
        return nodes;
    }
};

RouteSearch searchRoutes(const RouteGrid& grid, const RouteCost& rc, double waterLevel_m, int from,
                         int to, double maxLength_m) {
    const std::size_t count = std::size_t(grid.size()) * kHeadings;
    RouteSearch search;
    search.from = from;
    search.cost.assign(count, std::numeric_limits<double>::infinity());
    search.length_m.assign(count, 0.0);
    search.previous.assign(count, -1);
    using Entry = std::pair<double, std::int64_t>;  // (cost + heuristic, state)
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    const double wet_m = waterLevel_m + 1.0;
    const glm::dvec2 goal = to >= 0 ? grid.position(to) : glm::dvec2(0.0);
    // Every edge costs at least its length: the straight-line distance is admissible.
    auto heuristic = [&](int node) {
        return to >= 0 ? glm::length(grid.position(node) - goal) : 0.0;
    };
    auto relaxFrom = [&](int node, int heading, double d, double len, std::int32_t state) {
        const int i = node % grid.nx, j = node / grid.nx;
        const double h0 = grid.height_m[std::size_t(node)];
        for (int k = 0; k < kHeadings; ++k) {
            int turn = 0;
            if (heading >= 0) {
                turn = std::abs(k - heading);
                turn = std::min(turn, kHeadings - turn);
                if (turn > rc.maxTurnSteps) continue;
            }
            const int ni = i + kMoves[k][0], nj = j + kMoves[k][1];
            if (ni < 0 || nj < 0 || ni >= grid.nx || nj >= grid.nz) continue;
            const int next = grid.index(ni, nj);
            const double h1 = grid.height_m[std::size_t(next)];
            const double length =
                grid.cell_m *
                std::sqrt(double(kMoves[k][0] * kMoves[k][0] + kMoves[k][1] * kMoves[k][1]));
            if (len + length > maxLength_m) continue;
            const double slope = std::abs(h1 - h0) / length;
            double factor = 1.0 + rc.slopeWeight * slope * slope;
            if (slope > rc.gradeLimit) factor += rc.overGradeWeight * (slope / rc.gradeLimit - 1.0);
            if (rc.lowlandWeight > 0.0)
                factor +=
                    rc.lowlandWeight * std::max(0.0, 0.5 * (h0 + h1) - rc.lowlandRef_m) / 100.0;
            if (std::min(h0, h1) < wet_m) factor *= rc.waterFactor;
            const double nd = d + length * factor + rc.turnWeight * grid.cell_m * turn;
            const std::size_t ns = std::size_t(next) * kHeadings + std::size_t(k);
            if (nd < search.cost[ns]) {
                search.cost[ns] = nd;
                search.length_m[ns] = len + length;
                search.previous[ns] = state;
                open.push({nd + heuristic(next), std::int64_t(ns)});
            }
        }
    };
    relaxFrom(from, -1, 0.0, 0.0, -1);
    while (!open.empty()) {
        const auto [f, state] = open.top();
        open.pop();
        const int node = int(state / kHeadings);
        const double d = search.cost[std::size_t(state)];
        if (f > d + heuristic(node) + 1e-9 * (1.0 + d)) continue;  // stale entry
        if (node == to) break;
        relaxFrom(node, int(state % kHeadings), d, search.length_m[std::size_t(state)],
                  std::int32_t(state));
    }
    return search;
}

// ---- Endpoints ------------------------------------------------------------------------------

// True if no node within `radius` cells of `node` is below the water line.
bool dryAround(const RouteGrid& grid, int node, int radius, double wet_m) {
    const int i = node % grid.nx, j = node / grid.nx;
    for (int dj = -radius; dj <= radius; ++dj)
        for (int di = -radius; di <= radius; ++di) {
            const int a = std::clamp(i + di, 0, grid.nx - 1),
                      b = std::clamp(j + dj, 0, grid.nz - 1);
            if (grid.height_m[std::size_t(grid.index(a, b))] < wet_m) return false;
        }
    return true;
}

// The largest height difference from `node` to its 8 neighbours, over the distance.
double localSlope(const RouteGrid& grid, int node) {
    const int i = node % grid.nx, j = node / grid.nx;
    double s = 0.0;
    for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
            const int a = std::clamp(i + di, 0, grid.nx - 1),
                      b = std::clamp(j + dj, 0, grid.nz - 1);
            const double len = grid.cell_m * std::sqrt(double(di * di + dj * dj));
            if (len > 0.0)
                s = std::max(s, std::abs(grid.height_m[std::size_t(grid.index(a, b))] -
                                         grid.height_m[std::size_t(node)]) /
                                    len);
        }
    return s;
}

// A highway end near one side of the grid (within a band of a sixth of its width), in the
// middle 80 % along it: the lowest node on dry land away from the shore (else just dry, else
// anything), with a seeded jitter so different seeds pick different valleys.
int lowlandEnd(const RouteGrid& grid, double waterLevel_m, int side, std::uint64_t& rng) {
    const bool alongZ = side < 2;  // west/east sides run along z
    const int across = alongZ ? grid.nx : grid.nz, along = alongZ ? grid.nz : grid.nx;
    const int band = std::max(3, across / 6);
    int best = -1;
    double bestScore = std::numeric_limits<double>::infinity();
    for (int k = along / 10; k <= along - 1 - along / 10; ++k) {
        for (int depth = 2; depth < band; ++depth) {
            const int c = (side % 2 == 0) ? depth : across - 1 - depth;
            const int node = alongZ ? grid.index(c, k) : grid.index(k, c);
            const double h = grid.height_m[std::size_t(node)];
            // Lowest wins; 40 m of height buys one band of depth (keep the highway long).
            double score = h - waterLevel_m + 40.0 * depth / band + 20.0 * uniform01(rng);
            if (h < waterLevel_m + 3.0) score += 1e6;
            if (score < bestScore && !dryAround(grid, node, 6, waterLevel_m + 1.0)) score += 1e4;
            if (score < bestScore) bestScore = score, best = node;
        }
    }
    return best;
}

// ---- Smoothing and resampling ---------------------------------------------------------------

std::vector<glm::dvec2> relax(std::vector<glm::dvec2> p, int iterations) {
    for (int it = 0; it < iterations; ++it) {
        std::vector<glm::dvec2> q = p;
        for (std::size_t i = 1; i + 1 < p.size(); ++i)
            q[i] = p[i] + 0.5 * (0.5 * (p[i - 1] + p[i + 1]) - p[i]);
        p.swap(q);
    }
    return p;
}

// Uniform cubic B-spline with the end control points tripled (the curve starts and ends there),
// evaluated densely.
std::vector<glm::dvec2> bspline(const std::vector<glm::dvec2>& control, int samplesPerSpan) {
    std::vector<glm::dvec2> c;
    c.push_back(control.front());
    c.push_back(control.front());
    c.insert(c.end(), control.begin(), control.end());
    c.push_back(control.back());
    c.push_back(control.back());
    std::vector<glm::dvec2> out;
    for (std::size_t k = 0; k + 3 < c.size(); ++k) {
        for (int s = 0; s < samplesPerSpan; ++s) {
            const double t = double(s) / samplesPerSpan, t2 = t * t, t3 = t2 * t;
            const double b0 = (1 - t) * (1 - t) * (1 - t) / 6.0;
            const double b1 = (3 * t3 - 6 * t2 + 4) / 6.0;
            const double b2 = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6.0;
            const double b3 = t3 / 6.0;
            out.push_back(b0 * c[k] + b1 * c[k + 1] + b2 * c[k + 2] + b3 * c[k + 3]);
        }
    }
    out.push_back(control.back());
    return out;
}

// Resample a polyline at `count` + 1 points evenly spaced in arc length; returns the spacing.
double resample(const std::vector<glm::dvec2>& line, double spacing_m,
                std::vector<glm::dvec2>& out) {
    std::vector<double> s(line.size(), 0.0);
    for (std::size_t i = 1; i < line.size(); ++i)
        s[i] = s[i - 1] + glm::length(line[i] - line[i - 1]);
    const double total = s.back();
    const std::size_t count = std::max<std::size_t>(1, std::size_t(std::ceil(total / spacing_m)));
    const double step = total / double(count);
    out.clear();
    std::size_t seg = 0;
    for (std::size_t k = 0; k <= count; ++k) {
        const double target = std::min(total, double(k) * step);
        while (seg + 2 < line.size() && s[seg + 1] < target) ++seg;
        const double len = s[seg + 1] - s[seg];
        const double t = len > 0.0 ? std::clamp((target - s[seg]) / len, 0.0, 1.0) : 0.0;
        out.push_back(glm::mix(line[seg], line[seg + 1], t));
    }
    return step;
}

// ---- Grade-bounded surface profile ----------------------------------------------------------

// The sequence h (evenly spaced by step_m) made g-Lipschitz in the least-deviation way (mean of
// the largest g-Lipschitz minorant and the smallest g-Lipschitz majorant), then moving-averaged
// over `window` samples each side (an average of shifted g-Lipschitz sequences is g-Lipschitz).
std::vector<double> gradeBoundedProfile(const std::vector<double>& h, double step_m, double grade,
                                        int window) {
    const std::size_t n = h.size();
    const double dMax = grade * step_m;
    std::vector<double> lo = h, hi = h;
    for (std::size_t i = 1; i < n; ++i) {
        lo[i] = std::min(lo[i], lo[i - 1] + dMax);
        hi[i] = std::max(hi[i], hi[i - 1] - dMax);
    }
    for (std::size_t i = n - 1; i-- > 0;) {
        lo[i] = std::min(lo[i], lo[i + 1] + dMax);
        hi[i] = std::max(hi[i], hi[i + 1] - dMax);
    }
    std::vector<double> mid(n);
    for (std::size_t i = 0; i < n; ++i) mid[i] = 0.5 * (lo[i] + hi[i]);
    std::vector<double> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        double sum = 0.0;
        for (int k = -window; k <= window; ++k) {
            const long j = std::clamp<long>(long(i) + k, 0, long(n) - 1);
            sum += mid[std::size_t(j)];
        }
        out[i] = sum / double(2 * window + 1);
    }
    return out;
}

struct RoadRecipe {
    std::string name;
    double halfWidth_m;
    double maxGrade;
    int relaxIterations;
    double preSmooth_m;  // moving average of the terrain profile before the grade bound
};

// `junction` (optional): the road starts exactly there (x, z) and at its height y, joining
// another road without a step.
Road buildRoad(const RoadRecipe& recipe, const RouteGrid& grid, const Heightfield& heightfield,
               double waterLevel_m, const std::vector<int>& nodes,
               const glm::dvec3* junction = nullptr) {
    std::vector<glm::dvec2> control;
    control.reserve(nodes.size());
    for (int node : nodes) control.push_back(grid.position(node));
    if (junction) control.front() = {junction->x, junction->z};
    if (control.size() < 2) control.push_back(control.front() + glm::dvec2(grid.cell_m, 0.0));
    control = relax(std::move(control), recipe.relaxIterations);
    const std::vector<glm::dvec2> dense = bspline(control, 24);
    std::vector<glm::dvec2> xz;
    const double step = resample(dense, RoadNetwork::kRoadSpacing_m, xz);

    // Terrain along the line; never below the water surface (a causeway where it must cross).
    std::vector<double> h(xz.size());
    for (std::size_t i = 0; i < xz.size(); ++i)
        h[i] = std::max(heightfield.broadHeight(xz[i].x, xz[i].y), waterLevel_m + 0.5);
    // Pre-smooth the terrain (drop bumps shorter than the road cares about), bound the grade with
    // a 10 % margin for the chord/arc difference in curves, then average again.
    const int pre = std::max(1, int(std::lround(recipe.preSmooth_m / step)));
    const std::vector<double> smoothTerrain = gradeBoundedProfile(h, step, 1e9, pre);
    std::vector<double> y =
        gradeBoundedProfile(smoothTerrain, step, 0.9 * recipe.maxGrade, std::max(1, pre / 2));
    if (junction) {
        // Ramp the start onto the junction height; the ramp adds at most 0.09 x the grade limit,
        // which the 10 % margin above leaves room for.
        const double delta = junction->y - y.front();
        const double ramp_m = std::max(30.0, std::abs(delta) / (0.09 * recipe.maxGrade));
        for (std::size_t i = 0; i < y.size(); ++i)
            y[i] += delta * std::max(0.0, 1.0 - double(i) * step / ramp_m);
    }

    Road road;
    road.name = recipe.name;
    road.halfWidth_m = recipe.halfWidth_m;
    road.maxGrade = recipe.maxGrade;
    road.length_m = step * double(xz.size() - 1);
    road.centreline.resize(xz.size());
    for (std::size_t i = 0; i < xz.size(); ++i) road.centreline[i] = {xz[i].x, y[i], xz[i].y};
    return road;
}

std::vector<Road> routeRoads(const WorldSettings& settings, const Heightfield& heightfield) {
    std::uint64_t rng = settings.seed ^ 0x526F61644E657477ull;  // "RoadNetw"
    const double water = settings.waterLevel_m;
    // Keep a margin so the smoothed road (inside the convex hull of its path) stays in the region.
    const double region = settings.roadRegion_m;
    if (!(region >= 100.0 && region <= 1.0e6))
        throw InputError("roadRegion_m", "expected a road region half size in [100, 1e6] m");
    const double half = region - std::min(100.0, 0.2 * region);
    // Grid cells: kRouteCell_m x 1.5 for the highway in the default 6 km region, scaled with the
    // region so that a search never holds more than ~200^2 nodes.
    const double highwayCell = std::max(2.0 * half / 200.0, 2.0);
    const double mountainCell = std::min(RoadNetwork::kRouteCell_m, highwayCell / 1.5);
    std::vector<Road> roads;

    // Highway: A* between lowland ends near two opposite sides (W-E or N-S by the seed) on a
    // coarser grid (it is gentle and long; this keeps routing fast).
    {
        const RouteGrid grid = makeRouteGrid(heightfield, highwayCell, -half, half, -half, half);
        const bool eastWest = (splitmix64(rng) & 1u) == 0;
        const int a = lowlandEnd(grid, water, eastWest ? 0 : 2, rng);
        const int b = lowlandEnd(grid, water, eastWest ? 1 : 3, rng);
        const double lowRef =
            std::max(std::min(grid.height_m[std::size_t(a)], grid.height_m[std::size_t(b)]), water);
        const RouteCost cost{400.0, 0.06, 40.0, 25.0, 0.5, lowRef, 1, 0.3};
        const RouteSearch search =
            searchRoutes(grid, cost, water, a, b, std::numeric_limits<double>::infinity());
        const RoadRecipe recipe{"highway", 5.0, 0.08, 6, 45.0};
        roads.push_back(
            buildRoad(recipe, grid, heightfield, water, search.path(search.bestState(b))));
    }

    // Mountain road: single-source Dijkstra from a junction on the highway's middle stretch over
    // a box around it; the end is the highest reachable, dry, not too steep node whose path is
    // between minLength and maxLength long (several km, winding where the terrain is steep).
    {
        const Road& hw = roads.front();
        const glm::dvec3 j = hw.pointAt(hw.length_m * (0.35 + 0.3 * uniform01(rng)));
        const double reach = std::min(4000.0, 0.8 * region);
        const double cell = mountainCell;
        const RouteGrid grid = makeRouteGrid(
            heightfield, cell, std::max(-half, j.x - reach), std::min(half, j.x + reach),
            std::max(-half, j.z - reach), std::min(half, j.z + reach));
        const int start = grid.nodeAt(j.x, j.z);
        const double maxLength = 2.2 * reach, minLength = 0.9 * reach;
        const RouteCost cost{60.0, 0.10, 200.0, 25.0, 0.0, 0.0, 2, 0.1};
        const RouteSearch search = searchRoutes(grid, cost, water, start, -1, maxLength);
        std::int64_t end = -1;
        double bestScore = -std::numeric_limits<double>::infinity();
        for (int node = 0; node < grid.size(); ++node) {
            const std::int64_t state = search.bestState(node);
            if (state < 0 || search.length_m[std::size_t(state)] < minLength) continue;
            const double h = grid.height_m[std::size_t(node)];
            if (h < water + 3.0 || localSlope(grid, node) > 0.25) continue;
            // Highest wins, but a cheaper (less tortuous) road is worth some height.
            const double score =
                h - 0.004 * search.cost[std::size_t(state)] + 30.0 * uniform01(rng);
            if (score > bestScore) bestScore = score, end = state;
        }
        if (end < 0) {  // flat or wet everywhere: the longest reachable path
            for (int node = 0; node < grid.size(); ++node) {
                const std::int64_t state = search.bestState(node);
                if (state >= 0 && (end < 0 || search.length_m[std::size_t(state)] >
                                                  search.length_m[std::size_t(end)]))
                    end = state;
            }
        }
        const RoadRecipe recipe{"mountain", 3.5, 0.12, 2, 24.0};
        roads.push_back(buildRoad(recipe, grid, heightfield, water, search.path(end), &j));
    }
    return roads;
}

}  // namespace

// ---- RoadNetwork ----------------------------------------------------------------------------

RoadNetwork::RoadNetwork(const WorldSettings& settings, const Heightfield& heightfield) {
    // Routing takes a noticeable fraction of a second; worlds with the same settings share it.
    using Key = std::tuple<std::uint64_t, double, double>;
    static std::mutex mutex;
    static std::map<Key, std::shared_ptr<const std::vector<Road>>> cache;
    const Key key{settings.seed, settings.waterLevel_m, settings.roadRegion_m};
    std::shared_ptr<const std::vector<Road>> routed;
    {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = cache.find(key);
        if (it != cache.end()) routed = it->second;
    }
    if (!routed) {
        routed = std::make_shared<const std::vector<Road>>(routeRoads(settings, heightfield));
        std::lock_guard<std::mutex> lock(mutex);
        if (cache.size() > 16) cache.clear();
        cache.emplace(key, routed);
    }
    roads_ = *routed;
    buildIndex();
}

std::vector<Road> RoadNetwork::route(const WorldSettings& settings,
                                     const Heightfield& heightfield) {
    return routeRoads(settings, heightfield);
}

const std::vector<Road>& RoadNetwork::roads() const {
    return roads_;
}

const Road* RoadNetwork::find(const std::string& name) const {
    for (const Road& road : roads_)
        if (road.name == name) return &road;
    return nullptr;
}

void RoadNetwork::buildIndex() {
    double minX = std::numeric_limits<double>::infinity(), minZ = minX;
    double maxX = -minX, maxZ = -minX;
    for (const Road& road : roads_)
        for (const glm::dvec3& p : road.centreline) {
            minX = std::min(minX, p.x), maxX = std::max(maxX, p.x);
            minZ = std::min(minZ, p.z), maxZ = std::max(maxZ, p.z);
        }
    if (!(minX <= maxX)) {
        indexNx_ = indexNz_ = 0;
        return;
    }
    indexMinX_m_ = minX;
    indexMinZ_m_ = minZ;
    indexNx_ = int((maxX - minX) / kIndexCell_m) + 1;
    indexNz_ = int((maxZ - minZ) / kIndexCell_m) + 1;
    auto cellRange = [&](const glm::dvec3& p, const glm::dvec3& q, int& i0, int& i1, int& j0,
                         int& j1) {
        i0 = std::clamp(int((std::min(p.x, q.x) - minX) / kIndexCell_m), 0, indexNx_ - 1);
        i1 = std::clamp(int((std::max(p.x, q.x) - minX) / kIndexCell_m), 0, indexNx_ - 1);
        j0 = std::clamp(int((std::min(p.z, q.z) - minZ) / kIndexCell_m), 0, indexNz_ - 1);
        j1 = std::clamp(int((std::max(p.z, q.z) - minZ) / kIndexCell_m), 0, indexNz_ - 1);
    };
    // Two passes (count, fill) into a compressed cell -> segments table.
    std::vector<std::uint32_t> counts(std::size_t(indexNx_) * indexNz_ + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
        for (std::size_t r = 0; r < roads_.size(); ++r) {
            const auto& line = roads_[r].centreline;
            for (std::size_t s = 0; s + 1 < line.size(); ++s) {
                int i0, i1, j0, j1;
                cellRange(line[s], line[s + 1], i0, i1, j0, j1);
                for (int j = j0; j <= j1; ++j)
                    for (int i = i0; i <= i1; ++i) {
                        const std::size_t c = std::size_t(j) * indexNx_ + i;
                        if (pass == 0)
                            ++counts[c + 1];
                        else
                            cellSegments_[counts[c]++] = {std::int32_t(r), std::int32_t(s)};
                    }
            }
        }
        if (pass == 0) {
            for (std::size_t c = 1; c < counts.size(); ++c) counts[c] += counts[c - 1];
            cellStart_ = counts;
            cellSegments_.resize(counts.back());
        }
    }
}

std::optional<RoadQuery> RoadNetwork::nearest(double x_m, double z_m, double maxDistance_m) const {
    if (indexNx_ == 0 || !(maxDistance_m >= 0.0) || !std::isfinite(x_m) || !std::isfinite(z_m))
        return std::nullopt;
    // Distance from the point to the index bounds: nothing can be nearer than that.
    const double maxX = indexMinX_m_ + indexNx_ * kIndexCell_m;
    const double maxZ = indexMinZ_m_ + indexNz_ * kIndexCell_m;
    const double dx = std::max({indexMinX_m_ - x_m, 0.0, x_m - maxX});
    const double dz = std::max({indexMinZ_m_ - z_m, 0.0, z_m - maxZ});
    if (dx * dx + dz * dz > maxDistance_m * maxDistance_m) return std::nullopt;

    // Cells overlapping the query square, clamped to the index.
    const double r = std::min(maxDistance_m, 1e7);
    const int i0 =
        std::clamp(int(std::floor((x_m - r - indexMinX_m_) / kIndexCell_m)), 0, indexNx_ - 1);
    const int i1 =
        std::clamp(int(std::floor((x_m + r - indexMinX_m_) / kIndexCell_m)), 0, indexNx_ - 1);
    const int j0 =
        std::clamp(int(std::floor((z_m - r - indexMinZ_m_) / kIndexCell_m)), 0, indexNz_ - 1);
    const int j1 =
        std::clamp(int(std::floor((z_m + r - indexMinZ_m_) / kIndexCell_m)), 0, indexNz_ - 1);

    double best2 = maxDistance_m * maxDistance_m;
    std::optional<RoadQuery> result;
    const glm::dvec2 p(x_m, z_m);
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            const std::size_t c = std::size_t(j) * indexNx_ + i;
            for (std::uint32_t k = cellStart_[c]; k < cellStart_[c + 1]; ++k) {
                const SegmentRef ref = cellSegments_[k];
                const Road& road = roads_[std::size_t(ref.road)];
                const glm::dvec3& a3 = road.centreline[std::size_t(ref.segment)];
                const glm::dvec3& b3 = road.centreline[std::size_t(ref.segment) + 1];
                const glm::dvec2 a(a3.x, a3.z), ab(b3.x - a3.x, b3.z - a3.z);
                const double len2 = glm::dot(ab, ab);
                const double t =
                    len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
                const glm::dvec2 d = p - (a + t * ab);
                const double d2 = glm::dot(d, d);
                if (d2 < best2 || (!result && d2 <= best2)) {
                    best2 = d2;
                    RoadQuery q;
                    q.distance_m = std::sqrt(d2);
                    q.surfaceHeight_m = a3.y + t * (b3.y - a3.y);
                    q.halfWidth_m = road.halfWidth_m;
                    q.roadIndex = ref.road;
                    q.along_m = (double(ref.segment) + t) * vertexSpacing(road);
                    result = q;
                }
            }
        }
    }
    return result;
}

}  // namespace amb
