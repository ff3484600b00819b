// NearFieldTransfer.cpp — the near field's closed forms and its transfer: caps, terrain bands,
// the transfer of a point and how it is applied to the far field (NearField.h).
#include "lighting/NearField.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Sky.h"

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
        c.sunVisibility = std::clamp(si.occluder->sunVisibility, 0.0, 1.0);
        c.skyVisibility = std::clamp(si.occluder->skyVisibility, 0.0, 1.0);
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
                u[ch][k] = float(e.skyVisibility * e.albedo[ch] * shows[i][k] -
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

double capSunVisibility(const std::vector<OccluderCap>& caps, const glm::dvec3& lightDirection) {
    // Each weighted by what it shows of the light: w Omega rho Phi(alpha), alpha between the
    // light and the cap's face towards the point (-direction); a band as a cap at full phase.
    double shown = 0.0, lit = 0.0;
    for (const OccluderCap& c : caps) {
        const double rho = (c.albedo.x + c.albedo.y + c.albedo.z) / 3.0;
        const double phase =
            c.band ? 1.0
                   : lambertSpherePhase(std::acos(std::clamp(-glm::dot(c.direction, lightDirection), -1.0, 1.0)));
        const double f = c.weight * c.solidAngle * rho * phase;
        if (!(f > 0.0)) continue;
        // What T_c shows of it: its albedo scaled by its share of the sky (see Plants' sky).
        shown += f * (c.band ? 1.0 : std::clamp(c.skyVisibility, 0.0, 1.0));
        lit += f * (c.band ? 1.0 : std::clamp(c.sunVisibility, 0.0, 1.0));
    }
    return shown > 0.0 ? lit / shown : 1.0;
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
            t.s[ch][j] = float(v) * t.capSun;
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
    n.capSun = t->capSun;
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
        t.light[ch] = float(v) * t.capSun;
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
    double capSun = 0.0, weightSum = 0.0;  // the samples' shares, weighted as they are
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
        capSun += w * t.capSun, weightSum += w;
        m.lightEpoch = t.lightEpoch;
        m.any = true;
    }
    if (!m.any) return m;
    for (int k = 0; k < kShCoefficients; ++k)
        m.hide[k] = float(hide[k]), m.groundHide[k] = float(groundHide[k]);
    for (std::size_t k = 0; k < show.size(); ++k) m.show[k] = float(show[k]);
    m.light = glm::vec3(light);
    m.capSun = weightSum > 0.0 ? float(capSun / weightSum) : 1.0f;
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
    const std::vector<OccluderCap> caps = nearOccluders(point_m, occluders, horizon);
    NearFieldTransfer t = nearFieldTransfer(caps, ground);
    t.capSun = float(capSunVisibility(caps, light.direction));
    updateLightTerm(t, light.direction, ambient);
    return toDouble(applyTransfer(t, toFloat(far), light));
}

}  // namespace amb
