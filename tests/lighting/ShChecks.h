// ShChecks.h — comparisons of SH sets the lighting tests share.
#pragma once

#include <algorithm>
#include <cmath>

#include "lighting/SH.h"

namespace amb::testing_support {

// Every coefficient of every channel finite.
inline bool allFinite(const ShRgb& sh) {
    for (const auto& c : sh.c) {
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) return false;
    }
    return true;
}

// Largest absolute coefficient difference.
inline double maxDiff(const ShRgb& a, const ShRgb& b) {
    double m = 0.0;
    for (int k = 0; k < kShCoefficients; ++k) {
        for (int ch = 0; ch < 3; ++ch) m = std::max(m, std::fabs(double(a.c[k][ch]) - b.c[k][ch]));
    }
    return m;
}

}  // namespace amb::testing_support
