// WorldCommand.cpp — `ambience world`: a top-down map of the generated world (shaded relief,
// water, vegetation density, roads, and a replay's path over it) and the heightmap as float EXR.
//
// [SECTION] Options and validation
// [SECTION] Sampling the world on the map grid (parallel)
// [SECTION] Colouring: albedo x hill shading, water by depth, forest tint
// [SECTION] Overlays: roads, replay path
// [SECTION] Writing with OpenImageIO
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>
#include <CLI/CLI.hpp>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "app/cli/CliChecks.h"
#include "app/cli/Commands.h"
#include "app/cli/OutputPaths.h"
#include "world/Error.h"
#include "world/Replay.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {

namespace {

struct WorldMapOptions {
    std::uint64_t seed = 1;
    std::string replayPath;
    std::string mapPath;
    std::string heightmapPath;
    std::string centre;   // "X,Z" in metres
    double size_m = 0.0;  // 0: 12 km, or the replay's extent
    int pixels = 1024;
};

glm::dvec2 parseCentre(const std::string& text) {
    const auto comma = text.find(',');
    if (comma == std::string::npos)
        throw InputError("--centre", "expected X,Z in metres, got '" + text + "'");
    try {
        std::size_t usedX = 0, usedZ = 0;
        const std::string xs = text.substr(0, comma), zs = text.substr(comma + 1);
        const double x = std::stod(xs, &usedX), z = std::stod(zs, &usedZ);
        if (usedX != xs.size() || usedZ != zs.size() || !std::isfinite(x) || !std::isfinite(z) ||
            std::abs(x) > 1e12 || std::abs(z) > 1e12) {
            throw std::invalid_argument("bad");
        }
        return {x, z};
    } catch (const std::logic_error&) {
        throw InputError("--centre", "expected X,Z in metres (finite numbers), got '" + text + "'");
    }
}

// Writes an image (8-bit or float) with OpenImageIO; failures are input errors on the path.
template <typename T>
void writeImage(const std::string& path, int w, int h, int channels, const std::vector<T>& pixels,
                OIIO::TypeDesc type, const std::vector<std::pair<std::string, float>>& attributes) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw InputError(path, "cannot write this image format (" + OIIO::geterror() + ")");
    OIIO::ImageSpec spec(w, h, channels, type);
    if (channels == 1) spec.channelnames = {"Y"};
    for (const auto& [name, value] : attributes) spec.attribute(name, value);
    if (!out->open(path, spec))
        throw InputError(path, "cannot open for writing: " + out->geterror());
    if (!out->write_image(type, pixels.data())) {
        throw InputError(path, "cannot write: " + out->geterror());
    }
    out->close();
}

// Draws a line of width ~2 px with a colour into an RGB8 image.
// Segments are clipped to the image (grown by the radius) first, so a line far outside a small
// map costs nothing and the step count stays within the image's size.
bool clipSegment(glm::dvec2& a, glm::dvec2& b, glm::dvec2 lo, glm::dvec2 hi) {
    double t0 = 0.0, t1 = 1.0;
    const glm::dvec2 d = b - a;
    for (int k = 0; k < 2; ++k) {
        if (d[k] == 0.0) {
            if (a[k] < lo[k] || a[k] > hi[k]) return false;
            continue;
        }
        double ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (!(t0 <= t1)) return false;
    }
    const glm::dvec2 a0 = a;
    a = a0 + d * t0;
    b = a0 + d * t1;
    return true;
}

void drawLine(std::vector<unsigned char>& img, int w, int h, glm::dvec2 a, glm::dvec2 b,
              const unsigned char colour[3], int radius) {
    const double margin = radius + 1.0;
    if (!clipSegment(a, b, glm::dvec2(-margin), glm::dvec2(w + margin, h + margin))) return;
    const double len = glm::length(b - a);
    const int steps = std::max(1, static_cast<int>(std::ceil(len * 2.0)));
    for (int s = 0; s <= steps; ++s) {
        const glm::dvec2 p = a + (b - a) * (double(s) / steps);
        const int px = static_cast<int>(std::floor(p.x)), py = static_cast<int>(std::floor(p.y));
        for (int dy = -radius; dy <= radius; ++dy) {
            for (int dx = -radius; dx <= radius; ++dx) {
                const int x = px + dx, y = py + dy;
                if (x < 0 || y < 0 || x >= w || y >= h || dx * dx + dy * dy > radius * radius + 1)
                    continue;
                for (int c = 0; c < 3; ++c) img[3 * (std::size_t(y) * w + x) + c] = colour[c];
            }
        }
    }
}

// ---- [SECTION] Options and validation

void checkMapOptions(const WorldMapOptions& o) {
    if (o.pixels < 16 || o.pixels > 8192) {
        throw InputError("--pixels",
                         "expected an image size in [16, 8192], got " + std::to_string(o.pixels));
    }
    // 0 means "default"; below 1 m a map shows nothing a terrain sandbox models.
    if (!std::isfinite(o.size_m) || (o.size_m != 0.0 && (o.size_m < 1.0 || o.size_m > 1e7))) {
        throw InputError("--size", "expected a map size in metres in [1, 1e7]");
    }
    FilePlan files;
    files.input("--replay", o.replayPath);
    files.output("--map", o.mapPath);
    files.output("--heightmap", o.heightmapPath);
    files.check();
}

// The square of the world the map shows, and its pixel grid.
struct MapArea {
    glm::dvec2 centre{0.0};     // X, Z [m]
    double size_m = 0.0;        // width and height
    int n = 0;                  // pixels per side
    double pixel_m = 0.0;       // width of one pixel
    double x0 = 0.0, z0 = 0.0;  // X and Z of the map's corner at pixel (0, 0) [m]

    // Pixel (i, j): column i grows with +X, row j grows with +Z (north = -Z at the top).
    double worldX(double i) const { return x0 + (i + 0.5) * pixel_m; }
    double worldZ(double j) const { return z0 + (j + 0.5) * pixel_m; }
    glm::dvec2 toPixel(const glm::dvec3& p) const {
        return glm::dvec2((p.x - x0) / pixel_m, (p.z - z0) / pixel_m);
    }
};

// 12 km around the origin, or the replay's extent around its centre; --size and --centre win.
MapArea mapArea(const WorldMapOptions& o, const std::optional<Replay>& replay) {
    MapArea a;
    a.size_m = o.size_m > 0.0 ? o.size_m : 12000.0;
    if (replay && !replay->samples.empty()) {
        glm::dvec2 lo(1e300), hi(-1e300);
        for (const CameraSample& s : replay->samples) {
            lo = glm::min(lo, glm::dvec2(s.position_m.x, s.position_m.z));
            hi = glm::max(hi, glm::dvec2(s.position_m.x, s.position_m.z));
        }
        a.centre = 0.5 * (lo + hi);
        if (o.size_m <= 0.0) a.size_m = std::max(2000.0, 1.15 * std::max(hi.x - lo.x, hi.y - lo.y));
    }
    if (!o.centre.empty()) a.centre = parseCentre(o.centre);
    a.n = o.pixels;
    a.pixel_m = a.size_m / a.n;
    a.x0 = a.centre.x - 0.5 * a.size_m;
    a.z0 = a.centre.y - 0.5 * a.size_m;
    return a;
}

// ---- [SECTION] Sampling the world on the map grid

struct MapSamples {
    std::vector<double> height, road;  // per pixel: terrain height [m] and road weight
    int nd = 0;                        // side of the density grid
    std::vector<float> density;        // tree density on a grid of half the resolution
};

MapSamples sampleWorld(const World& world, const MapArea& area) {
    const int n = area.n;
    MapSamples m;
    m.height.resize(std::size_t(n) * n);
    m.road.resize(std::size_t(n) * n);
    tbb::parallel_for(0, n, [&](int j) {
        for (int i = 0; i < n; ++i) {
            const std::size_t idx = std::size_t(j) * n + i;
            m.height[idx] = world.heightAndRoad(area.worldX(i), area.worldZ(j), &m.road[idx]);
        }
    });
    // Tree density on a grid of half the resolution (it costs a few height evaluations).
    const int nd = (n + 1) / 2;
    m.nd = nd;
    m.density.resize(std::size_t(nd) * nd);
    tbb::parallel_for(0, nd, [&](int j) {
        for (int i = 0; i < nd; ++i) {
            m.density[std::size_t(j) * nd + i] = static_cast<float>(
                world.vegetation().treeDensity(area.worldX(2 * i + 0.5), area.worldZ(2 * j + 0.5)));
        }
    });
    return m;
}

// ---- [SECTION] Colouring

// The map as RGB8: albedo with hill shading and the forest tint on land, blue by depth in water.
std::vector<unsigned char> shadedRelief(const World& world, const MapArea& area,
                                        const MapSamples& m, double water) {
    const int n = area.n, nd = m.nd;
    const double pixel_m = area.pixel_m;
    const std::vector<double>& height = m.height;
    const glm::dvec3 light = glm::normalize(glm::dvec3(-1.0, 1.2, -1.0));  // from the north-west
    std::vector<unsigned char> img(std::size_t(n) * n * 3);
    tbb::parallel_for(0, n, [&](int j) {
        for (int i = 0; i < n; ++i) {
            const std::size_t idx = std::size_t(j) * n + i;
            const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, n - 1);
            const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, n - 1);
            const double dhdx =
                (height[std::size_t(j) * n + i1] - height[std::size_t(j) * n + i0]) /
                ((i1 - i0) * pixel_m);
            const double dhdz =
                (height[std::size_t(j1) * n + i] - height[std::size_t(j0) * n + i]) /
                ((j1 - j0) * pixel_m);
            const glm::dvec3 normal = glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
            const GroundSample g =
                world.classify(area.worldX(i), area.worldZ(j), height[idx], m.road[idx], normal);
            glm::dvec3 c;
            if (height[idx] < water) {
                const double depth = water - height[idx];
                c = glm::mix(glm::dvec3(0.35, 0.55, 0.75), glm::dvec3(0.05, 0.15, 0.40),
                             std::min(depth / 40.0, 1.0));
            } else {
                // Albedo brightened for display, times Lambert hill shading with some ambient.
                const double shade = 0.35 + 0.75 * std::max(glm::dot(normal, light), 0.0);
                c = glm::dvec3(g.albedo) * 2.2 * shade;
                const double d =
                    m.density[std::size_t(std::min(j / 2, nd - 1)) * nd + std::min(i / 2, nd - 1)];
                c = glm::mix(c, glm::dvec3(0.03, 0.16, 0.05) * shade * 1.4, 0.85 * d);
            }
            // Display gamma (the map is for eyes, not for measurement).
            for (int k = 0; k < 3; ++k) {
                img[3 * idx + k] = static_cast<unsigned char>(
                    std::lround(255.0 * std::pow(std::clamp(c[k], 0.0, 1.0), 1.0 / 2.2)));
            }
        }
    });
    return img;
}

// ---- [SECTION] Overlays

int overlayLineRadius(const MapArea& area) {
    return std::max(1, area.n / 700);
}

void drawRoads(std::vector<unsigned char>& img, const World& world, const MapArea& area) {
    const int n = area.n;
    const unsigned char roadColours[2][3] = {{250, 235, 190}, {255, 170, 60}};
    const int lineRadius = overlayLineRadius(area);
    for (std::size_t r = 0; r < world.roads().roads().size(); ++r) {
        const auto& line = world.roads().roads()[r].centreline;
        for (std::size_t s = 1; s < line.size(); ++s) {
            drawLine(img, n, n, area.toPixel(line[s - 1]), area.toPixel(line[s]),
                     roadColours[r % 2], lineRadius);
        }
    }
}

// The replay's path in red, and a white dot where it starts.
void drawReplayPath(std::vector<unsigned char>& img, const MapArea& area,
                    const std::vector<CameraSample>& samples) {
    const int n = area.n;
    const int lineRadius = overlayLineRadius(area);
    const unsigned char red[3] = {230, 20, 30};
    for (std::size_t s = 1; s < samples.size(); ++s) {
        if (samples[s].cut) continue;  // a teleport: no line across it
        drawLine(img, n, n, area.toPixel(samples[s - 1].position_m),
                 area.toPixel(samples[s].position_m), red, lineRadius);
    }
    if (!samples.empty()) {
        const unsigned char white[3] = {255, 255, 255};
        const glm::dvec2 p = area.toPixel(samples.front().position_m);
        drawLine(img, n, n, p, p, white, 3 * lineRadius);
    }
}

// ---- [SECTION] Writing

// The map and (with --heightmap) the heights, both tagged with where they lie in the world.
void writeMapImages(const WorldMapOptions& o, const MapArea& area,
                    const std::vector<unsigned char>& img, const MapSamples& m) {
    const int n = area.n;
    const std::vector<std::pair<std::string, float>> geo = {
        {"ambience:originX_m", float(area.x0)},
        {"ambience:originZ_m", float(area.z0)},
        {"ambience:pixel_m", float(area.pixel_m)}};
    writeImage(o.mapPath, n, n, 3, img, OIIO::TypeDesc::UINT8, geo);
    if (!o.heightmapPath.empty()) {
        std::vector<float> hf(m.height.begin(), m.height.end());
        writeImage(o.heightmapPath, n, n, 1, hf, OIIO::TypeDesc::FLOAT, geo);
    }
}

void printMapSummary(const WorldMapOptions& o, const WorldSettings& settings, const MapArea& area,
                     const MapSamples& m, std::size_t roads, bool replayDrawn) {
    const double water = settings.waterLevel_m;
    double lo = 1e300, hi = -1e300, waterShare = 0.0, meanDensity = 0.0;
    for (double h : m.height) {
        lo = std::min(lo, h);
        hi = std::max(hi, h);
        waterShare += h < water;
    }
    for (float d : m.density) meanDensity += d;
    std::printf("world map: seed %llu, %.0f m wide around (%.1f, %.1f), %d px (%.2f m/px) -> %s\n",
                static_cast<unsigned long long>(settings.seed), area.size_m, area.centre.x,
                area.centre.y, area.n, area.pixel_m, o.mapPath.c_str());
    std::printf("  heights %.1f .. %.1f m, water %.1f %%, mean tree density %.3f, roads %zu%s\n",
                lo, hi, 100.0 * waterShare / m.height.size(), meanDensity / m.density.size(), roads,
                replayDrawn ? ", replay path drawn" : "");
    if (!o.heightmapPath.empty()) std::printf("  heightmap -> %s\n", o.heightmapPath.c_str());
}

void runWorldMap(const WorldMapOptions& o) {
    checkMapOptions(o);
    WorldSettings settings;
    settings.seed = o.seed;
    std::optional<Replay> replay;
    if (!o.replayPath.empty()) {
        replay = readReplay(o.replayPath);
        settings = replay->world;
    }
    const MapArea area = mapArea(o, replay);
    const World world(settings);
    const MapSamples samples = sampleWorld(world, area);
    std::vector<unsigned char> img = shadedRelief(world, area, samples, settings.waterLevel_m);
    drawRoads(img, world, area);
    if (replay) drawReplayPath(img, area, replay->samples);
    writeMapImages(o, area, img, samples);
    printMapSummary(o, settings, area, samples, world.roads().roads().size(), replay.has_value());
}

}  // namespace

void addWorldCommand(CLI::App& app) {
    auto opts = std::make_shared<WorldMapOptions>();
    auto* cmd = app.add_subcommand("world", "Write a top-down map (and heightmap) of a world");
    auto* seed =
        cmd->add_option("--seed", opts->seed, "World seed (default 1)")->check(SeedValidator());
    auto* replay = cmd->add_option("--replay", opts->replayPath,
                                   "Take the world from a replay and draw its path");
    seed->excludes(replay);
    replay->excludes(seed);
    cmd->add_option("--map", opts->mapPath, "Output map picture (PNG)")->required();
    cmd->add_option("--size", opts->size_m,
                    "Map width in metres (default 12000, or the replay's extent)");
    cmd->add_option("--heightmap", opts->heightmapPath,
                    "Also write the heights [m] as a float EXR");
    cmd->add_option("--centre", opts->centre,
                    "Map centre X,Z in metres (default the origin or the replay's centre)");
    cmd->add_option("--pixels", opts->pixels, "Map width and height in pixels (default 1024)");
    cmd->callback([opts] { runWorldMap(*opts); });
}

}  // namespace amb
