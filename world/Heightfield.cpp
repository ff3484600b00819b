// Heightfield.cpp — natural terrain: domain-warped continent mask, ridged multifractal
// mountains and fBm hills; central-difference normals; a moisture field.
//
// [SECTION] Seeding: a SplitMix64 stream turns the seed into per-octave rotations and offsets.
// [SECTION] Octave evaluation: exact reduction into GLM Perlin's period, then double noise.
// [SECTION] Height: warp -> continent -> ridges -> hills.
// [SECTION] Normal and moisture.
#include "world/Heightfield.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/noise.hpp>
#include <glm/vec2.hpp>

#include "world/Conventions.h"

namespace amb {

namespace {

// ---- [SECTION] Seeding ---------------------------------------------------------------------

// SplitMix64 (Steele, Lea, Flood 2014): a tiny, well-mixed generator; same seed, same stream.
struct SplitMix64 {
    std::uint64_t state;
    std::uint64_t next() {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

constexpr double kPeriod = 289.0;  // GLM's classic Perlin noise repeats every 289 lattice units

template <std::size_t N>
void seedOctaves(std::array<Heightfield::Octave, N>& octaves, SplitMix64& rng, double wavelength_m,
                 double lacunarity) {
    double frequency = 1.0 / wavelength_m;
    for (auto& o : octaves) {
        // A different rotation per octave hides the lattice axes; offsets pick a region of the
        // noise's period, so two seeds see unrelated terrain.
        const double angle = 2.0 * kPi * rng.uniform();
        o.cosA = std::cos(angle);
        o.sinA = std::sin(angle);
        o.frequency_per_m = frequency;
        o.offsetU = kPeriod * rng.uniform();
        o.offsetV = kPeriod * rng.uniform();
        frequency *= lacunarity;
    }
}

// ---- [SECTION] Octave evaluation -----------------------------------------------------------

// Reduces a lattice coordinate into [0, 289). k * 289 is an exact integer-valued double and u and
// k * 289 share their magnitude, so the subtraction is exact: the fraction of u is preserved.
inline double reduce(double u) {
    return u - kPeriod * std::floor(u * (1.0 / kPeriod));
}

// glm::perlin(dvec2) (Gustavson's classic noise, glm/gtc/noise.inl) reads its lattice through
// permute(permute(x) + y), permute(x) = mod289((34 x + 1) x), and turns the hash i into the
// gradient g = (gx, |gx| - 1/2) * (1.79284291400159 - 0.85373472095314 |g|^2), gx from
// 2 fract(i / 41) - 1 less floor(gx + 1/2). On one period those are functions of integers below
// 600: tables, each entry made with the same operations GLM makes. (mod289 multiplies by a
// rounded 1/289, so a multiple of 289 may come out as 289, not 0: the tables keep that.)
struct PerlinTables {
    static constexpr int kLattice = 289;
    std::array<int, kLattice> first{};            // permute(x), x in [0, 288]
    std::array<int, 2 * kLattice> second{};       // permute(x), x in [0, 577]
    std::array<glm::dvec2, kLattice + 1> gradient{};  // g for the hash i in [0, 289]
    PerlinTables() {
        const auto permute = [](double x) { return glm::detail::permute(x); };
        for (int x = 0; x < kLattice; ++x) first[std::size_t(x)] = int(permute(double(x)));
        for (int x = 0; x < 2 * kLattice; ++x) second[std::size_t(x)] = int(permute(double(x)));
        for (int i = 0; i <= kLattice; ++i) {
            double gx = 2.0 * glm::fract(double(i) / 41.0) - 1.0;
            const double gy = std::abs(gx) - 0.5;
            gx = gx - std::floor(gx + 0.5);
            const glm::dvec2 g(gx, gy);
            gradient[std::size_t(i)] = g * glm::detail::taylorInvSqrt(glm::dot(g, g));
        }
    }
};

}  // namespace

double Heightfield::classicNoise(double u, double v) {
    static const PerlinTables t;
    const double iu = std::floor(u), iv = std::floor(v);
    // The lattice corners mod 289, as glm::mod(floor + (0, 0, 1, 1), 289) gives them (exact for
    // integers: the quotient's rounding never crosses an integer).
    const auto wrap = [](double i) {
        const int m = int(i) % PerlinTables::kLattice;
        return m < 0 ? m + PerlinTables::kLattice : m;
    };
    const int x0 = wrap(iu), y0 = wrap(iv), x1 = wrap(iu + 1.0), y1 = wrap(iv + 1.0);
    const double fu = u - iu, fv = v - iv;  // glm::fract
    const double fu1 = fu - 1.0, fv1 = fv - 1.0;
    const auto corner = [](int x, int y, double dx, double dy) {
        const glm::dvec2& g = t.gradient[std::size_t(t.second[std::size_t(t.first[std::size_t(x)] + y)])];
        return glm::dot(g, glm::dvec2(dx, dy));
    };
    const double n00 = corner(x0, y0, fu, fv), n10 = corner(x1, y0, fu1, fv);
    const double n01 = corner(x0, y1, fu, fv1), n11 = corner(x1, y1, fu1, fv1);
    const glm::dvec2 fade = glm::detail::fade(glm::dvec2(fu, fv));
    const glm::dvec2 nx = glm::mix(glm::dvec2(n00, n01), glm::dvec2(n10, n11), fade.x);
    return 2.3 * glm::mix(nx.x, nx.y, fade.y);
}

namespace {

inline double perlinAt(const Heightfield::Octave& o, double x_m, double z_m) {
    const double u = (o.cosA * x_m - o.sinA * z_m) * o.frequency_per_m + o.offsetU;
    const double v = (o.sinA * x_m + o.cosA * z_m) * o.frequency_per_m + o.offsetV;
    return Heightfield::classicNoise(reduce(u), reduce(v));
}

template <std::size_t N>
double fbm(const std::array<Heightfield::Octave, N>& octaves, double x_m, double z_m, double gain) {
    double sum = 0.0, amplitude = 1.0, norm = 0.0;
    for (const auto& o : octaves) {
        sum += amplitude * perlinAt(o, x_m, z_m);
        norm += amplitude;
        amplitude *= gain;
    }
    return sum / norm;
}

inline double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// Terrain shape constants [m].
constexpr double kWarpAmplitude_m = 420.0;
constexpr double kBase_m = 55.0;         // mean lowland height above the datum
constexpr double kContinent_m = 150.0;   // amplitude of the continent mask
constexpr double kMountain_m = 720.0;    // peak height of the ridged layer
constexpr double kHills_m = 38.0;        // amplitude of the hills
constexpr double kRidgeSoftness = 0.04;  // in noise units; rounds the ridge crests

}  // namespace

Heightfield::Heightfield(const WorldSettings& settings) : waterLevel_m_(settings.waterLevel_m) {
    SplitMix64 rng{settings.seed ^ 0x6A09E667F3BCC909ull};
    seedOctaves(warpU_, rng, 2600.0, 2.13);
    seedOctaves(warpV_, rng, 2600.0, 2.13);
    seedOctaves(continent_, rng, 7000.0, 2.21);
    seedOctaves(ridged_, rng, 2200.0, 2.07);
    seedOctaves(hills_, rng, 620.0, 2.31);
    seedOctaves(moisture_, rng, 3100.0, 2.17);
    // Their own streams (makeOctave), so the layers above are the same with or without them.
    ravine_ = makeOctave(settings.seed, 0x6D21u, 2700.0);
    gully_[0] = makeOctave(settings.seed, 0x6A12u, kGullyWavelength_m);
    gully_[1] = makeOctave(settings.seed, 0x6A13u, 400.0);
}

double Heightfield::octaveNoise(const Octave& octave, double x_m, double z_m) {
    return perlinAt(octave, x_m, z_m);
}

Heightfield::Octave Heightfield::makeOctave(std::uint64_t seed, std::uint64_t salt,
                                            double wavelength_m) {
    SplitMix64 rng{seed ^ (salt * 0xD1B54A32D192ED03ull)};
    std::array<Octave, 1> o;
    seedOctaves(o, rng, wavelength_m, 2.0);
    return o[0];
}

// ---- [SECTION] Height ------------------------------------------------------------------------

double Heightfield::warpedHeight(double x_m, double z_m) const {
    // Domain warping (Quilez, "warping"): displace the sample point by a smooth vector field so
    // ridges and valleys bend instead of following the noise lattice.
    const double wx = x_m + kWarpAmplitude_m * fbm(warpU_, x_m, z_m, 0.45);
    const double wz = z_m + kWarpAmplitude_m * fbm(warpV_, x_m, z_m, 0.45);

    // Continent mask: lowlands with lakes where negative, mountains where positive.
    const double c = fbm(continent_, wx, wz, 0.4);
    const double mountainMask = smoothstep(-0.05, 0.45, c);

    // Ridged multifractal (Musgrave): each octave's ridge weight follows the previous octave,
    // so fine ridges grow on the big ones and valleys stay smooth.
    double ridges = 0.0, weight = 1.0, amplitude = 1.0, norm = 0.0;
    if (mountainMask > 0.0) {
        for (const auto& o : ridged_) {
            // 1 - |n| with |n| softened to sqrt(n^2 + s^2): ridges stay sharp at the metre
            // scale but the surface is smooth (C-infinity), so normals are well defined.
            const double n = perlinAt(o, wx, wz);
            double r = 1.0 - std::sqrt(n * n + kRidgeSoftness * kRidgeSoftness);
            r *= r;
            r *= weight;
            // Smooth saturation t / sqrt(1 + t^2) instead of clamp(t, 0, 1) (no kink).
            const double t = r * 1.6;
            weight = t / std::sqrt(1.0 + t * t);
            ridges += amplitude * r;
            norm += amplitude;
            amplitude *= 0.5;
        }
        ridges /= norm;
    }

    // fBm hills, fading slightly in the mountains where ridges carry the detail.
    const double hills = fbm(hills_, wx, wz, 0.42);

    return kBase_m + kContinent_m * c + kMountain_m * mountainMask * ridges * ridges * 1.4 +
           kHills_m * hills * (1.0 - 0.5 * mountainMask);
}

// Gully shape constants.
constexpr double kRavineFrom = 0.45, kRavineTo = 0.7;  // mask noise where ravine country begins, is full
constexpr double kGullyHalfWidth = 0.09;  // in noise units either side of the course's zero line

double Heightfield::ravineMask(double x_m, double z_m) const {
    return smoothstep(kRavineFrom, kRavineTo, perlinAt(ravine_, x_m, z_m));
}

bool Heightfield::mayHaveGullies(double x_m, double z_m, double radius_m) const {
    const double reach = kNoiseSlopeBound * ravine_.frequency_per_m * std::max(radius_m, 0.0);
    return perlinAt(ravine_, x_m, z_m) + reach > kRavineFrom;
}

double Heightfield::gullyDepth(double x_m, double z_m) const {
    const double mask = ravineMask(x_m, z_m);
    if (mask <= 0.0) return 0.0;
    // A gully follows a zero line of the course's noise n: its cross-section (1 - (n / w)^2)^2 is
    // smooth everywhere (even in n, flat where it meets the land at |n| = w), about 15 m wide
    // where the noise's slope is typical. Its depth wanders along it.
    const double s = perlinAt(gully_[0], x_m, z_m) / kGullyHalfWidth;
    if (s * s >= 1.0) return 0.0;
    const double profile = (1.0 - s * s) * (1.0 - s * s);
    const double along = std::clamp(0.65 + 0.5 * perlinAt(gully_[1], x_m, z_m), 0.2, 1.0);
    return kGullyDepth_m * mask * along * profile;
}

double Heightfield::broadHeight(double x_m, double z_m) const {
    return warpedHeight(x_m, z_m);
}

double Heightfield::height(double x_m, double z_m) const {
    return warpedHeight(x_m, z_m) - gullyDepth(x_m, z_m);
}

// ---- [SECTION] Normal and moisture -----------------------------------------------------------

glm::dvec3 Heightfield::normal(double x_m, double z_m) const {
    // Central differences: n ~ (-dh/dx, 1, -dh/dz). Error O(step^2) against features of tens of
    // metres; tested against a finer difference quotient.
    const double e = kNormalStep_m;
    const double dhdx = (height(x_m + e, z_m) - height(x_m - e, z_m)) / (2.0 * e);
    const double dhdz = (height(x_m, z_m + e) - height(x_m, z_m - e)) / (2.0 * e);
    return glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
}

double Heightfield::moistureAt(double x_m, double z_m, double height_m) const {
    // A slow noise field, wetter near the water level and drier high up.
    const double n = fbm(moisture_, x_m, z_m, 0.5);
    const double above_m = height_m - waterLevel_m_;
    const double nearWater = std::exp(-std::max(above_m, 0.0) / 25.0);
    const double m = 0.5 + 0.55 * n + 0.35 * nearWater - 0.00045 * std::max(above_m - 150.0, 0.0);
    return std::clamp(m, 0.0, 1.0);
}

double Heightfield::moisture(double x_m, double z_m) const {
    return moistureAt(x_m, z_m, height(x_m, z_m));
}

}  // namespace amb
