// AnchorField.cpp — hierarchical bicubic Hermite interpolation of the anchor store (see
// AnchorField.h).
#include "lighting/AnchorField.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace amb {

namespace {

constexpr int kN = 3 * kShCoefficients;  // floats in a coefficient set
constexpr double kOnCorner_m = 1e-9;     // a query this close to a lattice line is on it

void toFloats(const ShRgb& sh, float* out) {
    for (int k = 0; k < kShCoefficients; ++k)
        for (int ch = 0; ch < 3; ++ch) out[3 * k + ch] = sh.c[k][ch];
}

ShRgb fromFloats(const float* in) {
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k)
        for (int ch = 0; ch < 3; ++ch) sh.c[k][ch] = in[3 * k + ch];
    return sh;
}

// A slope from the differences on either side of a sample: their harmonic mean where they agree
// in sign (the central difference for equal ones, smaller near an extremum), 0 where they do not:
// a Hermite cubic with such slopes stays within its samples' range in one dimension. Continuous
// in the differences.
double harmonicSlope(double left, double right) {
    if (!(left * right > 0.0)) return 0.0;
    return 2.0 * left * right / (left + right);
}

// The smallest in magnitude of four values that agree in sign, else 0 (continuous).
double minMod4(const double* q) {
    double m = q[0];
    for (int n = 1; n < 4; ++n) {
        if (!(q[n] * m > 0.0)) return 0.0;
        if (std::fabs(q[n]) < std::fabs(m)) m = q[n];
    }
    return m;
}

// out = sum over the 4 corners q and their 4 blocks m (value, slopes, twist; kStride floats
// each, kStride x 4 per corner) of weight[4q + m] x block: the lookup's inner loop. The sum is
// kept local (in registers) and written once: summing into `out` made every step wait for the
// previous step's store (a third of a lookup). (An AVX2 clone of it measured no faster.)
void blend16(const float* const corner[4], const float* __restrict weight,
             float* __restrict out) {
    constexpr int kStride = 28;
    float sum[kStride] = {};
    for (int q = 0; q < 4; ++q) {
        for (int m = 0; m < 4; ++m) {
            const float wm = weight[4 * q + m];
            const float* __restrict block = corner[q] + m * kStride;
            for (int j = 0; j < kStride; ++j) sum[j] += wm * block[j];
        }
    }
    for (int j = 0; j < kStride; ++j) out[j] = sum[j];
}

// floor() for |v| < 2^62 without a library call.
std::int64_t floorToInt(double v) {
    const std::int64_t i = std::int64_t(v);
    return double(i) > v ? i - 1 : i;
}

std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

}  // namespace

std::size_t AnchorField::CellKeyHash::operator()(const CellKey& c) const {
    return hashLatticeCell(c.i, c.k);
}

void AnchorField::CellMap::insert(const CellKey& c, const CellRef& ref) {
    const auto block = blocks.try_emplace(CellKey{c.i >> kBlockShift, c.k >> kBlockShift},
                                          std::uint32_t(refs.size()));
    if (block.second)
        refs.resize(refs.size() + (std::size_t(1) << (2 * kBlockShift)), {kNoCell, kNoCell});
    CellRef& r = refs[block.first->second +
                      std::size_t(((c.k & kBlockMask) << kBlockShift) | (c.i & kBlockMask))];
    if (r.row0 == kNoCell) ++count;
    r = ref;
}

std::size_t AnchorField::CellMap::bytes() const {
    return blocks.bucket_count() *
               (sizeof(std::pair<CellKey, std::uint32_t>) + sizeof(std::uint64_t)) +
           refs.capacity() * sizeof(CellRef);
}

std::size_t AnchorField::cells() const {
    std::size_t n = 0;
    for (const CellMap& m : cells_) n += m.count;
    return n;
}

std::size_t AnchorField::bytes() const {
    std::size_t b = sizeof(*this) + points_.capacity() * sizeof(float);
    for (const CellMap& m : cells_) b += m.bytes();
    b += levelsIn_.bucket_count() *
         (sizeof(std::pair<CellKey, std::uint32_t>) + sizeof(std::uint64_t));
    return b;
}

std::array<double, 4> AnchorField::hermite(double t, bool derivative) {
    const double t2 = t * t, t3 = t2 * t;
    if (derivative)
        return {6.0 * t2 - 6.0 * t, 3.0 * t2 - 4.0 * t + 1.0, -6.0 * t2 + 6.0 * t, 3.0 * t2 - 2.0 * t};
    return {2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, -2.0 * t3 + 3.0 * t2, t3 - t2};
}

std::array<double, 27> AnchorField::slopeBound() const {
    std::array<double, 27> bound{};
    for (int L = 0; L < lattice_.levels; ++L)
        for (int j = 0; j < kN; ++j) bound[j] = std::max(bound[j], slope_[L][j]);
    return bound;
}

void AnchorField::rebuild(const FieldLattice& lattice, const std::vector<FieldAnchor>& anchors,
                          const ShRgb& fallback, int fromLevel) {
    // All of it: the first time, a new kind of cell, or finer anchors informing coarser levels.
    if (!built_ || lattice.smooth != lattice_.smooth || lattice.finerWeight > 0.0) fromLevel = 0;
    lattice_ = lattice;
    pointFloats_ = lattice.smooth ? 4 * kStride : kStride;
    lattice_.levels = std::clamp(lattice.levels, 1, kFieldMaxLevels);
    fromLevel = std::min(fromLevel, lattice_.levels);
    for (int L = 0; L < lattice_.levels; ++L) inverseSpacing_[L] = 1.0 / lattice_.spacing[L];
    fallback_ = fallback;
    for (int L = fromLevel; L < kFieldMaxLevels; ++L) cells_[L].clear(), slope_[L].fill(0.0);
    points_.resize(levelStart_[fromLevel] * pointFloats_);
    levelsIn_.clear();
    finest_ = -1;

    for (auto& m : anchorAt_) m.clear();
    anySlope_ = false;
    for (std::uint32_t n = 0; n < anchors.size(); ++n) {
        const FieldAnchor& a = anchors[n];
        if (a.presence > 0.0f && a.level >= 0 && a.level < lattice_.levels)
            anchorAt_[a.level][CellKey{a.i, a.k}] = n;
        anySlope_ = anySlope_ || a.hasSlope;
    }
    anchors_ = &anchors;  // for anchorAt() during the build only
    for (int L = 0; L < lattice_.levels; ++L) {
        if (L >= fromLevel) {
            buildLevel(L, anchors);
            levelStart_[L + 1] = points_.size() / pointFloats_;
        }
        if (cells_[L].empty()) continue;
        finest_ = L;
        const std::int64_t ratio = lattice_.scale[0] / lattice_.scale[L];  // 3^L
        const CellMap& m = cells_[L];
        for (const auto& block : m.blocks) {
            for (std::int64_t n = 0; n < (std::int64_t(1) << (2 * kBlockShift)); ++n) {
                if (m.refs[block.second + std::size_t(n)].row0 == kNoCell) continue;
                // (A product, not a left shift: block coordinates may be negative.)
                constexpr std::int64_t side = std::int64_t(1) << kBlockShift;
                const std::int64_t i = block.first.i * side + (n & kBlockMask);
                const std::int64_t k = block.first.k * side + (n >> kBlockShift);
                levelsIn_[CellKey{floorDiv(i, ratio), floorDiv(k, ratio)}] |= 1u << L;
            }
        }
    }
    anchors_ = nullptr;
    built_ = true;
}

// F_{L-1}'s Hermite data at (x, z), derivatives scaled to level-L units: the finest stored cell
// of a coarser level, or the fallback (flat).
void AnchorField::coarserData(int L, double x, double z, double* out) const {
    std::fill(out, out + 4 * kN, 0.0);
    Hit hit;
    float value[kN];
    toFloats(L == 0 ? fallback_ : at(x, z, &hit, L - 1), value);
    for (int j = 0; j < kN; ++j) out[j] = double(value[j]);  // the value exactly as at() gives it
    if (L == 0 || hit.level < 0 || !lattice_.smooth) return;
    const CellRef* it = cells_[hit.level].find(hit.i, hit.k);
    const float* r[2] = {points_.data() + std::size_t(it->row0) * pointFloats_,
                         points_.data() + std::size_t(it->row1) * pointFloats_};
    // d/du, d/dw and d2/dudw of the coarser cell, then to level-L units (s_L / s_hit = 3^-n).
    const std::array<double, 4> hu = hermite(hit.u), hw = hermite(hit.w);
    const std::array<double, 4> du = hermite(hit.u, true), dw = hermite(hit.w, true);
    double ratio = 1.0;
    for (int n = hit.level; n < L; ++n) ratio /= 3.0;
    const std::array<double, 4>* wu[3] = {&du, &hu, &du};
    const std::array<double, 4>* ww[3] = {&hw, &dw, &dw};
    const double scale[3] = {ratio, ratio, ratio * ratio};
    for (int d = 0; d < 3; ++d) {
        double* o = out + (d + 1) * kN;
        for (int b = 0; b < 2; ++b)
            for (int a = 0; a < 2; ++a) {
                const float* corner = r[b] + a * pointFloats_;
                const double vu = (*wu[d])[2 * a], su = (*wu[d])[2 * a + 1];
                const double vw = (*ww[d])[2 * b], sw = (*ww[d])[2 * b + 1];
                const double w4[4] = {vu * vw, su * vw, vu * sw, su * sw};
                for (int m = 0; m < 4; ++m)
                    for (int j = 0; j < kN; ++j)
                        o[j] += w4[m] * scale[d] * double(corner[m * kStride + j]);
            }
    }
}

// F_{L-1}'s data at level-L points, each computed once (node-based: references stay valid).
struct AnchorField::CoarserCache {
    static_assert(kN == kFloats, "a coefficient set");
    const AnchorField& field;
    int L;
    std::unordered_map<CellKey, std::array<double, 4 * kN>, CellKeyHash> coarse;

    const std::array<double, 4 * kN>& operator()(const CellKey& c) {
        const double fine = field.lattice_.fineSpacing_m;
        const std::int64_t sc = field.lattice_.scale[L];
        auto xOf = [&](const CellKey& p) { return double(p.i * sc) * fine; };
        auto zOf = [&](const CellKey& p) { return double(p.k * sc) * fine; };
        auto it = coarse.find(c);
        if (it == coarse.end()) {
            std::array<double, 4 * kN> d;
            field.coarserData(L, xOf(c), zOf(c), d.data());
            it = coarse.emplace(c, d).first;
        }
        return it->second;
    }
};

// A lattice point in reach of the level's anchors: C_L as float (what the lookup shows), D_L
// and the level's coverage there.
struct AnchorField::ReachPoint {
    std::array<float, kN> value;
    std::array<double, kN> d;
    double coverage;
};

// The cells of one level (the coarser levels are built): every cell with a corner in reach of
// an anchor of this level.
void AnchorField::buildLevel(int L, const std::vector<FieldAnchor>& anchors) {
    CoarserCache coarserAt{*this, L, {}};
    reach_.clear();
    residuals_.clear();
    const int R = std::max(0, L == 0 ? lattice_.coarseReachCells : lattice_.reachCells);
    addLevelAnchors(L, R, anchors, coarserAt);
    addFinerAnchors(L, R, anchors);
    if (reach_.empty()) return;

    const ReachPoints inReach = valuesInReach(L, coarserAt);
    std::vector<CellKey> cellList, cornerList;
    cellsAroundReach(cellList, cornerList);
    const std::vector<float> values = cornerData(L, cornerList, inReach, coarserAt);
    writeCells(L, cellList, cornerList, values);
}

// Reach: per lattice point within R cells of this level's anchors, sum K p and sum K p r,
// r = v - F_{L-1} at the anchor (its residual against the coarser levels).
void AnchorField::addLevelAnchors(int L, int R, const std::vector<FieldAnchor>& anchors,
                                  CoarserCache& coarserAt) {
    std::array<float, kN> v;
    for (std::uint32_t n = 0; n < anchors.size(); ++n) {
        const FieldAnchor& a = anchors[n];
        if (a.level != L || !(a.presence > 0.0f)) continue;
        toFloats(a.value, v.data());
        const auto& base = coarserAt({a.i, a.k});
        std::array<double, kN> r;
        for (int j = 0; j < kN; ++j) r[j] = double(v[j]) - base[j];
        residuals_.emplace(CellKey{a.i, a.k}, r);
        for (int di = -R; di <= R; ++di) {
            for (int dk = -R; dk <= R; ++dk) {
                const int d2 = di * di + dk * dk;
                if (d2 >= R * R && d2 > 0) continue;
                const double t2 = R > 0 ? double(d2) / double(R * R) : 0.0;
                const double K = (1.0 - t2) * (1.0 - t2) * double(a.presence);
                auto& sum = reach_[CellKey{a.i + di, a.k + dk}];
                sum[0] += K;
                for (int j = 0; j < kN; ++j) sum[1 + j] += K * r[j];
            }
        }
    }
}

// The finer levels' anchors inform this level's missing points too (weight finerWeight
// each): r = v - F_{L-1} at the anchor's own position, the kernel over its true distance.
void AnchorField::addFinerAnchors(int L, int R, const std::vector<FieldAnchor>& anchors) {
    const double fine = lattice_.fineSpacing_m;
    std::array<float, kN> v;
    const double finer = lattice_.finerWeight;
    for (std::uint32_t n = 0; finer > 0.0 && R > 0 && n < anchors.size(); ++n) {
        const FieldAnchor& a = anchors[n];
        if (a.level <= L || a.level >= lattice_.levels || !(a.presence > 0.0f)) continue;
        toFloats(a.value, v.data());
        float base[kN];
        if (L == 0) {
            toFloats(fallback_, base);
        } else {
            const double ax = double(a.i * lattice_.scale[a.level]) * fine;
            const double az = double(a.k * lattice_.scale[a.level]) * fine;
            toFloats(at(ax, az, nullptr, L - 1), base);
        }
        std::array<double, kN> r;
        for (int j = 0; j < kN; ++j) r[j] = double(v[j]) - double(base[j]);
        // Offsets from the level-L points in finest-lattice units (integers: the same bits near
        // and far from the origin).
        const std::int64_t sc = lattice_.scale[L];
        const std::int64_t ai = a.i * lattice_.scale[a.level], ak = a.k * lattice_.scale[a.level];
        const std::int64_t i0 = floorDiv(ai, sc) - R + 1, k0 = floorDiv(ak, sc) - R + 1;
        for (std::int64_t ci = i0; ci < i0 + 2 * R; ++ci) {
            for (std::int64_t ck = k0; ck < k0 + 2 * R; ++ck) {
                const double du = double(ai - ci * sc) / double(sc);
                const double dw = double(ak - ck * sc) / double(sc);
                const double t2 = (du * du + dw * dw) / double(R * R);
                if (t2 >= 1.0) continue;
                const double K = (1.0 - t2) * (1.0 - t2) * double(a.presence) * finer;
                auto& sum = reach_[CellKey{ci, ck}];
                sum[0] += K;
                for (int j = 0; j < kN; ++j) sum[1 + j] += K * r[j];
            }
        }
    }
}

// C_L (as float, what the lookup shows) and D_L at every point in reach (AnchorField.h).
AnchorField::ReachPoints AnchorField::valuesInReach(int L, CoarserCache& coarserAt) const {
    std::array<float, kN> v;
    ReachPoints inReach;
    inReach.reserve(reach_.size());
    for (const auto& entry : reach_) {
        const CellKey& c = entry.first;
        const auto& sum = entry.second;
        const auto& base = coarserAt(c);
        ReachPoint lv;
        lv.coverage = std::min(1.0, sum[0]);
        float* out = lv.value.data();
        const FieldAnchor* anchor = anchorAt(L, c);
        if (anchor && anchor->level < L && anchor->presence >= 1.0f) {
            for (int j = 0; j < kN; ++j) out[j] = float(base[j]);  // a present coarser anchor
        } else if (anchor && anchor->level == L && anchor->presence >= 1.0f) {
            toFloats(anchor->value, out);  // exact on a present anchor
        } else {
            // G_L: the coarser value plus this level's residuals nearby (its own left out).
            double w = sum[0];
            std::array<double, kN> g;
            for (int j = 0; j < kN; ++j) g[j] = sum[1 + j];
            const double p = anchor ? double(anchor->presence) : 0.0;
            if (anchor && anchor->level == L) {
                const auto& own = residuals_.find(c)->second;
                w -= p;
                for (int j = 0; j < kN; ++j) g[j] -= p * own[j];
            }
            w = coverageDivisor(w);
            for (int j = 0; j < kN; ++j) g[j] = base[j] + g[j] / w;
            if (anchor && anchor->level == L) {
                toFloats(anchor->value, v.data());
                for (int j = 0; j < kN; ++j) out[j] = float(p * double(v[j]) + (1.0 - p) * g[j]);
            } else {  // a coarser anchor fading (weight 1 - p on the residuals) or none (p = 0)
                for (int j = 0; j < kN; ++j) out[j] = float(base[j] + (1.0 - p) * (g[j] - base[j]));
            }
        }
        for (int j = 0; j < kN; ++j) lv.d[j] = double(out[j]) - base[j];
        inReach.emplace(c, lv);
    }
    return inReach;
}

// The order of corner rows: by k, then by i.
bool AnchorField::rowOrder(const CellKey& a, const CellKey& b) {
    return a.k != b.k ? a.k < b.k : a.i < b.i;
}

// The cells around the points in reach and their corners, in rows sorted by (k, i).
void AnchorField::cellsAroundReach(std::vector<CellKey>& cellList,
                                   std::vector<CellKey>& cornerList) const {
    tsl::hopscotch_map<CellKey, bool, CellKeyHash> seen;
    for (const auto& entry : reach_)
        for (std::int64_t dk = -1; dk <= 0; ++dk)
            for (std::int64_t di = -1; di <= 0; ++di) {
                const CellKey c{entry.first.i + di, entry.first.k + dk};
                if (seen.emplace(c, true).second) cellList.push_back(c);
            }
    for (const CellKey& c : cellList)
        for (int q = 0; q < 4; ++q) cornerList.push_back({c.i + (q & 1), c.k + (q >> 1)});
    std::sort(cornerList.begin(), cornerList.end(), rowOrder);
    cornerList.erase(std::unique(cornerList.begin(), cornerList.end()), cornerList.end());
}

// H_L at each corner: value, s d/dx, s d/dz, s^2 d2/dxdz.
std::vector<float> AnchorField::cornerData(int L, const std::vector<CellKey>& cornerList,
                                           const ReachPoints& inReach,
                                           CoarserCache& coarserAt) const {
    std::vector<float> values(cornerList.size() * pointFloats_, 0.0f);
    for (std::size_t n = 0; n < cornerList.size(); ++n) {
        const CellKey& c = cornerList[n];
        float* out = values.data() + n * pointFloats_;
        const auto& base = coarserAt(c);
        const auto own = inReach.find(c);
        if (!lattice_.smooth) {  // bilinear: the value alone
            if (own == inReach.end())
                for (int j = 0; j < kN; ++j) out[j] = float(base[j]);
            else
                std::copy(own->second.value.begin(), own->second.value.end(), out);
            continue;
        }
        if (own == inReach.end()) {  // out of reach: F_{L-1}'s own data
            for (int m = 0; m < 4; ++m)
                for (int j = 0; j < kN; ++j) out[m * kStride + j] = float(base[m * kN + j]);
            continue;
        }
        cornerInReach(L, c, own->second, base, inReach, coarserAt, out);
    }
    return values;
}

// H_L at a corner in reach: its value C_L, and slopes and twist blended by the coverage between
// F_{L-1}'s own plus D_L's central differences and the lattice's limited ones.
void AnchorField::cornerInReach(int L, const CellKey& c, const ReachPoint& own,
                                const std::array<double, 4 * kFloats>& base,
                                const ReachPoints& inReach, CoarserCache& coarserAt,
                                float* out) const {
    static const std::array<double, kN> zero{};
    auto dAt = [&](std::int64_t i, std::int64_t k) -> const std::array<double, kN>& {
        const auto it = inReach.find(CellKey{i, k});
        return it == inReach.end() ? zero : it->second.d;
    };
    std::copy(own.value.begin(), own.value.end(), out);
    const double k = own.coverage;
    const auto &e = dAt(c.i + 1, c.k), &wst = dAt(c.i - 1, c.k);
    const auto &nth = dAt(c.i, c.k + 1), &sth = dAt(c.i, c.k - 1);
    const auto &ne = dAt(c.i + 1, c.k + 1), &nw = dAt(c.i - 1, c.k + 1);
    const auto &se = dAt(c.i + 1, c.k - 1), &sw = dAt(c.i - 1, c.k - 1);
    // With coverage k > 0, the lattice's own slopes stand in for F_{L-1}'s in part: from
    // the values C = F_{L-1} + D_L at the neighbours, limited so that a cubic never
    // overshoots its samples (harmonic mean of the one-sided differences, 0 at an extremum;
    // the twist the smallest of the four one-sided cross differences, 0 if they disagree).
    // Both are exact for a bilinear field.
    std::array<double, kN> lx{}, lz{}, lxz{};
    if (k > 0.0) {
        const double* C[3][3];  // C[dk + 1][di + 1] at (c.i + di, c.k + dk)
        std::array<std::array<std::array<double, kN>, 3>, 3> cv;
        for (int dk = -1; dk <= 1; ++dk)
            for (int di = -1; di <= 1; ++di) {
                const auto& f = coarserAt({c.i + di, c.k + dk});
                const auto& d = dAt(c.i + di, c.k + dk);
                auto& out3 = cv[dk + 1][di + 1];
                for (int j = 0; j < kN; ++j) out3[j] = f[j] + d[j];
                C[dk + 1][di + 1] = out3.data();
            }
        for (int j = 0; j < kN; ++j) {
            const double c0 = C[1][1][j];
            lx[j] = harmonicSlope(c0 - C[1][0][j], C[1][2][j] - c0);
            lz[j] = harmonicSlope(c0 - C[0][1][j], C[2][1][j] - c0);
            const double q[4] = {C[2][2][j] - C[2][1][j] - C[1][2][j] + c0,
                                 -(C[2][0][j] - C[2][1][j] - C[1][0][j] + c0),
                                 -(C[0][2][j] - C[0][1][j] - C[1][2][j] + c0),
                                 C[0][0][j] - C[0][1][j] - C[1][0][j] + c0};
            lxz[j] = minMod4(q);
        }
    }
    for (int j = 0; j < kN; ++j) {
        const double gx = base[kN + j], gz = base[2 * kN + j], gxz = base[3 * kN + j];
        const double ox = gx + 0.5 * (e[j] - wst[j]);
        const double oz = gz + 0.5 * (nth[j] - sth[j]);
        const double oxz = gxz + 0.25 * (ne[j] - nw[j] - se[j] + sw[j]);
        out[kStride + j] = float(ox + k * (lx[j] - ox));
        out[2 * kStride + j] = float(oz + k * (lz[j] - oz));
        out[3 * kStride + j] = float(oxz + k * (lxz[j] - oxz));
    }
    // An anchor with a measured slope gives its point that slope, weighted by its presence.
    const FieldAnchor* anchor = anySlope_ ? anchorAt(L, c) : nullptr;
    if (anchor && anchor->hasSlope) {
        // Over a cell much wider than the slope's radius of validity, the slope describes the
        // near surfaces around the probe, not the way to the next lattice point: its weight
        // falls as validity / spacing.
        const double s = lattice_.spacing[L];
        const double p =
            double(anchor->presence) * std::clamp(double(anchor->slope.validity_m) / s, 0.0, 1.0);
        for (int j = 0; j < kN; ++j) {
            const double mx = s * double(anchor->slope.dx.c[j / 3][j % 3]);
            const double mz = s * double(anchor->slope.dz.c[j / 3][j % 3]);
            out[kStride + j] = float((1.0 - p) * double(out[kStride + j]) + p * mx);
            out[2 * kStride + j] = float((1.0 - p) * double(out[2 * kStride + j]) + p * mz);
        }
    }
}

// Cells point at their corner rows: (i, k) and (i, k + 1); (i + 1, .) follow them.
void AnchorField::writeCells(int L, const std::vector<CellKey>& cellList,
                             const std::vector<CellKey>& cornerList,
                             const std::vector<float>& values) {
    const std::uint32_t first = std::uint32_t(points_.size() / pointFloats_);
    points_.insert(points_.end(), values.begin(), values.end());
    auto indexOf = [&](const CellKey& c) {
        const auto it = std::lower_bound(cornerList.begin(), cornerList.end(), c, rowOrder);
        return first + std::uint32_t(it - cornerList.begin());
    };
    CellMap& cells = cells_[L];
    std::array<double, kN>& slope = slope_[L];
    for (const CellKey& c : cellList) {
        const CellRef ref{indexOf(c), indexOf(CellKey{c.i, c.k + 1})};
        cells.insert(c, ref);
        // slopeBound: the Hermite bound of the cell in both axes.
        const float* p[4] = {points_.data() + std::size_t(ref.row0) * pointFloats_,
                             points_.data() + std::size_t(ref.row0 + 1) * pointFloats_,
                             points_.data() + std::size_t(ref.row1) * pointFloats_,
                             points_.data() + std::size_t(ref.row1 + 1) * pointFloats_};
        for (int j = 0; j < kN; ++j) {
            double dvx = 0, dvz = 0, gx = 0, gz = 0, gxz = 0;
            dvx = std::max(std::fabs(double(p[1][j]) - p[0][j]),
                           std::fabs(double(p[3][j]) - p[2][j]));
            dvz = std::max(std::fabs(double(p[2][j]) - p[0][j]),
                           std::fabs(double(p[3][j]) - p[1][j]));
            if (!lattice_.smooth) {  // bilinear: the larger edge difference per axis
                slope[j] = std::max(slope[j], std::max(dvx, dvz) * inverseSpacing_[L]);
                continue;
            }
            for (int q = 0; q < 4; ++q) {
                gx = std::max(gx, std::fabs(double(p[q][kStride + j])));
                gz = std::max(gz, std::fabs(double(p[q][2 * kStride + j])));
                gxz = std::max(gxz, std::fabs(double(p[q][3 * kStride + j])));
            }
            const double bx = 1.5 * dvx + gx + 0.75 * gz + 0.25 * gxz;
            const double bz = 1.5 * dvz + gz + 0.75 * gx + 0.25 * gxz;
            slope[j] = std::max(slope[j], std::max(bx, bz) * inverseSpacing_[L]);
        }
    }
}

const FieldAnchor* AnchorField::anchorAt(int L, CellKey c) const {
    // The point under its canonical (coarsest) level.
    while (L > 0 && c.i % 3 == 0 && c.k % 3 == 0) c.i /= 3, c.k /= 3, --L;
    const auto it = anchorAt_[L].find(c);
    return it != anchorAt_[L].end() ? &(*anchors_)[it->second] : nullptr;
}

inline __attribute__((always_inline)) AnchorField::Locus AnchorField::locate(int L, double x,
                                                                            double z) const {
    const std::int64_t sc = lattice_.scale[L];
    const double fine = lattice_.fineSpacing_m, inv = inverseSpacing_[L];
    Locus c;
    c.i = floorToInt(x * inv);
    c.k = floorToInt(z * inv);
    // The estimate may be one off after rounding: settle on the exact bounds.
    c.x0 = double(c.i * sc) * fine, c.x1 = double((c.i + 1) * sc) * fine;
    if (x < c.x0) c.x1 = c.x0, c.x0 = double((--c.i) * sc) * fine;
    else if (x >= c.x1) c.x0 = c.x1, c.x1 = double((++c.i + 1) * sc) * fine;
    c.z0 = double(c.k * sc) * fine, c.z1 = double((c.k + 1) * sc) * fine;
    if (z < c.z0) c.z1 = c.z0, c.z0 = double((--c.k) * sc) * fine;
    else if (z >= c.z1) c.z0 = c.z1, c.z1 = double((++c.k + 1) * sc) * fine;
    return c;
}

ShRgb AnchorField::at(double x, double z, Hit* hit, int maxLevel) const {
    if (hit) *hit = Hit{};
    const double reach = 2147483647.0 * lattice_.fineSpacing_m;
    if (!(std::fabs(x) <= reach) || !(std::fabs(z) <= reach)) return fallback_;  // NaN too
    if (finest_ < 0) return fallback_;
    const Locus top = locate(0, x, z);
    const auto in = levelsIn_.find(CellKey{top.i, top.k});
    if (in == levelsIn_.end()) return fallback_;
    const std::uint32_t levels = in->second;
    for (int L = std::min(maxLevel, finest_); L >= 0; --L) {
        if (!(levels & (1u << L))) continue;
        const Locus c = L == 0 ? top : locate(L, x, z);
        const CellRef* ref = cells_[L].find(c.i, c.k);
        if (!ref) continue;
        const float* r0 = points_.data() + std::size_t(ref->row0) * pointFloats_;
        const float* r1 = points_.data() + std::size_t(ref->row1) * pointFloats_;
        // The cell's corner data (two rows of two points) are asked for at once, so that their
        // cache misses overlap each other and the weights' arithmetic.
        for (int b = 0; b < 2 * pointFloats_; b += 16) {
            __builtin_prefetch(r0 + b);
            __builtin_prefetch(r1 + b);
        }
        const double dx = x - c.x0, dz = z - c.z0;
        double u = dx / (c.x1 - c.x0), w = dz / (c.z1 - c.z0);
        // On a lattice line (within 1e-9 m): exactly on it, so an anchor's value comes back
        // bit for bit.
        int cu = -1, cw = -1;
        if (dx < kOnCorner_m) u = 0.0, cu = 0;
        else if (c.x1 - x < kOnCorner_m) u = 1.0, cu = 1;
        if (dz < kOnCorner_m) w = 0.0, cw = 0;
        else if (c.z1 - z < kOnCorner_m) w = 1.0, cw = 1;
        if (hit) {
            hit->level = L;
            hit->i = c.i, hit->k = c.k;
            hit->u = u, hit->w = w;
        }
        if (cu >= 0 && cw >= 0) {
            if (hit) hit->corner = cu + 2 * cw;
            return fromFloats((cw ? r1 : r0) + cu * pointFloats_);
        }
        if (!lattice_.smooth) {  // bilinear between the corner values
            const float w00 = float((1.0 - u) * (1.0 - w)), w10 = float(u * (1.0 - w));
            const float w01 = float((1.0 - u) * w), w11 = float(u * w);
            float out[kN];
            for (int j = 0; j < kN; ++j)
                out[j] = w00 * r0[j] + w10 * r0[pointFloats_ + j] + w01 * r1[j] + w11 * r1[pointFloats_ + j];
            return fromFloats(out);
        }
        // Bicubic Hermite: 4 corners x (value, slope x, slope z, twist), 16 weights.
        // (The basis in float: the weights are applied to float data.)
        const float fu = float(u), fw = float(w);
        const float fu2 = fu * fu, fw2 = fw * fw;
        const float hu[4] = {(2.0f * fu - 3.0f) * fu2 + 1.0f, (fu - 2.0f) * fu2 + fu,
                             (3.0f - 2.0f * fu) * fu2, (fu - 1.0f) * fu2};
        const float hw[4] = {(2.0f * fw - 3.0f) * fw2 + 1.0f, (fw - 2.0f) * fw2 + fw,
                             (3.0f - 2.0f * fw) * fw2, (fw - 1.0f) * fw2};
        const float* corner[4] = {r0, r0 + pointFloats_, r1, r1 + pointFloats_};
        float weight[16];
        for (int q = 0; q < 4; ++q) {
            const int a = q & 1, b = q >> 1;
            weight[4 * q + 0] = hu[2 * a] * hw[2 * b];
            weight[4 * q + 1] = hu[2 * a + 1] * hw[2 * b];
            weight[4 * q + 2] = hu[2 * a] * hw[2 * b + 1];
            weight[4 * q + 3] = hu[2 * a + 1] * hw[2 * b + 1];
        }
        alignas(32) float out[kStride];
        blend16(corner, weight, out);
        return fromFloats(out);
    }
    return fallback_;
}

}  // namespace amb
