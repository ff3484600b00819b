// BenchCollect.cpp — the files --collect reads back (see BenchCollect.h).
#include "app/bench/BenchCollect.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "app/cli/OutputPaths.h"
#include "app/cli/ReferenceLightFlags.h"
#include "world/Error.h"
#include "world/JsonText.h"

namespace amb {

namespace {

using nlohmann::json;

bool isControl(char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 0x20 || u == 0x7f;
}

// Reads the keys of bench.json, each checked for its type; a message names the key.
class ManifestFields {
  public:
    ManifestFields(const json& j, std::string where) : j_(j), where_(std::move(where)) {
        if (!j_.is_object())
            throw InputError(where_, "expected a JSON object (bench.json of --emit)");
    }
    const json& at(const char* key) const {
        if (!j_.contains(key)) fail(key, "missing");
        return j_.at(key);
    }
    std::string text(const char* key) const {
        const json& v = at(key);
        if (!v.is_string()) fail(key, "expected a string");
        const std::string s = v.get<std::string>();
        if (hasControlCharacter(s)) fail(key, "holds a control character");
        return s;
    }
    int integer(const char* key, int lo, int hi) const {
        const json& v = at(key);
        if (!v.is_number_integer()) fail(key, "expected a whole number");
        // Above LLONG_MAX an unsigned value would wrap negative as a long long.
        const unsigned long long u = v.is_number_unsigned() ? v.get<unsigned long long>() : 0;
        const long long x = v.is_number_unsigned()
                                ? (u > (unsigned long long)hi ? (long long)hi + 1 : (long long)u)
                                : v.get<long long>();
        if (x < lo || x > hi)
            fail(key, "expected " + std::to_string(lo) + " to " + std::to_string(hi));
        return int(x);
    }
    bool boolean(const char* key) const {
        const json& v = at(key);
        if (!v.is_boolean()) fail(key, "expected true or false");
        return v.get<bool>();
    }
    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw InputError(where_, "'" + key + "': " + what);
    }

  private:
    const json& j_;
    std::string where_;
};

}  // namespace

// ---- Text for one line -----------------------------------------------------------------------

bool hasControlCharacter(const std::string& text) {
    for (const char c : text)
        if (isControl(c)) return true;
    return false;
}

std::string printable(const std::string& text, std::size_t limit) {
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (out.size() >= limit) return out + "...";
        const char c = text[i];
        if (c == '\n') {
            out += "\\n";
        } else if (c == '\t') {
            out += "\\t";
        } else if (c == '\r') {
            out += "\\r";
        } else if (isControl(c)) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(static_cast<unsigned char>(c)));
            out += hex;
        } else {
            out += c;
        }
    }
    return out;
}

// ---- exit-status.txt -------------------------------------------------------------------------

ExitStatus parseExitStatus(const std::string& text, const std::string& where) {
    const auto refuse = [&] {
        throw InputError(
            where, "expected \"<exit code 0-255> <seconds>\", got \"" + printable(text, 60) + "\"");
    };
    // Words separated by blanks, one optional newline at the end.
    std::string body = text;
    if (!body.empty() && body.back() == '\n') body.pop_back();
    std::vector<std::string> words;
    std::string word;
    for (const char c : body) {
        if (c == ' ') {
            if (!word.empty()) words.push_back(word), word.clear();
        } else if (isControl(c)) {
            refuse();
        } else {
            word += c;
        }
    }
    if (!word.empty()) words.push_back(word);
    if (words.empty() || words.size() > 2) refuse();
    const std::string& code = words[0];
    if (code.empty() || code.size() > 3 ||
        code.find_first_not_of("0123456789") != std::string::npos)
        refuse();
    ExitStatus s;
    s.code = std::atoi(code.c_str());
    if (s.code > 255) refuse();
    if (words.size() == 2) {
        const std::string& seconds = words[1];
        if (seconds.find_first_not_of("0123456789.eE+-") != std::string::npos) refuse();
        char* end = nullptr;
        const double v = std::strtod(seconds.c_str(), &end);
        if (end != seconds.c_str() + seconds.size() || !std::isfinite(v) || v < 0.0) refuse();
        s.wall_s = v;
    }
    return s;
}

// ---- report.json -----------------------------------------------------------------------------

nlohmann::json parseRunReport(const std::string& text, const std::string& where) {
    json j;
    try {
        j = parseJsonText(text, where);
    } catch (const json::exception& e) {
        throw InputError(where, std::string("malformed report: ") + e.what());
    }
    if (!j.is_object()) throw InputError(where, "malformed report: expected a JSON object");
    return j;
}

// ---- bench.json ------------------------------------------------------------------------------

BenchManifest parseBenchManifest(const std::string& text, const std::string& where) {
    json j;
    try {
        j = parseJsonText(text, where);
    } catch (const json::exception& e) {
        throw InputError(where, std::string("not a bench.json of --emit: ") + e.what());
    }
    const ManifestFields f(j, where);
    BenchManifest m;
    m.command = f.text("command");
    const json& replays = f.at("replays");
    if (!replays.is_array() || replays.empty()) f.fail("replays", "expected a non-empty list");
    std::set<std::string> names;
    for (std::size_t i = 0; i < replays.size(); ++i) {
        const ManifestFields r(replays[i], where + ": replays[" + std::to_string(i) + "]");
        BenchManifest::Replay replay{r.text("name"), r.text("path")};
        if (replay.name.empty() || safeFileStem(replay.name) != replay.name)
            r.fail("name", "'" + printable(replay.name) +
                               "' is not a plain file stem (letters, digits, '-', '_')");
        if (!names.insert(replay.name).second)
            r.fail("name", "'" + replay.name + "' is named twice");
        if (replay.path.empty() || replay.path.front() != '/')
            r.fail("path", "expected an absolute path");
        m.replays.push_back(std::move(replay));
    }
    m.methods = f.text("methods");
    m.sweep = f.text("sweep");
    if (!m.sweep.empty() && m.sweep != "sweep.json")
        f.fail("sweep", "expected \"\" or \"sweep.json\" (the copy in the folder), got '" +
                            printable(m.sweep) + "'");
    m.budgets = f.text("budgets");
    m.oracle = f.text("oracle");
    m.referenceEvery = f.integer("referenceEvery", 1, 1000000);
    m.fullLengthBudget = f.integer("fullLengthBudget", 1, 64);
    m.screenWitnesses = f.integer("screenWitnesses", 0, 4096);
    m.measureEvery = f.integer("measureEvery", 1, 1000000);
    m.maxFrames = f.integer("maxFrames", 0, 100000000);
    m.stride = f.integer("stride", 1, 1000000);
    m.frames = f.boolean("frames");
    m.backend = f.text("backend");
    if (j.contains("referenceLight")) {
        m.referenceLight = f.text("referenceLight");
        if (m.referenceLight != "bounce" && m.referenceLight != "hemisphere")
            f.fail("referenceLight", "expected bounce or hemisphere");
        m.bounceSpacing_m = f.integer("bounceSpacing_m", 8, 4096);
        m.bounceReach_m = f.integer("bounceReach_m", 0, 20000);
        m.bounceFace = f.integer("bounceFace", 4, 256);
        // Manifests from before the two layers have one.
        if (j.contains("bounceCanopy_m")) m.bounceCanopy_m = f.integer("bounceCanopy_m", 0, 100);
    }
    if (j.contains("captureLight")) {
        m.captureLight = f.text("captureLight");
        if (!isCaptureLight(m.captureLight))
            f.fail("captureLight", "expected own or reference");
    }
    const json& runs = f.at("runs");
    if (!runs.is_array()) f.fail("runs", "expected a list of run folders");
    for (const json& r : runs) {
        if (!r.is_string()) f.fail("runs", "expected a list of run folders");
        const std::string dir = r.get<std::string>();
        // runs/<replay>__<method>__<point>: one plain component below runs/.
        const std::string name = dir.rfind("runs/", 0) == 0 ? dir.substr(5) : std::string();
        if (name.empty() || name.find_first_of("/\\") != std::string::npos || name == "." ||
            name == ".." || name.front() == '.' || hasControlCharacter(name))
            f.fail("runs", "'" + printable(dir) + "' is not a folder runs/<name>");
        m.runs.push_back(dir);
    }
    return m;
}

nlohmann::json benchManifestJson(const BenchManifest& m) {
    json replays = json::array();
    for (const auto& r : m.replays) replays.push_back({{"name", r.name}, {"path", r.path}});
    return {{"command", m.command},
            {"replays", replays},
            {"methods", m.methods},
            {"sweep", m.sweep},
            {"budgets", m.budgets},
            {"oracle", m.oracle},
            {"referenceEvery", m.referenceEvery},
            {"fullLengthBudget", m.fullLengthBudget},
            {"screenWitnesses", m.screenWitnesses},
            {"measureEvery", m.measureEvery},
            {"maxFrames", m.maxFrames},
            {"stride", m.stride},
            {"frames", m.frames},
            {"backend", m.backend},
            {"referenceLight", m.referenceLight},
            {"bounceSpacing_m", int(std::lround(m.bounceSpacing_m))},
            {"bounceReach_m", int(std::lround(m.bounceReach_m))},
            {"bounceFace", m.bounceFace},
            {"bounceCanopy_m", int(std::lround(m.bounceCanopy_m))},
            {"captureLight", m.captureLight},
            {"runs", m.runs}};
}

}  // namespace amb
