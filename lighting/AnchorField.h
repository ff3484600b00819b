// AnchorField.h — the interpolated field of the anchor store (AnchorStore.h "Interpolation"):
// a hierarchy over the store's 3 x 3 lattice in which each level holds, at its lattice points,
// a value and a gradient, and fills its cells by bicubic Hermite interpolation (smooth: no kink
// at lattice lines). It is kept as a cache of cells per level, indexed by blocks of 8 x 8 cells;
// a lookup is a few probes of small hash maps (finest level first) and one blend of 16
// coefficient sets (4 corners x value, d/dx, d/dz, d2/dxdz); the cache is rebuilt from the
// anchors when they change (once a frame: blends and fades move every frame while probes
// arrive).
//
// The field (s_L spacing of level L, v = an anchor's current x relight, p its presence weight
// easeInOut(presence), AnchorStore.h):
//   F_{-1}      = the fallback everywhere.
//   r_a         = v_a - F_{L-1}(a) for each anchor a of canonical level >= L: what it adds to
//                 the coarser levels' value at its point (its residual against level L).
//   G_L(c)      = F_{L-1}(c) + sum_a K_a p_a r_a / coverageDivisor(sum_a K_a p_a), over
//                 the anchors a other than c within R_L = reachCells x s_L of the lattice point
//                 c (coarseReachCells at level 0): this level's with K_a = (1 - (|c - a| /
//                 R_L)^2)^2, the finer levels' (at their own positions) with finerWeight x K_a.
//                 A missing point takes the coarser value corrected by the weighted mean of the
//                 residuals nearby, in part where they cover it thinly (far, or fading in), none
//                 beyond R_L. The finer anchors carry what a level's own lattice has not
//                 captured yet into its holes (a coarse point beside a densely probed road).
//   C_L(c)      = p v + (1 - p) G_L(c)                  with a level-L anchor at c,
//               = F_{L-1}(c) + (1 - p)(G_L(c) - F_{L-1}(c))  with a coarser anchor at c (whose
//                                                        presence F_{L-1} already carries),
//               = G_L(c)                                otherwise.
//   D_L(c)      = C_L(c) - F_{L-1}(c): what level L adds at c (zero beyond R_L).
//   H_L(c)      = the Hermite data at c: value C_L(c); derivatives d/dx, d/dz, d2/dxdz =
//                 (1 - k) (F_{L-1}'s own + D_L's central differences) + k (C_L's central
//                 differences), over c's neighbours s_L apart, with k = min(1, sum_a K_a p_a)
//                 the level's coverage at c: F_{L-1}'s own slopes where the level adds nothing,
//                 the lattice's slopes where its anchors cover c, continuous in between. At a
//                 point holding an anchor with a measured slope g (FieldAnchor::hasSlope), the
//                 d/dx and d/dz are then (1 - w) x those + w s_L g, with w = p min(1, validity /
//                 s_L): its own gradient where it is valid across the cell.
//   F_L(x)      = the bicubic Hermite interpolation of H_L over x's level-L cell.
//   result      = F_finest.
// Where no level-L anchor reaches a cell's corners, H_L there is F_{L-1}'s own value and
// derivatives, and F_{L-1} is bicubic on the cell (a level-L cell lies inside one level-(L-1)
// cell), so the Hermite interpolation reproduces it exactly: only cells with a corner in reach
// are stored, and a lookup answers from the finest stored cell containing it.
// Properties: neighbouring cells share their edge's corner data, so F_L is continuous with a
// continuous gradient everywhere (C1: across lattice lines, partly present cells and levels), and
// a point crossing it at a steady speed sees no kink; it moves continuously with presences and
// values. A present anchor's point shows its value (exact). An anchor of presence 0 changes
// nothing (it adds K p = 0 everywhere), nor does one whose residuals are all zero: its value is
// what every coarser level shows at its point (D_L = 0: H_L = F_{L-1}'s own data; with
// finerWeight 0, only its own level's r counts). Central differences are exact for a bilinear field, so a field
// bilinear over a complete coarse lattice is reproduced wherever a cell's corners and their
// neighbours are complete (the finer D_L vanish). Gradients are bounded (slopeBound) and the
// result is always finite.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tsl/hopscotch_map.h>

#include "lighting/SH.h"
#include "lighting/ShGradient.h"

namespace amb {

inline constexpr int kFieldMaxLevels = 8;

// Hash of an integer lattice cell, shared by every hash map keyed by a cell: each coordinate
// times its own odd 64-bit constant, and the high bits folded into the low ones that the maps'
// power-of-two tables use, so that neighbouring cells land far apart. (Two multiplies: a lookup
// hashes two or three cells.)
inline std::size_t hashLatticeCell(std::int64_t i, std::int64_t k) {
    const std::uint64_t h =
        std::uint64_t(i) * 0x9E3779B97F4A7C15ull ^ std::uint64_t(k) * 0xC2B2AE3D27D4EB4Full;
    return std::size_t(h ^ (h >> 29) ^ (h >> 47));
}

// The lattice the field lives on (AnchorStore's).
struct FieldLattice {
    int levels = 1;
    std::array<double, kFieldMaxLevels> spacing{};     // s_L [m]
    std::array<std::int64_t, kFieldMaxLevels> scale{};  // finest-lattice units per level-L unit
    double fineSpacing_m = 1.0;
    int reachCells = 2;        // reach of level-L anchors into holes, in level-L cells
    int coarseReachCells = 2;  // the same for level 0 (the coarsest)
    // Weight of each anchor of a finer level in a level's missing points (0: none).
    double finerWeight = 0.0;
    // Bicubic Hermite cells (C1, the default) or bilinear ones (C0: the values alone, kinks at
    // lattice lines; a quarter of the data and of the work per lookup).
    bool smooth = true;
};

// One anchor as the field sees it (only anchors with presence > 0 are given).
struct FieldAnchor {
    int level = 0;            // canonical level
    std::int64_t i = 0, k = 0;  // lattice coordinates on that level
    float presence = 1.0f;    // (0, 1]
    ShRgb value;              // current x relight
    // Its measured slope (AnchorStoreSettings::gradients), per metre, x relight: the smooth
    // cells' d/dx and d/dz at its point, weighted by presence, instead of the lattice's.
    bool hasSlope = false;
    ShSlope slope;
};

class AnchorField {
  public:
    // Where a lookup was answered.
    struct Hit {
        int level = -1;             // finest level with a cell there; -1: the fallback alone
        std::int64_t i = 0, k = 0;  // that cell's minimum corner (level coordinates)
        double u = 0.0, w = 0.0;    // position in the cell along x and z, [0, 1]
        int corner = -1;            // 0..3 when the query is on (within 1e-9 m of) a corner:
                                    // (i, k), (i + 1, k), (i, k + 1), (i + 1, k + 1)
    };

    // Builds the cells from the anchors (every anchor with presence > 0) and the fallback.
    // Levels coarser than `fromLevel` are kept as they are (nothing they depend on changed:
    // the anchors of those levels and the fallback); the lattice must then be the same.
    void rebuild(const FieldLattice& lattice, const std::vector<FieldAnchor>& anchors,
                 const ShRgb& fallback, int fromLevel = 0);
    // F at ground point (x, z) using levels up to maxLevel (all by default). Finite points
    // beyond the lattice's reach and non-finite points give the fallback.
    ShRgb at(double x_m, double z_m, Hit* hit = nullptr, int maxLevel = kFieldMaxLevels) const;

    std::size_t cells() const;
    std::size_t bytes() const;
    // Per coefficient (ShRgb order, c[k][ch] at 3k + ch), a bound on |dF/dx| and |dF/dz| over
    // the whole field: the largest over stored cells of (1.5 |corner value difference| +
    // |s dF/dx| + 0.75 |s dF/dz| + 0.25 |s^2 d2F/dxdz|) / s at the cell's corners (and the same
    // with x and z swapped). From the Hermite basis: sum |h'| <= 1.5 on value differences,
    // <= 1 on slopes, and sum |h| <= 1 on values, <= 0.25 on slopes.
    std::array<double, 27> slopeBound() const;

    // The cubic Hermite basis at t in [0, 1]: weights of (value at 0, slope at 0, value at 1,
    // slope at 1), slopes per unit t. `derivative`: their d/dt.
    static std::array<double, 4> hermite(double t, bool derivative = false);

    // Coverage below which G_L takes only part of the residuals nearby (the rest is the
    // coarser value), in units of one anchor at the corner itself.
    static constexpr double kCoverageFloor = 0.25;
    // The divisor of G_L's weighted residuals at coverage W = sum K p: W from 2 kCoverageFloor
    // up (the whole weighted mean), f + W^2 / (4 f) below (f = kCoverageFloor): at least f,
    // and with a continuous derivative, so that a hole filling as anchors fade in does not
    // stop rising abruptly when its coverage reaches the floor (a hard max(W, f) gave the
    // moving point a second-difference spike of 0.16 while an empty store filled at one probe
    // a frame).
    static double coverageDivisor(double W) {
        constexpr double f = kCoverageFloor;
        W = W > 0.0 ? W : 0.0;
        return W >= 2.0 * f ? W : f + W * W / (4.0 * f);
    }

  private:
    struct CellKey {
        std::int64_t i, k;
        bool operator==(const CellKey& o) const { return i == o.i && k == o.k; }
    };
    struct CellKeyHash {
        std::size_t operator()(const CellKey& c) const;
    };
    // A stored cell: where its corners' data are. Corner data are stored once per lattice
    // point, each level's in rows sorted by (k, i), so corner (i + 1, k) follows (i, k).
    struct CellRef {
        std::uint32_t row0;  // corner (i, k)
        std::uint32_t row1;  // corner (i, k + 1)
    };
    // A level's stored cells, in blocks of 8 x 8 cells: a small hash map from a block to its
    // 64 cell references (row0 = kNoCell where a cell is not stored). The map stays small
    // enough to sit in the cache, and a probe costs one hash of a few dozen entries and one
    // load, stored cell or not.
    // (A block is (i >> kBlockShift, k >> kBlockShift): the shift of a negative coordinate is
    // arithmetic, floor division by 8, with GCC and Clang, and in every C++20 compiler.)
    static constexpr std::uint32_t kNoCell = 0xFFFFFFFFu;
    static constexpr int kBlockShift = 3;
    static constexpr std::int64_t kBlockMask = (1 << kBlockShift) - 1;
    struct CellMap {
        tsl::hopscotch_map<CellKey, std::uint32_t, CellKeyHash> blocks;  // block -> first ref
        std::vector<CellRef> refs;
        std::size_t count = 0;
        const CellRef* find(std::int64_t i, std::int64_t k) const {
            const auto it = blocks.find(CellKey{i >> kBlockShift, k >> kBlockShift});
            if (it == blocks.end()) return nullptr;
            const CellRef& r = refs[it->second + std::size_t(((k & kBlockMask) << kBlockShift) |
                                                             (i & kBlockMask))];
            return r.row0 == kNoCell ? nullptr : &r;
        }
        void insert(const CellKey& c, const CellRef& ref);
        void clear() { blocks.clear(), refs.clear(), count = 0; }
        bool empty() const { return count == 0; }
        std::size_t bytes() const;
    };
    static constexpr int kFloats = 27;  // a coefficient set (ShRgb order)
    // A stored point: value, s_L d/dx, s_L d/dz, s_L^2 d2/dxdz, each a coefficient set padded
    // to kStride floats (whole SIMD vectors).
    static constexpr int kStride = 28;
    int pointFloats_ = 4 * kStride;  // floats per stored point: 4 blocks (smooth) or 1 (bilinear)
    // F_{L-1}'s Hermite data at (x, z) in level-L units (value, s dx, s dz, s^2 dxdz).
    void coarserData(int level, double x, double z, double* out) const;

    void buildLevel(int level, const std::vector<FieldAnchor>& anchors);
    // buildLevel's steps, in order (AnchorField.cpp).
    struct CoarserCache;  // F_{L-1}'s data at level-L points, each computed once
    struct ReachPoint;    // C_L, D_L and the level's coverage at a lattice point in reach
    using ReachPoints = tsl::hopscotch_map<CellKey, ReachPoint, CellKeyHash>;
    void addLevelAnchors(int level, int reachCells, const std::vector<FieldAnchor>& anchors,
                         CoarserCache& coarserAt);
    void addFinerAnchors(int level, int reachCells, const std::vector<FieldAnchor>& anchors);
    ReachPoints valuesInReach(int level, CoarserCache& coarserAt) const;
    static bool rowOrder(const CellKey& a, const CellKey& b);
    void cellsAroundReach(std::vector<CellKey>& cellList, std::vector<CellKey>& cornerList) const;
    std::vector<float> cornerData(int level, const std::vector<CellKey>& cornerList,
                                  const ReachPoints& inReach, CoarserCache& coarserAt) const;
    void cornerInReach(int level, const CellKey& c, const ReachPoint& own,
                       const std::array<double, 4 * kFloats>& base, const ReachPoints& inReach,
                       CoarserCache& coarserAt, float* out) const;
    void writeCells(int level, const std::vector<CellKey>& cellList,
                    const std::vector<CellKey>& cornerList, const std::vector<float>& values);

    // The cell of level L holding (x, z) and its exact bounds (from the finest lattice, so
    // x - x0 is exact near and far from the origin).
    struct Locus {
        std::int64_t i, k;
        double x0, x1, z0, z1;
    };
    Locus locate(int level, double x, double z) const;

    FieldLattice lattice_;
    ShRgb fallback_;
    std::array<CellMap, kFieldMaxLevels> cells_;
    // Per level-0 cell, bit L set when some level-L cell inside it is stored: a lookup probes
    // only those levels.
    tsl::hopscotch_map<CellKey, std::uint32_t, CellKeyHash> levelsIn_;
    std::vector<float> points_;  // pointFloats_ floats per stored point
    std::array<std::size_t, kFieldMaxLevels + 1> levelStart_{};  // first point of each level
    std::array<std::array<double, 27>, kFieldMaxLevels> slope_{};  // slopeBound per level
    std::array<double, kFieldMaxLevels> inverseSpacing_{};
    int finest_ = -1;  // finest level holding a cell
    bool built_ = false;
    // The anchor at a level-L lattice point (under its canonical level), or null.
    const FieldAnchor* anchorAt(int level, CellKey point) const;

    // Scratch of rebuild(): anchors by canonical level and point; per level, reach sums by
    // lattice point (weight, then 27 sums) and the anchors' residuals.
    std::array<tsl::hopscotch_map<CellKey, std::uint32_t, CellKeyHash>, kFieldMaxLevels> anchorAt_;
    const std::vector<FieldAnchor>* anchors_ = nullptr;
    bool anySlope_ = false;  // some anchor of the rebuild has a measured slope
    tsl::hopscotch_map<CellKey, std::array<double, 28>, CellKeyHash> reach_;
    tsl::hopscotch_map<CellKey, std::array<double, 27>, CellKeyHash> residuals_;
};

}  // namespace amb
