// AnchorField.h — the interpolated field of the anchor store (AnchorStore.h "Interpolation"):
// hierarchical bilinear interpolation over the store's 3 x 3 lattice, kept as a cache of cells
// per level whose four corner values are precomputed. A lookup is a few hash probes (finest level
// first) and one bilinear blend of four coefficient sets; the cache is rebuilt from the anchors
// when they change (once a frame: blends and fades move every frame while probes arrive).
//
// The field (s_L spacing of level L, v = an anchor's current x relight, p its presence weight
// easeInOut(presence), AnchorStore.h):
//   F_{-1}      = the fallback everywhere.
//   r_a         = v_a - F_{L-1}(a) for each anchor a of canonical level L: what it adds to the
//                 coarser levels' value at its point (its residual).
//   G_L(c)      = F_{L-1}(c) + sum_a K_a p_a r_a / max(sum_a K_a p_a, kCoverageFloor), over
//                 this level's anchors a other than c within R_L = reachCells x s_L of the
//                 lattice point c, K_a = (1 - (|c - a| / R_L)^2)^2: a missing corner takes the
//                 coarser value corrected by the weighted mean of the residuals nearby, in part
//                 where they cover it thinly (far, or fading in), none beyond R_L.
//   C_L(c)      = p v + (1 - p) G_L(c)                  with a level-L anchor at c,
//               = F_{L-1}(c) + (1 - p)(G_L(c) - F_{L-1}(c))  with a coarser anchor at c (whose
//                                                        presence F_{L-1} already carries),
//               = G_L(c)                                otherwise.
//   F_L(x)      = the bilinear blend of C_L at the four corners of x's level-L cell.
//   result      = F_finest.
// Where no level-L anchor reaches a cell's corners, C_L = F_{L-1} there, and a bilinear function
// on a cell restricted to one of its 3 x 3 sub-cells is bilinear there, so such a cell equals
// F_{L-1} exactly: only cells with a corner in reach are stored, and a lookup answers from the
// finest stored cell containing it.
// Properties: corner values are shared by the cells that meet there and F_{L-1} is continuous,
// so F_L is continuous everywhere (piecewise bilinear, Lipschitz) and moves continuously with
// presences and values; a present anchor's corner is its value (exact); an anchor of presence 0,
// or one whose value is what the coarser levels show at its point (r = 0), changes nothing; a
// field bilinear over complete coarse cells is reproduced at every finer level (its residuals
// vanish); corner values are convex mixes of anchor values and the fallback.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tsl/hopscotch_map.h>

#include "lighting/SH.h"

namespace amb {

inline constexpr int kFieldMaxLevels = 8;

// The lattice the field lives on (AnchorStore's).
struct FieldLattice {
    int levels = 1;
    std::array<double, kFieldMaxLevels> spacing{};     // s_L [m]
    std::array<std::int64_t, kFieldMaxLevels> scale{};  // finest-lattice units per level-L unit
    double fineSpacing_m = 1.0;
    int reachCells = 2;  // reach of level-0 anchors into holes, in level-0 cells
};

// One anchor as the field sees it (only anchors with presence > 0 are given).
struct FieldAnchor {
    int level = 0;            // canonical level
    std::int64_t i = 0, k = 0;  // lattice coordinates on that level
    float presence = 1.0f;    // (0, 1]
    ShRgb value;              // current x relight
};

class AnchorField {
  public:
    // Where a lookup was answered.
    struct Hit {
        int level = -1;             // level of the cell used; -1: the fallback
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

    // Coverage below which G_L takes only part of the residuals nearby (the rest is the
    // coarser value), in units of one anchor at the corner itself.
    static constexpr double kCoverageFloor = 0.25;

  private:
    struct CellKey {
        std::int64_t i, k;
        bool operator==(const CellKey& o) const { return i == o.i && k == o.k; }
    };
    struct CellKeyHash {
        std::size_t operator()(const CellKey& c) const;
    };
    // A stored cell: where its corners' values are. Corner values are stored once per lattice
    // point, each level's in rows sorted by (k, i), so corner (i + 1, k) follows (i, k).
    struct CellRef {
        std::uint32_t row0;  // corner (i, k)
        std::uint32_t row1;  // corner (i, k + 1)
    };
    using CellMap = tsl::hopscotch_map<CellKey, CellRef, CellKeyHash>;
    static constexpr int kFloats = 27;  // a coefficient set (ShRgb order)

    void buildLevel(int level, const std::vector<FieldAnchor>& anchors);

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
    std::vector<float> corners_;  // kFloats per stored corner
    std::array<std::size_t, kFieldMaxLevels + 1> levelStart_{};  // first corner of each level
    std::array<double, kFieldMaxLevels> inverseSpacing_{};
    int finest_ = -1;  // finest level holding a cell
    bool built_ = false;
    // The anchor at a level-L lattice point (under its canonical level), or null.
    const FieldAnchor* anchorAt(int level, CellKey point) const;

    // Scratch of rebuild(): anchors by canonical level and point; per level, reach sums by
    // lattice point (weight, then 27 sums) and the anchors' residuals.
    std::array<tsl::hopscotch_map<CellKey, std::uint32_t, CellKeyHash>, kFieldMaxLevels> anchorAt_;
    const std::vector<FieldAnchor>* anchors_ = nullptr;
    tsl::hopscotch_map<CellKey, std::array<double, 28>, CellKeyHash> reach_;
    tsl::hopscotch_map<CellKey, std::array<double, 27>, CellKeyHash> residuals_;
};

}  // namespace amb
