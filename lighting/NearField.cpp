// NearField.cpp — the near field's closed forms, its transfer and its cache (NearField.h).
#include "lighting/NearField.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/Sky.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {

double rangeWeight(double distance_m, double range_m) {
    if (!(distance_m < range_m)) return 0.0;
    const double x = std::clamp((range_m - distance_m) / (kNearFade * range_m), 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// ---- [SECTION] Closed forms --------------------------------------------------------------------

namespace {

constexpr double kAhatBand[3] = {kShA0, kShA1, kShA2};
// Projected-area mean over a visible disc of the normals' irradiance, per band (NearField.h).
constexpr double kDiscMean[3] = {1.0, 2.0 / 3.0, 0.25};
// Caps narrower than this (a 0.3 m trunk 20 m away) are left out: 2e-4 of the sphere each.
constexpr double kMinSinHalfAngle = 0.015;
// Terrain bands thinner than this (about a degree) are left out.
constexpr double kMinBand_rad = 0.02;

// Four floats as one value (GCC's and Clang's vector extension): the transfers' sums run four
// lanes at a time whatever the optimiser does; the channels take lanes 0-2.
using Lanes = float __attribute__((vector_size(16)));
Lanes lanesOf(const glm::vec3& v) {
    return Lanes{v.x, v.y, v.z, 0.0f};
}

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
    static const double rotate[3] = {std::sqrt(4.0 * kPi), std::sqrt(4.0 * kPi / 3.0),
                                     std::sqrt(4.0 * kPi / 5.0)};
    const auto z = capZonal(cosHalfAngle);
    const auto y = shBasis(direction);
    std::array<double, kShCoefficients> out{};
    for (int k = 0; k < kShCoefficients; ++k) out[k] = rotate[shBand(k)] * z[shBand(k)] * y[k];
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
    // The geometry first, in a small record (sorted, then tested pair by pair).
    struct Seen {
        glm::dvec3 direction;
        double cosHalf, halfAngle, sinHalf, weight;
        const SphereOccluder* occluder;
    };
    std::vector<Seen> seen;
    seen.reserve(occluders.size());
    for (const SphereOccluder& o : occluders) {
        const glm::dvec3 to = o.centre_m - point_m;
        const double d = glm::length(to);
        if (!(o.radius_m > 0.0) || !std::isfinite(d) || d <= 0.0) continue;
        const double sinT = std::min(1.0, o.radius_m / d);
        if (sinT < kMinSinHalfAngle) continue;  // too small to matter (see NearField.h)
        // Outside, sin t = r / d; inside, t grows on from 90 degrees to 180 at the centre, so a
        // point that passes through a crown sees it close around it without a step (where it
        // is nearly the whole sphere, its direction no longer matters).
        const double c = d >= o.radius_m ? std::sqrt(1.0 - sinT * sinT)
                                         : -std::sin(0.5 * kPi * (1.0 - d / o.radius_m));
        seen.push_back({to / d, c, 0.0, 0.0, std::clamp(o.weight, 0.0, 1.0), &o});
    }
    // Largest first; each keeps what earlier ones leave of it.
    std::sort(seen.begin(), seen.end(),
              [](const Seen& a, const Seen& b) { return a.cosHalf < b.cosHalf; });
    const std::size_t n = seen.size();
    // Which earlier caps touch a cap is asked of every pair: in float, one array a quantity, so
    // the test vectorises (a pair at the edge overlaps by nearly nothing either way).
    std::vector<float> dx(n), dy(n), dz(n), cosHalf(n), sinHalf(n), halfAngle(n);
    std::vector<unsigned char> touches(n + 8);  // read 8 at a time; past i still 0
    for (std::size_t i = 0; i < n; ++i) {
        Seen& e = seen[i];
        e.halfAngle = std::acos(e.cosHalf), e.sinHalf = std::sin(e.halfAngle);
        dx[i] = float(e.direction.x), dy[i] = float(e.direction.y), dz[i] = float(e.direction.z);
        cosHalf[i] = float(e.cosHalf), sinHalf[i] = float(e.sinHalf), halfAngle[i] = float(e.halfAngle);
    }
    std::vector<OccluderCap> caps;
    caps.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        Seen& si = seen[i];
        const double omega = capSolidAngle(si.cosHalf);
        double w = si.weight;  // its fade (see Radii)
        // Apart when the separation is at least a_i + a_j: cos d <= cos(a_i + a_j).
        const float xi = dx[i], yi = dy[i], zi = dz[i], ci = cosHalf[i], s_i = sinHalf[i],
                    ai = halfAngle[i], pi = float(kPi);
        for (std::size_t j = 0; j < i; ++j)
            touches[j] = (xi * dx[j] + yi * dy[j] + zi * dz[j] > ci * cosHalf[j] - s_i * sinHalf[j]) |
                         (ai + halfAngle[j] >= pi);
        for (std::size_t j = 0; j < i && w > 0.0; ++j) {
            // Most caps touch none of the earlier ones: skip eight flags at a time.
            if (j % 8 == 0) {
                std::uint64_t eight;
                std::memcpy(&eight, &touches[j], sizeof eight);
                if (eight == 0) {
                    j += 7;
                    continue;
                }
            }
            if (!touches[j]) continue;
            const Seen& sj = seen[j];
            const double cosD = std::clamp(glm::dot(si.direction, sj.direction), -1.0, 1.0);
            // capOverlap, its cosines known: one cap within the other (d <= |a_i - a_j|, cos d
            // >= cos(a_i - a_j)) shares all of the smaller, else the blend needs d itself.
            const double shared =
                cosD >= si.cosHalf * sj.cosHalf + si.sinHalf * sj.sinHalf
                    ? capSolidAngle(std::max(si.cosHalf, sj.cosHalf))
                    : capOverlap(si.halfAngle, sj.halfAngle, std::acos(cosD));
            w *= std::max(0.0, 1.0 - sj.weight * shared / omega);
        }
        si.weight = w;  // later caps see what this one keeps
        if (w <= 0.0) continue;
        OccluderCap c;
        c.direction = si.direction;
        c.cosHalfAngle = si.cosHalf;
        c.albedo = si.occluder->albedo;
        c.weight = w;
        c.sh = capSh(c.direction, c.cosHalfAngle);
        c.solidAngle = omega;
        caps.push_back(c);
    }
    return caps;
}

std::vector<OccluderCap> nearOccluders(const glm::dvec3& point_m,
                                       const std::vector<SphereOccluder>& occluders,
                                       const std::vector<HorizonWedge>& horizon) {
    std::vector<OccluderCap> all = terrainBands(horizon);
    const std::size_t bands = all.size();
    if (bands == 0) return occluderCaps(point_m, occluders);
    for (OccluderCap& c : occluderCaps(point_m, occluders)) {
        // A plant whose centre is seen against a raised band hides that band, not the far field.
        const double phi = std::atan2(c.direction.z, c.direction.x);
        const double e = std::asin(std::clamp(c.direction.y, -1.0, 1.0));
        for (std::size_t b = 0; b < bands; ++b) {
            const OccluderCap& band = all[b];
            double rel = phi - band.azimuth0;
            rel -= 2.0 * kPi * std::floor(rel / (2.0 * kPi));
            if (rel <= band.azimuth1 - band.azimuth0 && e >= band.lower && e <= band.upper) {
                c.behind = int(b);
                break;
            }
        }
        all.push_back(c);
    }
    return all;
}

// ---- [SECTION] Terrain bands ------------------------------------------------------------------

namespace {

// Integrals over the band of the nine functions 1, x, y, z, xy, yz, xz, x^2 - z^2, 3y^2 - 1,
// direction (cos e cos phi, sin e, cos e sin phi), d omega = cos e de dphi: each splits into an
// azimuth and an elevation integral of sines and cosines.
std::array<double, 9> monomialIntegrals(double phi0, double phi1, double e1, double e2) {
    const double P0 = phi1 - phi0;
    const double Pc = std::sin(phi1) - std::sin(phi0), Ps = std::cos(phi0) - std::cos(phi1);
    const double P2 = (std::sin(2.0 * phi1) - std::sin(2.0 * phi0)) / 4.0;
    const double Pcc = P0 / 2.0 + P2, Pss = P0 / 2.0 - P2;
    const double Pcs = (std::sin(phi1) * std::sin(phi1) - std::sin(phi0) * std::sin(phi0)) / 2.0;
    const auto at = [&](auto f) { return f(e2) - f(e1); };
    const double c1 = at([](double e) { return std::sin(e); });                          // cos
    const double c2 = at([](double e) { return e / 2.0 + std::sin(2.0 * e) / 4.0; });    // cos^2
    const double cs = at([](double e) { return std::sin(e) * std::sin(e) / 2.0; });      // cos sin
    const double c2s = at([](double e) { return -std::pow(std::cos(e), 3) / 3.0; });     // cos^2 sin
    const double c3 = at([](double e) { return std::sin(e) - std::pow(std::sin(e), 3) / 3.0; });
    const double cs2 = at([](double e) { return std::pow(std::sin(e), 3) / 3.0; });      // cos sin^2
    return {P0 * c1,           c2 * Pc,         cs * P0,        c2 * Ps,
            c2s * Pc,          c2s * Ps,        c3 * Pcs,       c3 * (Pcc - Pss),
            3.0 * cs2 * P0 - P0 * c1};
}

// Y_k as combinations of the nine functions above, found once from shBasis (exact: they span
// the harmonics of degree <= 2, so the basis' own conventions carry over).
const std::array<std::array<double, 9>, kShCoefficients>& basisInMonomials() {
    static const auto table = [] {
        const auto f = [](const glm::dvec3& d) {
            return std::array<double, 9>{1.0,       d.x,       d.y,       d.z,
                                         d.x * d.y, d.y * d.z, d.x * d.z, d.x * d.x - d.z * d.z,
                                         3.0 * d.y * d.y - 1.0};
        };
        // Nine generic directions; solve F a_k = Y_k by Gaussian elimination.
        std::array<glm::dvec3, 9> dirs;
        for (int i = 0; i < 9; ++i)
            dirs[i] = glm::normalize(glm::dvec3(std::sin(1.3 * i + 0.4), std::cos(2.1 * i + 0.3),
                                                std::sin(0.7 * i + 1.9) + 0.1 * i));
        std::array<std::array<double, kShCoefficients>, kShCoefficients> out{};
        for (int k = 0; k < kShCoefficients; ++k) {
            double m[9][10];
            for (int i = 0; i < 9; ++i) {
                const auto row = f(dirs[i]);
                for (int j = 0; j < 9; ++j) m[i][j] = row[j];
                m[i][9] = shBasis(dirs[i])[k];
            }
            for (int c = 0; c < 9; ++c) {
                int pivot = c;
                for (int r = c + 1; r < 9; ++r)
                    if (std::fabs(m[r][c]) > std::fabs(m[pivot][c])) pivot = r;
                for (int j = 0; j < 10; ++j) std::swap(m[c][j], m[pivot][j]);
                for (int r = 0; r < 9; ++r) {
                    if (r == c) continue;
                    const double q = m[r][c] / m[c][c];
                    for (int j = c; j < 10; ++j) m[r][j] -= q * m[c][j];
                }
            }
            for (int j = 0; j < 9; ++j) out[k][j] = m[j][9] / m[j][j];
        }
        return out;
    }();
    return table;
}

}  // namespace

std::array<double, kShCoefficients> bandSh(double azimuth0, double azimuth1, double lower,
                                           double upper) {
    const auto m = monomialIntegrals(azimuth0, azimuth1, lower, upper);
    const auto& a = basisInMonomials();
    std::array<double, kShCoefficients> out{};
    for (int k = 0; k < kShCoefficients; ++k)
        for (int j = 0; j < 9; ++j) out[k] += a[k][j] * m[j];
    return out;
}

std::vector<OccluderCap> terrainBands(const std::vector<HorizonWedge>& wedges) {
    std::vector<OccluderCap> out;
    for (const HorizonWedge& w : wedges) {
        if (!(w.upper > w.lower + kMinBand_rad)) continue;
        OccluderCap b;
        b.band = true;
        b.azimuth0 = w.azimuth0, b.azimuth1 = w.azimuth1;
        b.lower = std::max(w.lower, -0.5 * kPi), b.upper = std::min(w.upper, 0.5 * kPi);
        const double phi = 0.5 * (w.azimuth0 + w.azimuth1), e = 0.5 * (b.lower + b.upper);
        b.direction = {std::cos(e) * std::cos(phi), std::sin(e), std::cos(e) * std::sin(phi)};
        b.sh = bandSh(w.azimuth0, w.azimuth1, b.lower, b.upper);
        b.solidAngle = b.sh[0] / kShY00;
        b.albedo = w.albedo;
        if (b.solidAngle > 0.0) out.push_back(b);
    }
    return out;
}

// ---- [SECTION] Transfer ------------------------------------------------------------------------

namespace {

// What an entry shows per unit albedo, as a functional of the far field: the irradiance of the
// surface facing the point (caps: its visible disc's mean, bands: a wall facing the point), over
// pi. The same functional of a delta Y(l) E is the light's term: for a cap the order-2 projection
// of the Lambert sphere's phase law (2/3) Phi / pi, for a band that of max(0, cos) / pi.
std::array<double, kShCoefficients> showFunctional(const OccluderCap& e) {
    const auto y = shBasis(-e.direction);
    std::array<double, kShCoefficients> g{};
    for (int k = 0; k < kShCoefficients; ++k)
        g[k] = kAhatBand[shBand(k)] * (e.band ? 1.0 : kDiscMean[shBand(k)]) * y[k] / kPi;
    return g;
}

}  // namespace

namespace {
// A(n)_k = Ahat_l Y_k(n): irradiance at n is A(n) . L.
std::array<double, kShCoefficients> irradianceFunctional(const glm::dvec3& normal) {
    const auto y = shBasis(normal);
    std::array<double, kShCoefficients> a{};
    for (int k = 0; k < kShCoefficients; ++k) a[k] = kAhatBand[shBand(k)] * y[k];
    return a;
}
}  // namespace

NearFieldTransfer nearFieldTransfer(const std::vector<OccluderCap>& caps, const GroundTerm* ground) {
    NearFieldTransfer t;
    constexpr int K = kShCoefficients;
    // Each entry adds rank-one terms: hide -= (w c) (c / omega)^T, show_c += (w c) u_c^T. Summed
    // in float, row by row, so the inner loops vectorise (a point has a few hundred entries).
    std::array<std::array<float, K * K>, 3> show{};  // what the caps show, per channel
    std::vector<std::array<double, K>> shows(caps.size());
    for (std::size_t i = 0; i < caps.size(); ++i) shows[i] = showFunctional(caps[i]);
    for (std::size_t i = 0; i < caps.size(); ++i) {
        const OccluderCap& e = caps[i];
        const auto& c = e.sh;
        // It hides the far field, or, in front of a band, that band's radiance.
        const OccluderCap* b = e.behind >= 0 ? &caps[std::size_t(e.behind)] : nullptr;
        float cw[K], hideRow[K], u[3][K];
        for (int k = 0; k < K; ++k) {
            cw[k] = float(e.weight * c[k]);
            hideRow[k] = b ? 0.0f : float(c[k] / e.solidAngle);
            for (int ch = 0; ch < 3; ++ch)
                u[ch][k] = float(e.albedo[ch] * shows[i][k] -
                                 (b ? b->albedo[ch] * shows[std::size_t(e.behind)][k] : 0.0));
        }
        for (int j = 0; j < K; ++j) {
            const float wj = cw[j];
            float* h = &t.hide[std::size_t(j * K)];
            if (!b)
                for (int k = 0; k < K; ++k) h[k] -= wj * hideRow[k];
            for (int ch = 0; ch < 3; ++ch) {
                float* row = &show[std::size_t(ch)][std::size_t(j * K)];
                for (int k = 0; k < K; ++k) row[k] += wj * u[ch][k];
            }
        }
    }
    if (ground && ground->any) {
        // The ground's ambient at its normal as the caps leave it: (I + T_c)^T a(n) with the
        // caps' T_c, of which only the ambient's two coefficients are read (see GroundAmbient).
        const auto a = irradianceFunctional(ground->normal);
        for (int k = 0; k < 2; ++k) {
            double hk = a[std::size_t(k)];
            for (int j = 0; j < K; ++j) hk += a[std::size_t(j)] * t.hide[std::size_t(j * K + k)];
            for (int ch = 0; ch < 3; ++ch) {
                double v = hk;
                for (int j = 0; j < K; ++j)
                    v += a[std::size_t(j)] * show[std::size_t(ch)][std::size_t(j * K + k)];
                t.groundAmbient[std::size_t(ch)][std::size_t(k)] = float(v);
            }
        }
        // What the probes saw below is hidden (part of T); what the ground shows, lit by the
        // ambient and the light, is remade with the light term (see Ground).
        for (int j = 0; j < K * K; ++j) {
            t.hide[std::size_t(j)] += ground->hide[std::size_t(j)];
            t.groundHide[std::size_t(j)] = ground->hide[std::size_t(j)];
        }
        t.groundShow = ground->show;
        t.groundLit = ground->lit;
        t.groundNormal = glm::vec3(ground->normal);
        t.ground = true;
    }
    // T_c = hide + show_c, stored by column for the apply: columns[k][ch][j].
    for (int k = 0; k < K; ++k)
        for (int ch = 0; ch < 3; ++ch)
            for (int j = 0; j < K; ++j)
                t.columns[std::size_t((k * K + j) * 4 + ch)] =
                    show[ch][j * K + k] + t.hide[j * K + k];
    t.any = !caps.empty() || t.ground;
    return t;
}

namespace {

// The light on the ground per unit of the light's irradiance (see Ground): max(0, n . l).
double groundCosine(const glm::vec3& groundNormal, const glm::dvec3& lightDirection) {
    return std::max(0.0, glm::dot(glm::dvec3(groundNormal), lightDirection));
}

// The ground's ambient irradiance per channel (see GroundAmbient).
glm::dvec3 groundAmbientIrradiance(const GroundAmbient& w, const HemisphereAmbient& ambient) {
    const glm::dvec3 a0 = ambient.shBand0(), a1 = ambient.shVertical();
    glm::dvec3 e;
    for (int ch = 0; ch < 3; ++ch)
        e[ch] = w[std::size_t(ch)][0] * a0[ch] + w[std::size_t(ch)][1] * a1[ch];
    return e;
}

}  // namespace

void updateLightTerm(NearFieldTransfer& t, const glm::dvec3& lightDirection,
                     const HemisphereAmbient& ambient) {
    // The light is a delta in the far field: what the caps show of it is show_c Y(l), show_c =
    // T_c - hide (see "What a cap does").
    constexpr int K = kShCoefficients;
    t.lightDirection = lightDirection;
    const auto y = shBasis(lightDirection);
    for (int ch = 0; ch < 3; ++ch)
        for (int j = 0; j < K; ++j) {
            double v = 0.0;
            for (int m = 0; m < K; ++m)
                v += (t.columns[std::size_t((m * K + j) * 4 + ch)] - t.hide[j * K + m]) * y[m];
            t.s[ch][j] = float(v);
        }
    if (t.ground) {
        const double cosine = groundCosine(t.groundNormal, lightDirection);
        for (int ch = 0; ch < 3; ++ch)
            for (int j = 0; j < K; ++j) t.s[ch][j] += float(t.groundLit[ch][j] * cosine);
        t.groundAmbientE = glm::vec3(groundAmbientIrradiance(t.groundAmbient, ambient));
    }
}

NormalTransfer normalTransfer(const NearFieldTransfer* t, const glm::dvec3& normal) {
    NormalTransfer n;
    if (!t || t->empty()) return n;
    constexpr int K = kShCoefficients;
    const auto a = irradianceFunctional(normal);
    for (int k = 0; k < K; ++k) {
        // The guard takes the caps' hide only: the ground's is a replacement (see Guard).
        double h = 0.0, hg = 0.0;
        for (int j = 0; j < K; ++j)
            h += a[j] * (t->hide[j * K + k] - t->groundHide[j * K + k]), hg += a[j] * t->groundHide[j * K + k];
        n.hide[k] = float(h);
        n.groundHide[k] = float(hg);
        for (int ch = 0; ch < 3; ++ch) {
            double v = 0.0;
            for (int j = 0; j < K; ++j)
                v += a[j] * (double(t->columns[std::size_t((k * K + j) * 4 + ch)]) -
                             double(t->hide[j * K + k]));
            n.show[std::size_t(ch * K + k)] = float(v + hg);
        }
    }
    if (t->ground) {
        for (int ch = 0; ch < 3; ++ch) {
            double show = 0.0, lit = 0.0;
            for (int j = 0; j < K; ++j)
                show += a[j] * t->groundShow[ch][j], lit += a[j] * t->groundLit[ch][j];
            n.groundShow[ch] = float(show), n.groundLit[ch] = float(lit);
        }
        n.groundNormal = t->groundNormal;
        n.groundAmbient = t->groundAmbient;
        n.ground = true;
    }
    n.any = true;
    return n;
}

void updateLightTerm(NormalTransfer& t, const glm::dvec3& lightDirection,
                     const HemisphereAmbient& ambient, std::uint32_t epoch) {
    const auto y = shBasis(lightDirection);
    for (int ch = 0; ch < 3; ++ch) {
        double v = 0.0;
        for (int k = 0; k < kShCoefficients; ++k)
            v += (t.show[std::size_t(ch * kShCoefficients + k)] - t.groundHide[std::size_t(k)]) * y[k];
        t.light[ch] = float(v);
    }
    t.sky = glm::vec3(0.0f);
    if (t.ground) {
        t.light += t.groundLit * float(groundCosine(t.groundNormal, lightDirection));
        t.sky += t.groundShow * glm::vec3(groundAmbientIrradiance(t.groundAmbient, ambient));
    }
    if (t.groundParts) {
        for (const GroundLightPart& part : *t.groundParts) {
            t.light += part.lit * float(groundCosine(part.normal, lightDirection));
            t.sky += part.show * glm::vec3(groundAmbientIrradiance(part.ambient, ambient));
        }
    }
    t.lightEpoch = epoch;
}

NormalTransfer meanNormalTransfer(const NormalTransfer* const* samples, const double* weights,
                                  std::size_t count) {
    NormalTransfer m;
    auto parts = std::make_shared<std::vector<GroundLightPart>>();
    std::array<double, kShCoefficients> hide{}, groundHide{};
    std::array<double, 3 * kShCoefficients> show{};
    glm::dvec3 light(0.0), sky(0.0);
    for (std::size_t i = 0; i < count; ++i) {
        const NormalTransfer& t = *samples[i];
        if (!t.any) continue;
        const double w = weights[i];
        for (int k = 0; k < kShCoefficients; ++k)
            hide[k] += w * t.hide[k], groundHide[k] += w * t.groundHide[k];
        for (std::size_t k = 0; k < show.size(); ++k) show[k] += w * t.show[k];
        light += w * glm::dvec3(t.light);
        sky += w * glm::dvec3(t.sky);
        if (t.ground)
            parts->push_back(GroundLightPart{t.groundShow * float(w), t.groundLit * float(w),
                                             t.groundNormal, t.groundAmbient});
        if (t.groundParts)
            for (GroundLightPart p : *t.groundParts) {
                p.show *= float(w), p.lit *= float(w);
                parts->push_back(p);
            }
        m.lightEpoch = t.lightEpoch;
        m.any = true;
    }
    if (!m.any) return m;
    for (int k = 0; k < kShCoefficients; ++k)
        m.hide[k] = float(hide[k]), m.groundHide[k] = float(groundHide[k]);
    for (std::size_t k = 0; k < show.size(); ++k) m.show[k] = float(show[k]);
    m.light = glm::vec3(light);
    m.sky = glm::vec3(sky);
    if (!parts->empty()) m.groundParts = std::move(parts);
    return m;
}

NormalApply normalApply(const NormalTransfer& t, const glm::dvec3& normal) {
    NormalApply out;
    if (!t.any) return out;
    constexpr int K = kShCoefficients;
    const auto a = irradianceFunctional(normal);
    for (int k = 0; k < K; ++k) {
        out.aHide[k] = float(a[k] + t.hide[k]);
        for (int ch = 0; ch < 3; ++ch)
            out.whole[std::size_t(k * 4 + ch)] =
                float(a[k] + t.hide[k] + t.show[std::size_t(ch * K + k)]);
    }
    out.light = t.light;
    out.sky = t.sky;
    out.lightEpoch = t.lightEpoch;
    out.any = true;
    return out;
}

namespace {

// applyNormalTransfer where the guard may act (rare: one point in a hundred on a drive) or the
// sum overflowed: the far field's own irradiance and what is hidden, the
// hidden part scaled where it would take the irradiance below min(0, a . L).
[[gnu::cold, gnu::noinline]] glm::vec3 guardedNormalApply(const NormalApply& t, const ShRgb& far,
                                                         const glm::vec3& normal,
                                                         const DirectionalLight& light) {
    constexpr int K = kShCoefficients;
    const auto y = shBasis(normal);
    glm::vec3 farE(0.0f), hidden(0.0f), whole(0.0f);
    for (int k = 0; k < K; ++k) {
        const float a = float(kAhatBand[shBand(k)]) * y[k];
        const glm::vec3& l = far.c[k];
        farE += a * l;
        hidden += (t.aHide[std::size_t(k)] - a) * l;
        whole += glm::vec3(t.whole[std::size_t(k * 4)], t.whole[std::size_t(k * 4 + 1)],
                           t.whole[std::size_t(k * 4 + 2)]) * l;
    }
    if (!t.any) return glm::max(farE, glm::vec3(0.0f));
    glm::vec3 e;
    for (int ch = 0; ch < 3; ++ch) {
        const float floor = std::min(farE[ch], 0.0f);
        float g = 1.0f;
        if (farE[ch] + hidden[ch] < floor && hidden[ch] < 0.0f)
            g = std::clamp((floor - farE[ch]) / hidden[ch], 0.0f, 1.0f);
        e[ch] = whole[ch] - (1.0f - g) * hidden[ch] + t.light[ch] * float(light.irradiance[ch]) +
                t.sky[ch];
    }
    if (!std::isfinite(e.x + e.y + e.z)) e = farE;
    return glm::max(e, glm::vec3(0.0f));
}

}  // namespace

glm::vec3 applyNormalTransfer(const NormalApply& t, const ShRgb& far, const glm::vec3& normal,
                              const DirectionalLight& light) {
    constexpr int K = kShCoefficients;
    if (!t.any) return glm::max(shIrradiance(far, normal), glm::vec3(0.0f));
    // Nine four-lane multiply-adds, the channels in lanes 0-2.
    Lanes e = {0.0f, 0.0f, 0.0f, 0.0f}, kept = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int k = 0; k < K; ++k) {
        const Lanes l = lanesOf(far.c[k]);
        Lanes w;
        std::memcpy(&w, &t.whole[std::size_t(4 * k)], sizeof w);
        e += w * l;
        kept += t.aHide[std::size_t(k)] * l;
    }
    // The unguarded sum where (a + h) . L_c >= 0 in every channel: then the guard cannot act.
    const glm::vec3 out(e[0] + t.light.x * float(light.irradiance.x) + t.sky.x,
                        e[1] + t.light.y * float(light.irradiance.y) + t.sky.y,
                        e[2] + t.light.z * float(light.irradiance.z) + t.sky.z);
    if (kept[0] >= 0.0f && kept[1] >= 0.0f && kept[2] >= 0.0f && std::isfinite(out.x + out.y + out.z))
        return glm::max(out, glm::vec3(0.0f));
    return guardedNormalApply(t, far, normal, light);
}

namespace {

// A sampled lower bound of min_n E(n): the minimum over a Fibonacci set of normals less
// (1/2) M2 delta^2, delta the set's covering radius and M2 a bound of E's second derivative along
// any great circle (Bernstein: l^2 max|E_l| per band, max|E_l| <= Ahat_l sqrt((2l+1)/4pi) |L_l|).
// At the true minimum the gradient vanishes, so the nearest sample is at most that much above it.
struct GuardSamples {
    std::vector<std::array<double, kShCoefficients>> ahatY;  // Ahat_l Y_k(n) per sample
    double halfDelta2 = 0.0;                                 // (1/2) delta^2
};

const GuardSamples& guardSamples() {
    static const GuardSamples g = [] {
        GuardSamples out;
        const auto fibonacci = [](int n) {
            std::vector<glm::dvec3> d;
            for (int i = 0; i < n; ++i) d.push_back(fibonacciDirection(i, n));
            return d;
        };
        const std::vector<glm::dvec3> samples = fibonacci(160);
        for (const glm::dvec3& n : samples) out.ahatY.push_back(irradianceFunctional(n));
        // The covering radius, measured on a much denser set, with a margin.
        double cover = 0.0;
        for (const glm::dvec3& p : fibonacci(20000)) {
            double best = -1.0;
            for (const glm::dvec3& n : samples) best = std::max(best, glm::dot(p, n));
            cover = std::max(cover, std::acos(std::min(1.0, best)));
        }
        cover *= 1.1;
        out.halfDelta2 = 0.5 * cover * cover;
        return out;
    }();
    return g;
}

// Per channel, the sampled lower bound of min_n E(n) (see above).
glm::dvec3 sampledLowerBound(const ShRgbD& sh) {
    const GuardSamples& g = guardSamples();
    glm::dvec3 bound;
    for (int ch = 0; ch < 3; ++ch) {
        double b1 = 0.0, b2 = 0.0;
        for (int k = 1; k < 4; ++k) b1 += sh.c[k][ch] * sh.c[k][ch];
        for (int k = 4; k < 9; ++k) b2 += sh.c[k][ch] * sh.c[k][ch];
        const double m2 = kShA1 * std::sqrt(3.0 / (4.0 * kPi)) * std::sqrt(b1) +
                          4.0 * kShA2 * std::sqrt(5.0 / (4.0 * kPi)) * std::sqrt(b2);
        double least = std::numeric_limits<double>::infinity();
        for (const auto& a : g.ahatY) {
            double e = 0.0;
            for (int k = 0; k < kShCoefficients; ++k) e += a[k] * sh.c[k][ch];
            least = std::min(least, e);
        }
        bound[ch] = least - g.halfDelta2 * m2;
    }
    return bound;
}

glm::dvec3 guardScale(const ShRgbD& far, const ShRgbD& hidden) {
    glm::dvec3 scale(1.0);
    const glm::dvec3 sampled = sampledLowerBound(hidden);
    if (sampled.x >= 0.0 && sampled.y >= 0.0 && sampled.z >= 0.0) return scale;
    const glm::dvec3 hiddenMin = shMinIrradiance(hidden);
    if (hiddenMin.x >= 0.0 && hiddenMin.y >= 0.0 && hiddenMin.z >= 0.0) return scale;
    const glm::dvec3 floor = glm::min(shMinIrradiance(far), glm::dvec3(0.0));
    for (int ch = 0; ch < 3; ++ch) {
        if (hiddenMin[ch] >= floor[ch]) continue;
        const auto mix = [&](double s) {
            ShRgbD m = far;
            for (int k = 0; k < kShCoefficients; ++k)
                m.c[k][ch] = far.c[k][ch] + s * (hidden.c[k][ch] - far.c[k][ch]);
            return m;
        };
        double lo = 0.0, hi = 1.0;
        for (int it = 0; it < 12; ++it) {
            const double mid = 0.5 * (lo + hi);
            (shMinIrradiance(mix(mid))[ch] >= floor[ch] ? lo : hi) = mid;
        }
        scale[ch] = lo;
    }
    return scale;
}

// Whether the guard found for t.guardFar is kept for `far`: while the far field stays within
// 25 % of it (coefficients, all channels; a point's far field moves that much only when new
// anchors arrive or the light changes). The scale found holds for the field's shape, which
// changes far less than its level; the draw clamps what is left.
bool stillGuarded(const NearFieldTransfer& t, const ShRgb& far) {
    float d = 0.0f, norm = 0.0f;
    for (int k = 0; k < kShCoefficients; ++k) {
        const glm::vec3 x = far.c[k] - t.guardFar.c[k];
        d += glm::dot(x, x);
        norm += glm::dot(t.guardFar.c[k], t.guardFar.c[k]);
    }
    return d <= 0.25f * 0.25f * norm;
}

}  // namespace

ShRgb applyTransfer(const NearFieldTransfer& t, const ShRgb& far, const DirectionalLight& light) {
    if (t.empty()) return far;
    constexpr int K = kShCoefficients;
    if (!t.guardValid || !stillGuarded(t, far)) {
        const ShRgbD farD = toDouble(far);
        ShRgbD hidden = farD;
        for (int j = 0; j < K; ++j)
            for (int k = 0; k < K; ++k)
                hidden.c[j] += double(t.hide[j * K + k] - t.groundHide[j * K + k]) * farD.c[k];
        t.guardScale = guardScale(farD, hidden);
        t.guardFar = far;
        t.guardValid = true;
    }
    // out[j] = far[j] + S[j] E + g[j] E_amb + sum_k T[j][k] far[k], the three channels in four
    // lanes: 81 four-lane multiply-adds.
    const Lanes e = lanesOf(glm::vec3(light.irradiance)), ambientE = lanesOf(t.groundAmbientE);
    Lanes out[K], f[K];
    for (int j = 0; j < K; ++j) {
        f[j] = lanesOf(far.c[j]);
        out[j] = f[j] + lanesOf(glm::vec3(t.s[0][j], t.s[1][j], t.s[2][j])) * e +
                 lanesOf(glm::vec3(t.groundShow[0][j], t.groundShow[1][j], t.groundShow[2][j])) *
                     ambientE;
    }
    for (int k = 0; k < K; ++k)
        for (int j = 0; j < K; ++j) {
            Lanes col;
            std::memcpy(&col, &t.columns[std::size_t((k * K + j) * 4)], sizeof col);
            out[j] += col * f[k];
        }
    ShRgb r;
    for (int j = 0; j < K; ++j) r.c[j] = glm::vec3(out[j][0], out[j][1], out[j][2]);
    // A guard that scaled: put back (1 - scale) of what is hidden.
    for (int ch = 0; ch < 3; ++ch) {
        const float unhide = float(1.0 - t.guardScale[ch]);
        if (unhide <= 0.0f) continue;
        for (int j = 0; j < K; ++j)
            for (int k = 0; k < K; ++k)
                r.c[j][ch] -= unhide * (t.hide[j * K + k] - t.groundHide[j * K + k]) * far.c[k][ch];
    }
    return r;
}

ShRgbD applyNearField(const ShRgbD& far, const glm::dvec3& point_m,
                      const std::vector<SphereOccluder>& occluders, const DirectionalLight& light,
                      const std::vector<HorizonWedge>& horizon, const GroundTerm* ground,
                      const HemisphereAmbient& ambient) {
    NearFieldTransfer t = nearFieldTransfer(nearOccluders(point_m, occluders, horizon), ground);
    updateLightTerm(t, light.direction, ambient);
    return toDouble(applyTransfer(t, toFloat(far), light));
}

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

// ---- [SECTION] Cache ---------------------------------------------------------------------------

namespace {
// A cached light term is remade when the light has moved more than 0.5 degrees.
const double kLightMoved = std::cos(0.5 * kPi / 180.0);

// The memory of one entry of each cache, the map's slot included.
constexpr std::size_t kMapSlot = 2 * sizeof(void*);
constexpr std::size_t kGroundEntryBytes = sizeof(std::array<float, 4>) + sizeof(GroundTerm) +
                                          sizeof(std::uint64_t) + kMapSlot;
constexpr std::size_t kNormalEntryBytes = sizeof(std::array<float, 4>) + sizeof(std::uint32_t) +
                                          kMapSlot + sizeof(NormalTransfer) +
                                          sizeof(NormalApply) + sizeof(std::uint64_t);
// A patch mean's entry holds its samples' ground light terms too.
std::size_t normalEntryBytes(const NormalTransfer& t) {
    return kNormalEntryBytes +
           (t.groundParts ? sizeof(std::vector<GroundLightPart>) + 2 * sizeof(void*) +
                                t.groundParts->size() * sizeof(GroundLightPart)
                          : 0);
}
constexpr std::size_t kSampleEntryBytes =
    sizeof(std::array<float, 4>) + sizeof(NormalTransfer) + kMapSlot;
std::size_t objectEntryBytes(const NearFieldTransfer* t) {
    return sizeof(std::array<float, 4>) + sizeof(void*) + sizeof(std::uint64_t) + kMapSlot +
           (t ? sizeof(NearFieldTransfer) : 0);
}

// The use below which the older half of `stamps` lies: entries used before it are dropped. If
// no use is older than the median (one batch asked them all), all of them.
std::uint64_t olderHalf(std::vector<std::uint64_t> stamps) {
    if (stamps.empty()) return 0;
    const auto mid = stamps.begin() + std::ptrdiff_t(stamps.size() / 2);
    std::nth_element(stamps.begin(), mid, stamps.end());
    const std::uint64_t cut = *mid;
    const bool older = std::any_of(stamps.begin(), stamps.end(),
                                   [cut](std::uint64_t u) { return u < cut; });
    return older ? cut : std::numeric_limits<std::uint64_t>::max();
}

// Erases the entries of `map` last used before olderHalf of their uses.
template <class Map, class Used>
void dropOlderHalf(Map& map, Used used) {
    std::vector<std::uint64_t> stamps;
    stamps.reserve(map.size());
    for (auto it = map.begin(); it != map.end(); ++it) stamps.push_back(used(it->second));
    const std::uint64_t cut = olderHalf(std::move(stamps));
    for (auto it = map.begin(); it != map.end();) it = used(it->second) < cut ? map.erase(it) : std::next(it);
}

}  // namespace

std::size_t NearField::KeyHash::operator()(const Key& k) const {
    std::uint32_t b[4];
    std::memcpy(b, k.data(), sizeof b);
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint32_t v : b) h = (h ^ v) * 1099511628211ull;
    // Mix the high bits down: lattice coordinates share their low mantissa bits, and the map
    // takes the low bits of the hash.
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return std::size_t(h);
}

NearField::NearField(const NearFieldScene& scene, const NearFieldSettings& settings)
    : scene_(scene), settings_(settings) {}

void NearField::setTimeOfDay(double timeOfDay_h) {
    const DirectionalLight l = scene_.mainLight(timeOfDay_h);
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::isfinite(l.direction.x + l.direction.y + l.direction.z) &&
        std::isfinite(l.irradiance.x + l.irradiance.y + l.irradiance.z)) {
        light_ = l;
        if (glm::dot(epochLight_, l.direction) < kLightMoved) {
            // The ambient follows the light's epochs: cached terms are remade with both.
            const HemisphereAmbient a = scene_.ambient(timeOfDay_h);
            const glm::dvec3 sum = a.sky + a.ground;
            if (std::isfinite(sum.x + sum.y + sum.z)) ambient_ = a;
            ++lightEpoch_, epochLight_ = l.direction;
        }
    }
}

void NearField::setViewer(const glm::dvec3& camera_m) {
    if (!std::isfinite(camera_m.x + camera_m.y + camera_m.z)) return;
    std::lock_guard<std::mutex> lock(mutex_);
    viewer_ = camera_m, viewerKnown_ = true;
}

bool NearField::blendsLattice(const glm::dvec3& p) const {
    // In three dimensions: a flight's ground point, 60 m below the camera, is not the car.
    return !viewerKnown_ || glm::length(p - viewer_) < settings_.latticeRange_m;
}

std::vector<SphereOccluder> NearField::occluders(const glm::dvec3& p) const {
    std::vector<SphereOccluder> out;
    if (!settings_.plants) return out;
    scene_.occludersNear(p, settings_.radius_m, settings_.smallRadius_m, out);
    return out;
}

std::unique_ptr<NearFieldTransfer> NearField::build(const glm::dvec3& p, double selfRadius_m,
                                                    const GroundTerm* objectGroundTerm,
                                                    const glm::dvec3* drawnNormal) const {
    std::vector<HorizonWedge> horizon;
    if (settings_.terrain && selfRadius_m <= 0.0)
        scene_.terrainNear(p, settings_.terrainRadius_m, horizon);
    if (drawnNormal && drawnNormal->y > 0.0) belowTangentPlaneOut(*drawnNormal, horizon);
    // The ground is shaded by every plant near it, the object's own included.
    std::vector<SphereOccluder> all = occluders(p);
    std::vector<SphereOccluder> others;
    if (selfRadius_m > 0.0) {
        // An object's own spheres sit on its axis, above its base.
        for (const SphereOccluder& o : all)
            if (std::hypot(o.centre_m.x - p.x, o.centre_m.z - p.z) >= selfRadius_m) others.push_back(o);
    }
    const std::vector<SphereOccluder>& caps0 = selfRadius_m > 0.0 ? others : all;
    GroundTerm ground;
    if (settings_.ground)
        ground = objectGroundTerm ? *objectGroundTerm
                 : selfRadius_m > 0.0 && blendsLattice(p)
                     ? objectGround(p)
                     : groundTerm(p, scene_, caps0, all, settings_.groundRadius_m, light_.direction,
                                  drawnNormal);
    std::vector<OccluderCap> caps = nearOccluders(p, caps0, horizon);
    if (caps.empty() && !ground.any) return nullptr;
    auto t = std::make_unique<NearFieldTransfer>(nearFieldTransfer(caps, &ground));
    updateLightTerm(*t, light_.direction, ambient_);
    return t;
}

void NearField::latticeOf(const glm::dvec3& p, Key keys[9], double weights[9],
                          glm::dvec3 points[9]) const {
    const double lift = p.y - scene_.groundHeight(p.x, p.z);
    // Quadratic B-spline weights of the three nearest lattice lines on each axis.
    const auto spline = [](double u, double w[3]) {
        const double f = u - std::round(u);
        w[0] = 0.5 * (0.5 - f) * (0.5 - f), w[1] = 0.75 - f * f, w[2] = 0.5 * (0.5 + f) * (0.5 + f);
        return std::round(u) - 1.0;
    };
    double wx[3], wz[3];
    const double cell = settings_.groundCell_m;
    const double i0 = spline(p.x / cell, wx), k0 = spline(p.z / cell, wz);
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double x = (i0 + a) * cell, z = (k0 + b) * cell;
            keys[a * 3 + b] = Key{float(x), -2e30f, float(z), float(lift)};
            weights[a * 3 + b] = wx[a] * wz[b];
            points[a * 3 + b] = glm::dvec3(x, lift, z);  // the lift for now (see latticeTerm)
        }
}

GroundTerm NearField::latticeTerm(const glm::dvec3& at) const {
    const glm::dvec3 q(at.x, scene_.groundHeight(at.x, at.z) + at.y, at.z);
    // No plant stops the rays from a lattice point: one standing at it would take its ground out
    // of the blend for an object that does not see that plant.
    return groundTerm(q, scene_, {}, occluders(q), settings_.groundRadius_m, light_.direction);
}

NormalTransfer NearField::groundSample(double x_m, double z_m) const {
    GroundPoint g;
    if (!scene_.groundAt(x_m, z_m, g)) {
        g.height_m = scene_.groundHeight(x_m, z_m);
        g.normal = glm::dvec3(0.0, 1.0, 0.0);
    }
    if (!std::isfinite(g.height_m) || !std::isfinite(g.normal.x + g.normal.y + g.normal.z)) return {};
    const std::unique_ptr<NearFieldTransfer> full =
        build(glm::dvec3(x_m, g.height_m + kShadingHeight_m, z_m), 0.0, nullptr, &g.normal);
    NormalTransfer nt = normalTransfer(full.get(), g.normal);
    if (full) updateLightTerm(nt, light_.direction, ambient_, lightEpoch_);
    return nt;
}

GroundTerm NearField::objectGround(const glm::dvec3& p) const {
    Key keys[9];
    double weights[9];
    glm::dvec3 points[9];
    latticeOf(p, keys, weights, points);
    if (groundCache_.size() + 9 > std::size_t(settings_.cacheEntries)) evictGround();
    const std::uint64_t now = ++uses_;
    for (int i = 0; i < 9; ++i) {
        if (auto it = groundCache_.find(keys[i]); it != groundCache_.end()) {
            it.value().used = now;
            continue;
        }
        groundCache_.emplace(keys[i], CachedGround{latticeTerm(points[i]), now});
        groundBytes_ += kGroundEntryBytes;
    }
    // Looked up only once all nine are in: an insertion may move the map's entries.
    const GroundTerm* terms[9];
    for (int i = 0; i < 9; ++i) terms[i] = &groundCache_.find(keys[i])->second.term;
    return blendGroundTerms(terms, weights, 9);
}

void NearField::buildObjects(std::size_t count, const Key* keys, const glm::dvec3* points_m,
                             double selfRadius_m) const {
    // The points not in the cache, each once.
    std::vector<std::size_t> missing;
    {
        tsl::hopscotch_map<Key, char, KeyHash> seen;
        for (std::size_t i = 0; i < count; ++i) {
            const glm::dvec3& p = points_m[i];
            if (!std::isfinite(p.x + p.y + p.z) || !std::isfinite(double(keys[i][0]) + keys[i][2]))
                continue;
            if (cache_.count(keys[i]) || !seen.emplace(keys[i], 0).second) continue;
            missing.push_back(i);
        }
    }
    if (missing.size() < 2) return;  // applyLocked builds a lone point itself
    const auto b0 = std::chrono::steady_clock::now();
    // An object's ground blends lattice terms: the missing ones first, on every thread.
    std::vector<GroundTerm> grounds(missing.size());
    std::vector<char> lattice(missing.size(), 0);
    for (std::size_t m = 0; m < missing.size(); ++m)
        lattice[m] = settings_.ground && selfRadius_m > 0.0 && blendsLattice(points_m[missing[m]]);
    if (std::find(lattice.begin(), lattice.end(), 1) != lattice.end()) {
        std::vector<Key> latticeKeys;
        std::vector<glm::dvec3> latticeAt;
        tsl::hopscotch_map<Key, char, KeyHash> seen;
        for (std::size_t m = 0; m < missing.size(); ++m) {
            if (!lattice[m]) continue;
            const std::size_t i = missing[m];
            Key k[9];
            double w[9];
            glm::dvec3 at[9];
            latticeOf(points_m[i], k, w, at);
            for (int j = 0; j < 9; ++j)
                if (!groundCache_.count(k[j]) && seen.emplace(k[j], 0).second)
                    latticeKeys.push_back(k[j]), latticeAt.push_back(at[j]);
        }
        if (groundCache_.size() + latticeKeys.size() + 9 > std::size_t(settings_.cacheEntries))
            evictGround();
        std::vector<GroundTerm> terms(latticeKeys.size());
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(std::size_t(0), terms.size(),
                              [&](std::size_t j) { terms[j] = latticeTerm(latticeAt[j]); });
        });
        const std::uint64_t now = ++uses_;
        for (std::size_t j = 0; j < terms.size(); ++j) {
            groundCache_.emplace(latticeKeys[j], CachedGround{terms[j], now});
            groundBytes_ += kGroundEntryBytes;
        }
        for (std::size_t m = 0; m < missing.size(); ++m)
            if (lattice[m]) grounds[m] = objectGround(points_m[missing[m]]);
    }
    // Then the transfers, which read only the scene, the light and those terms.
    std::vector<std::unique_ptr<NearFieldTransfer>> built(missing.size());
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(std::size_t(0), missing.size(), [&](std::size_t m) {
            built[m] = build(points_m[missing[m]], selfRadius_m,
                             lattice[m] ? &grounds[m] : nullptr);
        });
    });
    if (cache_.size() + missing.size() > std::size_t(settings_.cacheEntries)) evictObjects();
    const std::uint64_t now = ++uses_;
    for (std::size_t m = 0; m < missing.size(); ++m) {
        bytes_ += objectEntryBytes(built[m].get());
        cache_.emplace(keys[missing[m]], Cached{std::move(built[m]), now});
    }
    builds_ += missing.size();
    buildSeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
}

ShRgb NearField::apply(const ShRgb& far, const glm::dvec3& point_m, double selfRadius_m) const {
    const Key key{float(point_m.x), float(point_m.y), float(point_m.z), float(selfRadius_m)};
    return applyKeyed(far, key, [&] { return point_m; }, selfRadius_m);
}

ShRgb NearField::applyAbove(const ShRgb& far, double x_m, double z_m, double height_m,
                            double selfRadius_m) const {
    // A key no explicit point has (a height of -1e30): one NearField uses one lift.
    const Key key{float(x_m), -1e30f, float(z_m), float(selfRadius_m)};
    return applyKeyed(
        far, key, [&] { return glm::dvec3(x_m, scene_.groundHeight(x_m, z_m) + height_m, z_m); },
        selfRadius_m);
}

ShRgb NearField::applyKeyed(const ShRgb& far, const Key& key,
                            const std::function<glm::dvec3()>& point, double selfRadius_m) const {
    if (!settings_.enabled) return far;
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    const ShRgb out = applyLocked(far, key, point, selfRadius_m);
    ++points_;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

void NearField::applyMany(std::size_t count, ShRgb* inOut, const glm::dvec3* points_m) const {
    if (!settings_.enabled || count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Key> keys(count);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3& p = points_m[i];
        keys[i] = Key{float(p.x), float(p.y), float(p.z), 0.0f};
    }
    buildObjects(count, keys.data(), points_m, 0.0);
    for (std::size_t i = 0; i < count; ++i)
        inOut[i] = applyLocked(inOut[i], keys[i], [&] { return points_m[i]; }, 0.0);
    points_ += count;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void NearField::applyAboveMany(std::size_t count, ShRgb* inOut, const double* x_m,
                               const double* z_m, double height_m, double selfRadius_m) const {
    if (!settings_.enabled || count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Key> keys(count);
    std::vector<glm::dvec3> points(count);
    for (std::size_t i = 0; i < count; ++i) {
        const double x = x_m[i], z = z_m[i];
        keys[i] = Key{float(x), -1e30f, float(z), float(selfRadius_m)};
        // The ground's height only for points not yet cached (as applyAbove).
        points[i] = cache_.count(keys[i])
                        ? glm::dvec3(x, 0.0, z)
                        : glm::dvec3(x, scene_.groundHeight(x, z) + height_m, z);
    }
    buildObjects(count, keys.data(), points.data(), selfRadius_m);
    for (std::size_t i = 0; i < count; ++i)
        inOut[i] = applyLocked(inOut[i], keys[i], [&] { return points[i]; }, selfRadius_m);
    points_ += count;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::uint32_t NearField::addNormalEntry(const Key& key, const NormalTransfer& transfer,
                                       const NormalApply& apply) const {
    const std::uint32_t index = std::uint32_t(normalTransfers_.size());
    normalTransfers_.push_back(transfer);
    normalApplies_.push_back(apply);
    normalUsed_.push_back(uses_);
    normalBytes_ += normalEntryBytes(transfer);
    normalCache_.emplace(key, index);
    return index;
}

void NearField::irradianceMany(std::size_t count, const ShRgb* far, const glm::dvec3* points_m,
                               const glm::dvec3* normals, glm::vec3* out, const double* weights,
                               const double* patch_m) const {
    if (count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    static const NormalApply none;
    std::lock_guard<std::mutex> lock(mutex_);
    ++uses_;
    // A terrain corner's patch size when it takes the patch mean, else 0 (see Patch mean).
    const auto patchOf = [&](std::size_t i) {
        return settings_.patchMean && patch_m && patch_m[i] > 0.0 && patch_m[i] < 1e6
                   ? patch_m[i]
                   : 0.0;
    };
    const auto keyOf = [&](std::size_t i) {
        const glm::dvec3& p = points_m[i];
        return Key{float(p.x), float(p.y), float(p.z), -1.0f - float(patchOf(i))};
    };
    // The sequence this batch follows: the one that began with the same point, else the least
    // recently used.
    const auto sequenceOf = [&]() {
        Sequence* seq = &sequences_[0];
        const Key first = keyOf(0);
        for (Sequence& q : sequences_) {
            if (!q.keys.empty() && q.first == first) return &q;
            if (q.used < seq->used) seq = &q;
        }
        return seq;
    };
    constexpr std::uint32_t kNone = ~0u;      // a point not asked of the cache (disabled, not finite)
    constexpr std::uint32_t kMissing = ~1u;   // a point with no entry yet
    constexpr std::size_t kLookAhead = 16;    // points dropped from the batch since last time
    // This batch's keys and indices go into buffers kept from the last batch (no allocation).
    std::vector<Key>& keys = batchKeys_;
    std::vector<std::uint32_t>& at = batchAt_;
    std::vector<std::size_t>& missing = batchMissing_;
    Sequence* seq = nullptr;
    // Every point's entry, found on its sequence or in the map, or kMissing; the points without
    // an entry in `missing` (each key once).
    const auto find = [&]() {
        seq = sequenceOf();
        keys.clear(), at.assign(count, kNone), missing.clear();
        keys.reserve(count);
        std::size_t cursor = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const glm::dvec3& p = points_m[i];
            const glm::dvec3& n = normals[i];
            if (!settings_.enabled || !std::isfinite(p.x + p.y + p.z) ||
                !std::isfinite(n.x + n.y + n.z) || (weights && !(weights[i] > 0.0))) {
                keys.push_back(Key{});
                continue;
            }
            const Key key = keyOf(i);
            keys.push_back(key);
            bool found = false;
            for (std::size_t d = 0; d < kLookAhead && cursor + d < seq->keys.size(); ++d) {
                if (seq->keys[cursor + d] == key) {
                    at[i] = seq->index[cursor + d];
                    cursor += d + 1;
                    found = true;
                    break;
                }
            }
            if (found) {
                // A point on a sequence last asked under this light has its light term already
                // (its entry counts as used when the cache is full: see evictNormals).
                if (seq->lightEpoch == lightEpoch_) continue;
            } else {
                auto it = normalCache_.find(key);
                if (it == normalCache_.end()) {
                    at[i] = kMissing;
                    missing.push_back(i);
                    continue;
                }
                at[i] = it->second;
                normalUsed_[at[i]] = uses_;
            }
            NormalApply& na = normalApplies_[at[i]];
            if (na.any && na.lightEpoch != lightEpoch_) {
                NormalTransfer& nt = normalTransfers_[at[i]];
                updateLightTerm(nt, light_.direction, ambient_, lightEpoch_);
                na.light = nt.light, na.sky = nt.sky, na.lightEpoch = nt.lightEpoch;
            }
        }
    };
    find();
    if (!missing.empty()) {
        // Room first: evicting moves the kept entries (and clears the sequences), so the batch
        // is found again. A batch larger than the cache's room stays whole until the next.
        if (normalCache_.size() + missing.size() > std::size_t(settings_.cacheEntries)) {
            evictNormals();
            find();
        }
        const auto b0 = std::chrono::steady_clock::now();
        // A point asked twice in one batch is built once.
        std::vector<std::size_t>& unique = batchUnique_;
        unique.clear();
        {
            tsl::hopscotch_map<Key, std::uint32_t, KeyHash> first;
            for (std::size_t i : missing)
                if (first.emplace(keys[i], std::uint32_t(unique.size())).second) unique.push_back(i);
        }
        // A patch mean's samples (see Patch mean): its offsets a side and their tent weights.
        const int m = std::max(1, settings_.patchSamples);
        std::vector<double> offset(static_cast<std::size_t>(m)), tent(static_cast<std::size_t>(m));
        double tentSum = 0.0;
        for (int j = 0; j < m; ++j) {
            offset[std::size_t(j)] = -1.0 + 2.0 * (j + 1) / (m + 1);  // times the patch size
            tentSum += tent[std::size_t(j)] = 1.0 - std::abs(offset[std::size_t(j)]);
        }
        for (double& w : tent) w /= tentSum;
        const auto sampleAt = [&](std::size_t i, int j) {
            const double p = patchOf(i);
            return glm::dvec2(points_m[i].x + offset[std::size_t(j % m)] * p,
                              points_m[i].z + offset[std::size_t(j / m)] * p);
        };
        const auto sampleKey = [](const glm::dvec2& q) {
            return Key{float(q.x), float(q.y), 0.0f, 0.0f};
        };
        // The samples not cached yet, each once.
        std::vector<glm::dvec2> toSample;
        {
            if (sampleCache_.size() > std::size_t(settings_.cacheEntries)) sampleCache_.clear();
            tsl::hopscotch_map<Key, std::uint32_t, KeyHash> queued;
            for (std::size_t i : unique) {
                if (patchOf(i) <= 0.0) continue;
                for (int j = 0; j < m * m; ++j) {
                    const glm::dvec2 q = sampleAt(i, j);
                    const Key k = sampleKey(q);
                    if (sampleCache_.find(k) == sampleCache_.end() &&
                        queued.emplace(k, std::uint32_t(toSample.size())).second)
                        toSample.push_back(q);
                }
            }
        }
        // The builds only read the scene and the light: on every thread (a corner's is ~0.2 ms,
        // and a frame that refines patches asks hundreds). A patch mean is put together after.
        std::vector<NormalTransfer> transfers(unique.size()), samples(toSample.size());
        std::vector<NormalApply> applies(unique.size());
        std::size_t pointBuilds = 0;
        for (std::size_t i : unique) pointBuilds += patchOf(i) > 0.0 ? 0 : 1;
        const auto buildOne = [&](std::size_t u) {
            if (u >= unique.size()) {
                const glm::dvec2& q = toSample[u - unique.size()];
                samples[u - unique.size()] = groundSample(q.x, q.y);
                return;
            }
            const std::size_t i = unique[u];
            if (patchOf(i) > 0.0) return;
            // Nothing near: the entry has no transfer (any = false) and answers the far field.
            const std::unique_ptr<NearFieldTransfer> full =
                build(points_m[i], 0.0, nullptr, &normals[i]);
            NormalTransfer& nt = transfers[u];
            nt = normalTransfer(full.get(), normals[i]);
            if (full) updateLightTerm(nt, light_.direction, ambient_, lightEpoch_);
            applies[u] = normalApply(nt, normals[i]);
        };
        const std::size_t tasks = unique.size() + toSample.size();
        if (tasks == 1) {
            buildOne(0);
        } else {
            tbb::this_task_arena::isolate([&] {
                tbb::parallel_for(std::size_t(0), tasks, buildOne);
            });
        }
        for (std::size_t k = 0; k < toSample.size(); ++k)
            sampleCache_.emplace(sampleKey(toSample[k]), std::move(samples[k]));
        std::vector<const NormalTransfer*> meanOf(std::size_t(m * m));
        std::vector<double> meanWeight(std::size_t(m * m));
        for (std::size_t u = 0; u < unique.size(); ++u) {
            const std::size_t i = unique[u];
            if (patchOf(i) <= 0.0) continue;
            for (int j = 0; j < m * m; ++j) {
                auto it = sampleCache_.find(sampleKey(sampleAt(i, j)));
                NormalTransfer& sample = it.value();
                if (sample.any && sample.lightEpoch != lightEpoch_)
                    updateLightTerm(sample, light_.direction, ambient_, lightEpoch_);
                meanOf[std::size_t(j)] = &sample;
                meanWeight[std::size_t(j)] = tent[std::size_t(j % m)] * tent[std::size_t(j / m)];
            }
            transfers[u] = meanNormalTransfer(meanOf.data(), meanWeight.data(), meanOf.size());
            transfers[u].lightEpoch = lightEpoch_;
            applies[u] = normalApply(transfers[u], normals[i]);
        }
        for (std::size_t u = 0; u < unique.size(); ++u)
            addNormalEntry(keys[unique[u]], transfers[u], applies[u]);
        for (std::size_t i : missing) at[i] = normalCache_.find(keys[i])->second;
        builds_ += pointBuilds + toSample.size();
        buildSeconds_ +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
    }
    // The sums only read: on two threads for a frame's corners (a sum is ~30 ns).
    const auto answer = [&](std::size_t i) {
        const glm::vec3 n(normals[i]);
        if (at[i] == kNone) {
            out[i] = applyNormalTransfer(none, far[i], n, light_);
            return;
        }
        out[i] = applyNormalTransfer(normalApplies_[at[i]], far[i], n, light_);
        if (weights && weights[i] < 1.0)
            out[i] = glm::mix(applyNormalTransfer(none, far[i], n, light_), out[i],
                              float(weights[i]));
    };
    constexpr std::size_t kGrain = 2048;
    if (count <= kGrain) {
        for (std::size_t i = 0; i < count; ++i) answer(i);
    } else {
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i) answer(i);
                              });
        });
    }
    // The points asked of the cache become the batch's sequence.
    std::vector<std::uint32_t>& indices = batchIndex_;
    indices.clear();
    std::size_t kept = 0;
    for (std::size_t i = 0; i < count; ++i)
        if (at[i] != kNone) keys[kept++] = keys[i], indices.push_back(at[i]);
    keys.resize(kept);
    seq->keys.swap(keys), seq->index.swap(indices);
    seq->first = keyOf(0);
    seq->used = uses_;  // this batch's reading of the use clock
    seq->lightEpoch = lightEpoch_;
    points_ += count;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

ShRgb NearField::applyLocked(const ShRgb& far, const Key& key,
                             const std::function<glm::dvec3()>& point, double selfRadius_m) const {
    if (!std::isfinite(double(key[0]) + double(key[2]))) return far;
    const NearFieldTransfer* t = nullptr;
    const std::uint64_t now = ++uses_;
    auto it = cache_.find(key);
    if (it == cache_.end()) {
        const glm::dvec3 p = point();
        if (!std::isfinite(p.x + p.y + p.z)) return far;
        if (cache_.size() >= std::size_t(settings_.cacheEntries)) evictObjects();
        const auto b0 = std::chrono::steady_clock::now();
        std::unique_ptr<NearFieldTransfer> built = build(p, selfRadius_m);
        bytes_ += objectEntryBytes(built.get());
        t = cache_.emplace(key, Cached{std::move(built), now}).first->second.transfer.get();
        ++builds_;
        buildSeconds_ +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
    } else {
        it.value().used = now;
        t = it->second.transfer.get();
        if (t && glm::dot(t->lightDirection, light_.direction) < kLightMoved)
            updateLightTerm(*it.value().transfer, light_.direction, ambient_);
    }
    if (!t) return far;
    const ShRgb near = applyTransfer(*t, far, light_);
    // Never NaN: a far field that overflows keeps its own value.
    for (const auto& c : near.c)
        if (!std::isfinite(c.x + c.y + c.z)) return far;
    return near;
}

void NearField::evictObjects() const {
    dropOlderHalf(cache_, [](const Cached& c) { return c.used; });
    bytes_ = 0;
    for (auto it = cache_.begin(); it != cache_.end(); ++it)
        bytes_ += objectEntryBytes(it->second.transfer.get());
}

void NearField::evictGround() const {
    dropOlderHalf(groundCache_, [](const CachedGround& c) { return c.used; });
    groundBytes_ = groundCache_.size() * kGroundEntryBytes;
}

void NearField::evictNormals() const {
    // The last batches' entries were used when those batches were asked (irradianceMany marks
    // only the entries it finds off its sequences).
    for (const Sequence& q : sequences_)
        for (std::uint32_t i : q.index)
            if (i < normalUsed_.size()) normalUsed_[i] = std::max(normalUsed_[i], q.used);
    // The kept entries move down in their vectors; the map follows.
    const std::uint64_t cut = olderHalf(normalUsed_);
    constexpr std::uint32_t kGone = ~0u;
    std::vector<std::uint32_t> moved(normalUsed_.size(), kGone);
    std::uint32_t kept = 0;
    for (std::size_t i = 0; i < normalUsed_.size(); ++i) {
        if (normalUsed_[i] < cut) continue;
        normalTransfers_[kept] = normalTransfers_[i];
        normalApplies_[kept] = normalApplies_[i];
        normalUsed_[kept] = normalUsed_[i];
        moved[i] = kept++;
    }
    normalTransfers_.resize(kept), normalApplies_.resize(kept), normalUsed_.resize(kept);
    for (auto it = normalCache_.begin(); it != normalCache_.end();) {
        const std::uint32_t to = moved[it->second];
        if (to == kGone) {
            it = normalCache_.erase(it);
        } else {
            it.value() = to;
            ++it;
        }
    }
    normalBytes_ = 0;
    for (const NormalTransfer& t : normalTransfers_) normalBytes_ += normalEntryBytes(t);
    // The sequences' indices are stale (see irradianceMany).
    for (Sequence& q : sequences_) q.keys.clear(), q.index.clear();
}

std::size_t NearField::cachedPoints() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cache_.size() + normalCache_.size() + groundCache_.size() + sampleCache_.size();
}

std::size_t NearField::cacheBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return bytes_ + normalBytes_ + groundBytes_ + sampleCache_.size() * kSampleEntryBytes;
}

double NearField::seconds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return seconds_;
}

std::size_t NearField::points() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return points_;
}

std::size_t NearField::builds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return builds_;
}

double NearField::buildSeconds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return buildSeconds_;
}

void NearField::resetCounters() {
    std::lock_guard<std::mutex> lock(mutex_);
    seconds_ = buildSeconds_ = 0.0;
    points_ = builds_ = 0;
}

// ---- [SECTION] The decorator -------------------------------------------------------------------

NearFieldMethod::NearFieldMethod(std::unique_ptr<AmbienceMethod> far,
                                 std::unique_ptr<NearFieldScene> scene,
                                 const NearFieldSettings& settings)
    : far_(std::move(far)),
      scene_(std::move(scene)),
      near_(std::make_unique<NearField>(*scene_, settings)),
      skyDetail_(settings.terrain && settings.vertexDetail) {
    AMB_CHECK(far_ && scene_);
}

NearFieldMethod::~NearFieldMethod() = default;

void NearFieldMethod::predictStage(const glm::dvec3& cameraPosition_m,
                                   const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                                   double dt_s) {
    near_->resetCounters();
    if (std::isfinite(timeOfDay_h)) near_->setTimeOfDay(timeOfDay_h);
    if (std::isfinite(cameraPosition_m.x + cameraPosition_m.z)) {
        camera_m_ = cameraPosition_m;
        near_->setViewer(cameraPosition_m);
    }
    far_->predictStage(cameraPosition_m, cameraVelocity_mps, timeOfDay_h, dt_s);
}

namespace {

// far + w (near - far): the near field faded in by w (see Range).
ShRgb fadedNear(const ShRgb& far, const ShRgb& near, double w) {
    return w >= 1.0 ? near : lerp(far, near, float(w));
}

}  // namespace

double NearFieldMethod::weight(double x_m, double z_m, double range_m) const {
    return rangeWeight(std::hypot(x_m - camera_m_.x, z_m - camera_m_.z), range_m);
}

ShRgb NearFieldMethod::shAt(double x_m, double z_m) const {
    const ShRgb far = far_->shAt(x_m, z_m);
    const double w = weight(x_m, z_m, near_->settings().objectRange_m);
    if (w <= 0.0) return far;
    return fadedNear(far, near_->applyAbove(far, x_m, z_m, kShadingHeight_m, kSelfRadius_m), w);
}

void NearFieldMethod::gather(std::size_t count, const double* x_m, const double* z_m,
                             const ShRgb* far, double range_m) const {
    nearIndex_.clear(), nearX_.clear(), nearZ_.clear(), nearSh_.clear(), nearWeight_.clear();
    for (std::size_t i = 0; i < count; ++i) {
        const double w = weight(x_m[i], z_m[i], range_m);
        if (w <= 0.0) continue;
        nearIndex_.push_back(i), nearX_.push_back(x_m[i]), nearZ_.push_back(z_m[i]);
        nearSh_.push_back(far[i]), nearWeight_.push_back(w);
    }
}

void NearFieldMethod::scatter(ShRgb* out) const {
    for (std::size_t j = 0; j < nearIndex_.size(); ++j)
        out[nearIndex_[j]] = fadedNear(out[nearIndex_[j]], nearSh_[j], nearWeight_[j]);
}

void NearFieldMethod::shAt(std::size_t count, const double* x_m, const double* z_m,
                           ShRgb* out) const {
    far_->shAt(count, x_m, z_m, out);
    gather(count, x_m, z_m, out, near_->settings().objectRange_m);
    near_->applyAboveMany(nearSh_.size(), nearSh_.data(), nearX_.data(), nearZ_.data(),
                          kShadingHeight_m, kSelfRadius_m);
    scatter(out);
}

ShRgb NearFieldMethod::cornerShAt(double x_m, double z_m) const {
    const ShRgb far = far_->cornerShAt(x_m, z_m);
    const double w = weight(x_m, z_m, near_->settings().cornerRange_m);
    if (w <= 0.0) return far;
    return fadedNear(far, near_->applyAbove(far, x_m, z_m, kShadingHeight_m), w);
}

void NearFieldMethod::cornerShAt(std::size_t count, const double* x_m, const double* z_m,
                                 ShRgb* out) const {
    far_->cornerShAt(count, x_m, z_m, out);
    gather(count, x_m, z_m, out, near_->settings().cornerRange_m);
    near_->applyAboveMany(nearSh_.size(), nearSh_.data(), nearX_.data(), nearZ_.data(),
                          kShadingHeight_m);
    scatter(out);
}

ShRgb NearFieldMethod::cornerShAtPoint(const glm::dvec3& point_m) const {
    const ShRgb far = far_->cornerShAt(point_m.x, point_m.z);
    const double w = weight(point_m.x, point_m.z, near_->settings().cornerRange_m);
    if (w <= 0.0) return far;
    return fadedNear(far, near_->apply(far, point_m), w);
}

void NearFieldMethod::cornerShAtPoints(std::size_t count, const glm::dvec3* points_m,
                                       ShRgb* out) const {
    std::vector<double> x(count), z(count);
    for (std::size_t i = 0; i < count; ++i) x[i] = points_m[i].x, z[i] = points_m[i].z;
    far_->cornerShAt(count, x.data(), z.data(), out);
    gather(count, x.data(), z.data(), out, near_->settings().cornerRange_m);
    std::vector<glm::dvec3> points;
    points.reserve(nearIndex_.size());
    for (std::size_t i : nearIndex_) points.push_back(points_m[i]);
    near_->applyMany(points.size(), nearSh_.data(), points.data());
    scatter(out);
}

void NearFieldMethod::cornerIrradianceAtPoints(std::size_t count, const glm::dvec3* points_m,
                                               const glm::dvec3* normals, glm::vec3* out,
                                               const double* patch_m) const {
    std::vector<double> x(count), z(count);
    for (std::size_t i = 0; i < count; ++i) x[i] = points_m[i].x, z[i] = points_m[i].z;
    std::vector<ShRgb> far(count);
    far_->cornerShAt(count, x.data(), z.data(), far.data());
    // Every point's far-field irradiance (what the far method alone gives, not the near field's
    // time); the near field's answers replace it within range.
    for (std::size_t i = 0; i < count; ++i)
        out[i] = glm::max(shIrradiance(far[i], glm::vec3(normals[i])), glm::vec3(0.0f));
    gather(count, x.data(), z.data(), far.data(), near_->settings().cornerRange_m);
    std::vector<glm::dvec3> points, pointNormals;
    nearPatch_.clear();
    for (std::size_t i : nearIndex_) {
        points.push_back(points_m[i]), pointNormals.push_back(normals[i]);
        nearPatch_.push_back(patch_m ? patch_m[i] : 0.0);
    }
    std::vector<glm::vec3> near(points.size());
    near_->irradianceMany(points.size(), nearSh_.data(), points.data(), pointNormals.data(),
                          near.data(), nearWeight_.data(), nearPatch_.data());
    for (std::size_t j = 0; j < nearIndex_.size(); ++j) out[nearIndex_[j]] = near[j];
}

MethodStatistics NearFieldMethod::methodStatistics() const {
    MethodStatistics s = far_->methodStatistics();
    s.nearField_s = near_->seconds();
    s.nearFieldPoints = near_->points();
    s.nearFieldBuilds = near_->builds();
    s.nearFieldBuild_s = near_->buildSeconds();
    s.nearFieldCached = near_->cachedPoints();
    s.nearFieldBytes = near_->cacheBytes();
    return s;
}

}  // namespace amb
