// Replay.cpp — replay file format v1 (documented in replays/README.md): reader with validation
// that names the field or sample index, writer, and interpolation between samples.
//
// [SECTION] Replay helpers
// [SECTION] Reader: JSON -> Replay, with validation
// [SECTION] Writer: Replay -> JSON
#include "world/Replay.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "world/Error.h"
#include "world/JsonText.h"
#include "world/TextFile.h"

namespace amb {

using nlohmann::json;

namespace {

constexpr const char* kFormatName = "ambience-replay";
// Columns of one sample row, in order; the file repeats this list in "sampleFields".
const char* const kSampleFields[] = {"t_s",  "x_m",  "y_m",  "z_m",  "forward_x", "forward_y",
                                     "forward_z", "up_x", "up_y", "up_z", "cut"};
constexpr int kSampleFieldCount = 11;
constexpr double kMaxCoordinate_m = 1.0e8;   // far beyond any replay; rejects absurd values
constexpr std::size_t kMaxSamples = 2'000'000;

}  // namespace

// ---- [SECTION] Replay helpers ----------------------------------------------------------------

const char* toString(ReplayMode mode) {
    switch (mode) {
        case ReplayMode::Drive: return "drive";
        case ReplayMode::Fly: return "fly";
        case ReplayMode::Static: return "static";
    }
    return "?";
}

double Replay::duration_s() const {
    return samples.empty() ? 0.0 : samples.back().time_s - samples.front().time_s;
}

double Replay::timeOfDayAt_h(double time_s) const {
    const double hours = timeOfDayStart_h + timeRate * time_s / 3600.0;
    double wrapped = std::fmod(hours, 24.0);
    if (wrapped < 0.0) wrapped += 24.0;
    // A tiny negative remainder (-1e-17) plus 24 rounds to 24.0 itself: that is midnight, 0.
    if (wrapped >= 24.0) wrapped = 0.0;
    return wrapped;
}

CameraSample Replay::sampleAt(double time_s) const {
    AMB_CHECK(!samples.empty());
    if (time_s <= samples.front().time_s) return samples.front();
    if (time_s >= samples.back().time_s) return samples.back();
    // Samples are at a fixed step: index directly, then correct for rounding.
    std::size_t i = static_cast<std::size_t>((time_s - samples.front().time_s) / step_s);
    i = std::min(i, samples.size() - 2);
    while (i > 0 && samples[i].time_s > time_s) --i;
    while (i + 2 < samples.size() && samples[i + 1].time_s <= time_s) ++i;
    const CameraSample& a = samples[i];
    const CameraSample& b = samples[i + 1];
    if (b.cut) return a;  // never interpolate across a teleport
    const double f = (time_s - a.time_s) / (b.time_s - a.time_s);
    CameraSample s;
    s.time_s = time_s;
    s.position_m = glm::mix(a.position_m, b.position_m, f);
    s.forward = glm::normalize(glm::mix(a.forward, b.forward, f));
    glm::dvec3 up = glm::mix(a.up, b.up, f);
    up -= s.forward * glm::dot(up, s.forward);
    s.up = glm::normalize(up);
    return s;
}

// ---- [SECTION] Reader ------------------------------------------------------------------------

namespace {

// Validation context: every error names the input and the JSON path of the offending value.
struct Reader {
    std::string where;

    [[noreturn]] void fail(const std::string& field, const std::string& what) const {
        throw InputError(where, field.empty() ? what : "field '" + field + "': " + what);
    }

    const json& member(const json& obj, const char* key, const std::string& path) const {
        auto it = obj.find(key);
        if (it == obj.end()) fail(path + key, "missing (expected a value)");
        return *it;
    }

    double number(const json& obj, const char* key, const std::string& path, double lo,
                  double hi) const {
        const json& v = member(obj, key, path);
        if (!v.is_number()) fail(path + key, std::string("expected a number, got ") + v.type_name());
        const double d = v.get<double>();
        if (!std::isfinite(d)) fail(path + key, "expected a finite number");
        if (d < lo || d > hi) {
            std::ostringstream s;
            s << "value " << d << " out of range [" << lo << ", " << hi << "]";
            fail(path + key, s.str());
        }
        return d;
    }

    double numberOr(const json& obj, const char* key, const std::string& path, double lo,
                    double hi, double fallback) const {
        return obj.contains(key) ? number(obj, key, path, lo, hi) : fallback;
    }

    std::string string(const json& obj, const char* key, const std::string& path,
                       bool required) const {
        if (!required && !obj.contains(key)) return {};
        const json& v = member(obj, key, path);
        if (!v.is_string()) fail(path + key, std::string("expected a string, got ") + v.type_name());
        return v.get<std::string>();
    }

    const json& object(const json& obj, const char* key, const std::string& path) const {
        const json& v = member(obj, key, path);
        if (!v.is_object()) fail(path + key, std::string("expected an object, got ") + v.type_name());
        return v;
    }
};

WorldSettings readWorld(const Reader& r, const json& w) {
    const std::string p = "world.";
    WorldSettings s;
    const json& seed = r.member(w, "seed", p);
    if (!seed.is_number_unsigned() && !(seed.is_number_integer() && seed.get<std::int64_t>() >= 0))
        r.fail(p + "seed", std::string("expected a non-negative integer, got ") +
                               (seed.is_number() ? seed.dump() : seed.type_name()));
    s.seed = seed.get<std::uint64_t>();
    s.latitude_deg = r.number(w, "latitude_deg", p, -90.0, 90.0);
    s.dayOfYear = static_cast<int>(r.number(w, "dayOfYear", p, 1.0, 366.0));
    if (s.dayOfYear != r.number(w, "dayOfYear", p, 1.0, 366.0))
        r.fail(p + "dayOfYear", "expected an integer day 1..366");
    s.waterLevel_m = r.numberOr(w, "waterLevel_m", p, -1.0e4, 1.0e4, s.waterLevel_m);
    s.roadRegion_m = r.numberOr(w, "roadRegion_m", p, 100.0, 1.0e6, s.roadRegion_m);
    return s;
}

}  // namespace

Replay parseReplay(const std::string& text, const std::string& where) {
    Reader r{where};
    json doc;
    try {
        doc = parseJsonText(text, where);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e400
        std::string msg = e.what();
        // nlohmann's message starts with "[json.exception.parse_error.101] "; keep the rest.
        if (auto pos = msg.find("] "); pos != std::string::npos) msg = msg.substr(pos + 2);
        throw InputError(where, "not valid JSON (" + msg + ")");
    }
    if (!doc.is_object()) r.fail("", "expected a JSON object at the top level");

    const std::string format = r.string(doc, "format", "", true);
    if (format != kFormatName)
        r.fail("format", "expected \"" + std::string(kFormatName) + "\", got \"" + format + "\"");
    const json& version = r.member(doc, "version", "");
    if (!version.is_number_integer())
        r.fail("version", std::string("expected an integer, got ") + version.type_name());
    if (version.get<std::int64_t>() != Replay::kFormatVersion)
        r.fail("version", "unsupported version " + version.dump() + " (this build reads " +
                              std::to_string(Replay::kFormatVersion) + ")");

    Replay rp;
    rp.name = r.string(doc, "name", "", false);
    rp.description = r.string(doc, "description", "", false);
    rp.world = readWorld(r, r.object(doc, "world", ""));

    const std::string mode = r.string(doc, "mode", "", true);
    if (mode == "drive") rp.mode = ReplayMode::Drive;
    else if (mode == "fly") rp.mode = ReplayMode::Fly;
    else if (mode == "static") rp.mode = ReplayMode::Static;
    else r.fail("mode", "expected \"drive\", \"fly\" or \"static\", got \"" + mode + "\"");

    const json& tod = r.object(doc, "timeOfDay", "");
    rp.timeOfDayStart_h = r.number(tod, "start_h", "timeOfDay.", 0.0, 24.0);
    if (rp.timeOfDayStart_h >= 24.0) rp.timeOfDayStart_h = 0.0;
    rp.timeRate = r.number(tod, "rate", "timeOfDay.", 0.0, 1.0e5);
    rp.step_s = r.number(doc, "step_s", "", 1.0e-4, 10.0);
    if (rp.step_s <= 0.0) r.fail("step_s", "expected a positive step");

    // Columns must be exactly the v1 list, so a file written for another layout is refused.
    const json& fields = r.member(doc, "sampleFields", "");
    json expected = json::array();
    for (const char* f : kSampleFields) expected.push_back(f);
    if (fields != expected) r.fail("sampleFields", "expected " + expected.dump());

    const json& rows = r.member(doc, "samples", "");
    if (!rows.is_array()) r.fail("samples", std::string("expected an array, got ") + rows.type_name());
    if (rows.empty()) r.fail("samples", "expected at least one sample");
    if (rows.size() > kMaxSamples)
        r.fail("samples", "too many samples (" + std::to_string(rows.size()) + ", at most " +
                              std::to_string(kMaxSamples) + ")");

    rp.samples.reserve(rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const json& row = rows[i];
        const std::string at = "samples[" + std::to_string(i) + "]";
        if (!row.is_array() || row.size() != kSampleFieldCount)
            r.fail(at, "expected an array of " + std::to_string(kSampleFieldCount) + " values");
        double v[kSampleFieldCount];
        for (int k = 0; k < kSampleFieldCount; ++k) {
            const json& x = row[k];
            const std::string field = at + "." + kSampleFields[k];
            if (k == kSampleFieldCount - 1) {
                if (!x.is_boolean()) r.fail(field, std::string("expected true or false, got ") + x.type_name());
                v[k] = x.get<bool>() ? 1.0 : 0.0;
                continue;
            }
            if (!x.is_number()) r.fail(field, std::string("expected a number, got ") + x.type_name());
            v[k] = x.get<double>();
            if (!std::isfinite(v[k])) r.fail(field, "expected a finite number");
            if (std::abs(v[k]) > kMaxCoordinate_m) r.fail(field, "absurd value " + x.dump());
        }
        CameraSample s;
        s.time_s = v[0];
        s.position_m = {v[1], v[2], v[3]};
        s.forward = {v[4], v[5], v[6]};
        s.up = {v[7], v[8], v[9]};
        s.cut = v[10] != 0.0;
        if (std::abs(glm::length(s.forward) - 1.0) > 1e-3)
            r.fail(at + ".forward", "expected a unit vector");
        if (std::abs(glm::length(s.up) - 1.0) > 1e-3) r.fail(at + ".up", "expected a unit vector");
        if (std::abs(glm::dot(s.forward, s.up)) > 1e-3)
            r.fail(at + ".up", "expected a vector orthogonal to forward");
        // Fixed step: sample i is at t0 + i * step (to a microsecond), so time is monotonic.
        if (i > 0) {
            const double expectedT = rp.samples.front().time_s + static_cast<double>(i) * rp.step_s;
            if (s.time_s <= rp.samples.back().time_s)
                r.fail(at + ".t_s", "time not increasing (" + std::to_string(s.time_s) +
                                        " after " + std::to_string(rp.samples.back().time_s) + ")");
            if (std::abs(s.time_s - expectedT) > 1e-6 + 1e-9 * std::abs(expectedT))
                r.fail(at + ".t_s", "expected " + std::to_string(expectedT) +
                                        " (first time + index x step_s)");
        }
        rp.samples.push_back(s);
    }
    return rp;
}

Replay readReplay(const std::string& path) {
    return parseReplay(readTextFile(path, "replay file", kMaxReplayFileBytes), path);
}

// ---- [SECTION] Writer ------------------------------------------------------------------------

std::string formatReplay(const Replay& rp) {
    nlohmann::ordered_json doc;  // keeps "format" and "version" first
    doc["format"] = kFormatName;
    doc["version"] = Replay::kFormatVersion;
    doc["name"] = rp.name;
    doc["description"] = rp.description;
    doc["world"] = {{"seed", rp.world.seed},
                    {"latitude_deg", rp.world.latitude_deg},
                    {"dayOfYear", rp.world.dayOfYear},
                    {"waterLevel_m", rp.world.waterLevel_m},
                    {"roadRegion_m", rp.world.roadRegion_m}};
    doc["mode"] = toString(rp.mode);
    doc["timeOfDay"] = {{"start_h", rp.timeOfDayStart_h}, {"rate", rp.timeRate}};
    doc["step_s"] = rp.step_s;
    doc["sampleFields"] = nlohmann::ordered_json::array();
    for (const char* f : kSampleFields) doc["sampleFields"].push_back(f);
    // One sample per line keeps files diffable; nlohmann prints doubles with round-trip precision.
    std::string out = "{\n";
    bool first = true;
    for (auto it = doc.begin(); it != doc.end(); ++it) {
        out += first ? "  " : ",\n  ";
        first = false;
        out += nlohmann::ordered_json(it.key()).dump() + ": " + it.value().dump();
    }
    out += ",\n  \"samples\": [";
    for (std::size_t i = 0; i < rp.samples.size(); ++i) {
        const CameraSample& s = rp.samples[i];
        json row = {s.time_s,    s.position_m.x, s.position_m.y, s.position_m.z,
                    s.forward.x, s.forward.y,    s.forward.z,    s.up.x,
                    s.up.y,      s.up.z,         s.cut};
        out += (i ? ",\n    " : "\n    ") + row.dump();
    }
    out += "\n  ]\n}\n";
    return out;
}

void writeReplay(const Replay& replay, const std::string& path) {
    std::ofstream out(path, std::ios::binary);
    if (!out) throw InputError(path, "cannot open for writing");
    out << formatReplay(replay);
    if (!out) throw InputError(path, "write error");
}

}  // namespace amb
