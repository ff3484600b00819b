// AnchorField.cpp — hierarchical bilinear interpolation of the anchor store (see AnchorField.h).
#include "lighting/AnchorField.h"

#include <algorithm>
#include <cmath>

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
    // splitmix64 finaliser over both coordinates: neighbouring cells land far apart.
    std::uint64_t h = std::uint64_t(c.i) * 0x9E3779B97F4A7C15ull ^ std::uint64_t(c.k);
    h ^= h >> 30;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 27;
    h *= 0x94D049BB133111EBull;
    h ^= h >> 31;
    return std::size_t(h);
}

std::size_t AnchorField::cells() const {
    std::size_t n = 0;
    for (const CellMap& m : cells_) n += m.size();
    return n;
}

std::size_t AnchorField::bytes() const {
    std::size_t b = sizeof(*this) + corners_.capacity() * sizeof(float);
    for (const CellMap& m : cells_)
        b += m.bucket_count() * (sizeof(std::pair<CellKey, CellRef>) + sizeof(std::uint64_t));
    b += levelsIn_.bucket_count() *
         (sizeof(std::pair<CellKey, std::uint32_t>) + sizeof(std::uint64_t));
    return b;
}

void AnchorField::rebuild(const FieldLattice& lattice, const std::vector<FieldAnchor>& anchors,
                          const ShRgb& fallback, int fromLevel) {
    if (!built_) fromLevel = 0;  // never built: all of it
    lattice_ = lattice;
    lattice_.levels = std::clamp(lattice.levels, 1, kFieldMaxLevels);
    fromLevel = std::min(fromLevel, lattice_.levels);
    for (int L = 0; L < lattice_.levels; ++L) inverseSpacing_[L] = 1.0 / lattice_.spacing[L];
    fallback_ = fallback;
    for (int L = fromLevel; L < kFieldMaxLevels; ++L) cells_[L].clear();
    corners_.resize(levelStart_[fromLevel] * kN);
    levelsIn_.clear();
    finest_ = -1;

    for (auto& m : anchorAt_) m.clear();
    for (std::uint32_t n = 0; n < anchors.size(); ++n) {
        const FieldAnchor& a = anchors[n];
        if (a.presence > 0.0f && a.level >= 0 && a.level < lattice_.levels)
            anchorAt_[a.level][CellKey{a.i, a.k}] = n;
    }
    anchors_ = &anchors;  // for anchorAt() during the build only
    for (int L = 0; L < lattice_.levels; ++L) {
        if (L >= fromLevel) {
            buildLevel(L, anchors);
            levelStart_[L + 1] = corners_.size() / kN;
        }
        if (cells_[L].empty()) continue;
        finest_ = L;
        const std::int64_t ratio = lattice_.scale[0] / lattice_.scale[L];  // 3^L
        for (const auto& cell : cells_[L]) {
            const CellKey top{floorDiv(cell.first.i, ratio), floorDiv(cell.first.k, ratio)};
            levelsIn_[top] |= 1u << L;
        }
    }
    anchors_ = nullptr;
    built_ = true;
}

// The cells of one level (the coarser levels are built): every cell with a corner in reach of
// an anchor of this level.
void AnchorField::buildLevel(int L, const std::vector<FieldAnchor>& anchors) {
    const double fine = lattice_.fineSpacing_m;
    const std::int64_t sc = lattice_.scale[L];
    // F_{L-1} at a level-L lattice point (the fallback below level 0).
    auto coarser = [&](const CellKey& c, float* out) {
        toFloats(L == 0 ? fallback_
                        : at(double(c.i * sc) * fine, double(c.k * sc) * fine, nullptr, L - 1),
                 out);
    };
    // Reach: per lattice point within R cells of this level's anchors, sum K p and sum K p r,
    // r = v - F_{L-1} at the anchor (its residual against the coarser levels).
    reach_.clear();
    residuals_.clear();
    const int R = std::max(0, lattice_.reachCells);
    std::array<float, kN> v, base;
    for (std::uint32_t n = 0; n < anchors.size(); ++n) {
        const FieldAnchor& a = anchors[n];
        if (a.level != L || !(a.presence > 0.0f)) continue;
        toFloats(a.value, v.data());
        coarser({a.i, a.k}, base.data());
        std::array<double, kN> r;
        for (int j = 0; j < kN; ++j) r[j] = double(v[j]) - double(base[j]);
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
    if (reach_.empty()) return;

    // The cells around the points in reach and their corners, in rows sorted by (k, i).
    std::vector<CellKey> cellList, cornerList;
    {
        tsl::hopscotch_map<CellKey, bool, CellKeyHash> seen;
        for (const auto& entry : reach_)
            for (std::int64_t dk = -1; dk <= 0; ++dk)
                for (std::int64_t di = -1; di <= 0; ++di) {
                    const CellKey c{entry.first.i + di, entry.first.k + dk};
                    if (seen.emplace(c, true).second) cellList.push_back(c);
                }
        for (const CellKey& c : cellList)
            for (int q = 0; q < 4; ++q) cornerList.push_back({c.i + (q & 1), c.k + (q >> 1)});
    }
    auto rowOrder = [](const CellKey& a, const CellKey& b) {
        return a.k != b.k ? a.k < b.k : a.i < b.i;
    };
    std::sort(cornerList.begin(), cornerList.end(), rowOrder);
    cornerList.erase(std::unique(cornerList.begin(), cornerList.end()), cornerList.end());

    // C_L at each corner (AnchorField.h).
    std::vector<float> values(cornerList.size() * kN);
    for (std::size_t n = 0; n < cornerList.size(); ++n) {
        const CellKey& c = cornerList[n];
        float* out = values.data() + n * kN;
        coarser(c, base.data());
        const auto sum = reach_.find(c);
        // Out of reach, or a present coarser anchor: the coarser value as it is (exact there).
        const FieldAnchor* anchor = anchorAt(L, c);
        if (sum == reach_.end() || (anchor && anchor->level < L && anchor->presence >= 1.0f)) {
            std::copy(base.begin(), base.end(), out);
            continue;
        }
        if (anchor && anchor->level == L && anchor->presence >= 1.0f) {
            toFloats(anchor->value, out);  // exact on a present anchor
            continue;
        }
        // G_L: the coarser value plus this level's residuals nearby (its own left out).
        double w = sum->second[0];
        std::array<double, kN> g;
        for (int j = 0; j < kN; ++j) g[j] = sum->second[1 + j];
        const double p = anchor ? double(anchor->presence) : 0.0;
        if (anchor && anchor->level == L) {
            const auto& own = residuals_.find(c)->second;
            w -= p;
            for (int j = 0; j < kN; ++j) g[j] -= p * own[j];
        }
        w = std::max(w, kCoverageFloor);
        for (int j = 0; j < kN; ++j) g[j] = double(base[j]) + g[j] / w;
        if (anchor && anchor->level == L) {
            toFloats(anchor->value, v.data());
            for (int j = 0; j < kN; ++j) out[j] = float(p * double(v[j]) + (1.0 - p) * g[j]);
        } else {  // a coarser anchor fading (weight 1 - p on the residuals) or none (p = 0)
            for (int j = 0; j < kN; ++j)
                out[j] = float(double(base[j]) + (1.0 - p) * (g[j] - double(base[j])));
        }
    }

    // Cells point at their corner rows: (i, k) and (i, k + 1); (i + 1, .) follow them.
    const std::uint32_t first = std::uint32_t(corners_.size() / kN);
    corners_.insert(corners_.end(), values.begin(), values.end());
    auto indexOf = [&](const CellKey& c) {
        const auto it = std::lower_bound(cornerList.begin(), cornerList.end(), c, rowOrder);
        return first + std::uint32_t(it - cornerList.begin());
    };
    CellMap& cells = cells_[L];
    cells.reserve(cellList.size());
    for (const CellKey& c : cellList)
        cells.emplace(c, CellRef{indexOf(c), indexOf(CellKey{c.i, c.k + 1})});
}

const FieldAnchor* AnchorField::anchorAt(int L, CellKey c) const {
    // The point under its canonical (coarsest) level.
    while (L > 0 && c.i % 3 == 0 && c.k % 3 == 0) c.i /= 3, c.k /= 3, --L;
    const auto it = anchorAt_[L].find(c);
    return it != anchorAt_[L].end() ? &(*anchors_)[it->second] : nullptr;
}

AnchorField::Locus AnchorField::locate(int L, double x, double z) const {
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
        const auto it = cells_[L].find(CellKey{c.i, c.k});
        if (it == cells_[L].end()) continue;
        const float* r0 = corners_.data() + std::size_t(it->second.row0) * kN;  // (i, k), (i+1, k)
        const float* r1 = corners_.data() + std::size_t(it->second.row1) * kN;  // row k + 1
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
            return fromFloats((cw ? r1 : r0) + cu * kN);
        }
        const float w00 = float((1.0 - u) * (1.0 - w)), w10 = float(u * (1.0 - w));
        const float w01 = float((1.0 - u) * w), w11 = float(u * w);
        float out[kN];
        for (int j = 0; j < kN; ++j)
            out[j] = w00 * r0[j] + w10 * r0[kN + j] + w01 * r1[j] + w11 * r1[kN + j];
        return fromFloats(out);
    }
    return fallback_;
}

}  // namespace amb
