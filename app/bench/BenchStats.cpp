// BenchStats.cpp — ratios of mean errors with bootstrap intervals (see BenchStats.h).
#include "app/bench/BenchStats.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <vector>

#include "app/bench/BenchCollect.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

double FrameErrors::mean() const {
    double sum = 0.0;
    int count = 0;
    for (const auto& [frame, f] : byFrame) sum += f.first, count += f.second;
    return count ? sum / count : std::nan("");
}

namespace {

std::vector<std::string> csvCells(const std::string& line) {
    std::vector<std::string> f;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) f.push_back(cell);
    return f;
}

// The rows of a run's CSV file (header first) as errors per frame: the frame from column
// `frameColumn`, the error from the column named `errorName` (or column `errorColumn` when the
// name is empty), rows whose `filterColumn` cell does not start with `filterPrefix` skipped.
// A missing or unreadable file, or a header without the column, gives no frames.
FrameErrors readErrorColumn(const std::string& path, const std::string& errorName,
                            std::size_t errorColumn, std::size_t filterColumn = 0,
                            const std::string& filterPrefix = "") {
    FrameErrors out;
    std::string text;
    try {
        text = readTextFile(path, "measurement file", kMaxRunReportBytes * 4, Links::Refuse);
    } catch (const InputError&) {
        return out;
    }
    std::stringstream in(text);
    std::string line;
    std::getline(in, line);
    if (!errorName.empty()) {
        const auto header = csvCells(line);
        const auto at = std::find(header.begin(), header.end(), errorName);
        if (at == header.end()) return out;
        errorColumn = std::size_t(at - header.begin());
    }
    while (std::getline(in, line)) {
        const auto f = csvCells(line);
        if (f.size() <= std::max(errorColumn, filterColumn)) continue;
        if (!filterPrefix.empty() && f[filterColumn].rfind(filterPrefix, 0) != 0) continue;
        char* end = nullptr;
        const long frame = std::strtol(f[0].c_str(), &end, 10);
        if (end == f[0].c_str() || frame < 0 || frame > 100000000) continue;
        char* numberEnd = nullptr;
        const double e = std::strtod(f[errorColumn].c_str(), &numberEnd);
        if (numberEnd != f[errorColumn].c_str() && std::isfinite(e)) out.add(int(frame), e);
    }
    return out;
}

}  // namespace

FrameErrors readFrameErrors(const std::string& runDir, bool reference, bool drawn) {
    // reference.csv: frame,witness,x,y,z,total,...,drawn,...; measure.csv: frame,...,
    // error_mean (4). Objects are not headline: reference.csv's terrain rows ("ring_*") only.
    if (!reference) return readErrorColumn(runDir + "/measure.csv", "", 4);
    return readErrorColumn(runDir + "/reference.csv", drawn ? "drawn" : "", 5, 1, "ring_");
}

FrameErrors readScreenErrors(const std::string& runDir) {
    // screen.csv: frame,kind,error,bias,x,y,z,nx,ny,nz.
    return readErrorColumn(runDir + "/screen.csv", "error", 2);
}

RatioInterval pairedBootstrapRatio(const FrameErrors& ours, const FrameErrors& other, int resamples,
                                   std::uint64_t seed) {
    // The frames both measured, in order: (our sum, count, their sum, count).
    struct Pair {
        double a;
        int na;
        double b;
        int nb;
    };
    std::vector<Pair> pairs;
    for (const auto& [frame, a] : ours.byFrame) {
        const auto it = other.byFrame.find(frame);
        if (it != other.byFrame.end())
            pairs.push_back({a.first, a.second, it->second.first, it->second.second});
    }
    RatioInterval r;
    r.frames = int(pairs.size());
    const auto ratioOf = [](double a, int na, double b, int nb) {
        return na && nb && b > 0.0 ? (a / na) / (b / nb) : std::nan("");
    };
    double a = 0.0, b = 0.0;
    int na = 0, nb = 0;
    for (const Pair& p : pairs) a += p.a, na += p.na, b += p.b, nb += p.nb;
    r.ratio = ratioOf(a, na, b, nb);
    if (pairs.empty() || !std::isfinite(r.ratio)) {
        r.frames = 0;
        r.lo = r.hi = r.ratio;
        return r;
    }
    const int n = int(pairs.size());
    const int block = std::max(1, int(std::ceil(std::cbrt(double(n)))));
    const int starts = n - block + 1;
    std::mt19937_64 random(seed);
    std::uniform_int_distribution<int> pick(0, starts - 1);
    std::vector<double> ratios;
    ratios.reserve(std::size_t(resamples));
    for (int s = 0; s < resamples; ++s) {
        double sa = 0.0, sb = 0.0;
        int ca = 0, cb = 0;
        for (int drawn = 0; drawn < n;) {
            const int start = pick(random);
            for (int i = start; i < start + block && drawn < n; ++i, ++drawn) {
                sa += pairs[i].a, ca += pairs[i].na, sb += pairs[i].b, cb += pairs[i].nb;
            }
        }
        const double v = ratioOf(sa, ca, sb, cb);
        if (std::isfinite(v)) ratios.push_back(v);
    }
    if (ratios.empty()) {
        r.frames = 0;
        r.lo = r.hi = r.ratio;
        return r;
    }
    std::sort(ratios.begin(), ratios.end());
    const auto at = [&](double q) {
        const double x = q * double(ratios.size() - 1);
        const std::size_t i = std::size_t(x);
        const double t = x - double(i);
        return i + 1 < ratios.size() ? ratios[i] * (1.0 - t) + ratios[i + 1] * t : ratios[i];
    };
    r.lo = at(0.025);
    r.hi = at(0.975);
    return r;
}

std::string formatRatio(const RatioInterval& r) {
    if (!std::isfinite(r.ratio)) return "—";
    char text[96];
    if (r.frames > 0)
        std::snprintf(text, sizeof text, "%.3g [%.3g, %.3g]", r.ratio, r.lo, r.hi);
    else
        std::snprintf(text, sizeof text, "%.3g", r.ratio);
    return text;
}

}  // namespace amb
