// BenchCollect_test.cpp — the readers of `ambience bench --collect` on their own: the exit status
// file read strictly, reports that must be shallow JSON objects, and a bench.json whose names
// cannot lead outside its folder.
#include <gtest/gtest.h>

#include "app/bench/BenchCollect.h"
#include "world/Error.h"

namespace amb {
namespace {

std::string refusal(const std::function<void()>& read) {
    try {
        read();
    } catch (const InputError& e) {
        return e.what();
    }
    return "accepted";
}

TEST(BenchCollect, ExitStatusIsReadStrictly) {
    const ExitStatus ok = parseExitStatus("0 12\n", "s");
    EXPECT_EQ(ok.code, 0);
    EXPECT_DOUBLE_EQ(ok.wall_s, 12.0);
    const ExitStatus killed = parseExitStatus("137 3.25", "s");
    EXPECT_EQ(killed.code, 137);
    EXPECT_DOUBLE_EQ(killed.wall_s, 3.25);
    EXPECT_DOUBLE_EQ(parseExitStatus("2\n", "s").wall_s, -1.0);  // no wall time: unknown
    // A shell's codes are 0-255: "killed by signal 2147483519" came from trusting any integer.
    for (const char* bad : {"2147483647 1", "256 1", "-1 2", "abc", "", "\n", "0 nan", "0 inf",
                            "0 -1", "0 1 2", "0\n1\n", "0x10 1", "0 1e999", "1\t2"}) {
        const std::string why = refusal([&] { parseExitStatus(bad, "runs/x/exit-status.txt"); });
        EXPECT_NE(why.find("runs/x/exit-status.txt: expected"), std::string::npos)
            << "'" << bad << "': " << why;
        EXPECT_EQ(why.find('\n'), std::string::npos) << why;  // one line
    }
}

TEST(BenchCollect, ReportIsAShallowObject) {
    EXPECT_EQ(parseRunReport(R"({"frameCount": 3, "measurement": {"oracle": "self"}})", "r")
                  .at("frameCount"),
              3);
    EXPECT_NE(refusal([] { parseRunReport("[]", "r"); }).find("expected a JSON object"),
              std::string::npos);
    EXPECT_NE(refusal([] { parseRunReport("{", "r"); }).find("malformed report"),
              std::string::npos);
    // A NUL ends the input for the JSON library: the junk after it must not pass unseen.
    EXPECT_NE(refusal([] { parseRunReport(std::string("{}\0junk", 7), "r"); }).find("NUL byte"),
              std::string::npos);
    // A million levels deep: refused while parsing, before anything recurses over it (it
    // crashed the collector when a copy of the value overflowed the stack).
    std::string deep = "{\"measurement\": ";
    deep += std::string(1000000, '[') + std::string(1000000, ']') + "}";
    EXPECT_NE(refusal([&] { parseRunReport(deep, "r"); }).find("nested deeper than"),
              std::string::npos);
}

BenchManifest sampleManifest() {
    BenchManifest m;
    m.command = "ambience bench --emit /tmp/e";
    m.replays = {{"highway-drive", "/data/replays/highway-drive.json"},
                 {"low-flight", "/data/replays/low-flight.json"}};
    m.methods = "volume,constant";
    m.sweep = "sweep.json";
    m.oracle = "self";
    m.backend = "auto";
    m.runs = {"runs/highway-drive__constant__default", "runs/highway-drive__volume__default"};
    return m;
}

TEST(BenchCollect, ManifestRoundTrips) {
    const BenchManifest m = sampleManifest();
    const BenchManifest back = parseBenchManifest(benchManifestJson(m).dump(2), "bench.json");
    EXPECT_EQ(benchManifestJson(back), benchManifestJson(m));
}

// bench.json records what lit the reference (lighting/BounceField.h); one written before the
// bounce field has no such key and reads as the hemisphere, the only light then; any other
// light is refused.
TEST(BenchCollect, ManifestRecordsTheReferenceLight) {
    BenchManifest m = sampleManifest();
    m.oracle = "reference";
    m.referenceLight = "bounce";
    m.bounceSpacing_m = 128.0;
    nlohmann::json j = benchManifestJson(m);
    EXPECT_EQ(j["referenceLight"], "bounce");
    const BenchManifest back = parseBenchManifest(j.dump(), "bench.json");
    EXPECT_EQ(back.referenceLight, "bounce");
    EXPECT_DOUBLE_EQ(back.bounceSpacing_m, 128.0);
    j.erase("referenceLight");
    EXPECT_EQ(parseBenchManifest(j.dump(), "bench.json").referenceLight, "hemisphere");
    j["referenceLight"] = "sky";
    EXPECT_THROW(parseBenchManifest(j.dump(), "bench.json"), InputError);
}

// bench.json records what lit the methods' captures (--capture-light); one written before the
// option has no such key and reads as own, the only light then; any other light is refused.
TEST(BenchCollect, ManifestRecordsTheCaptureLight) {
    BenchManifest m = sampleManifest();
    m.oracle = "reference";
    m.referenceLight = "bounce";
    m.captureLight = "reference";
    nlohmann::json j = benchManifestJson(m);
    EXPECT_EQ(j["captureLight"], "reference");
    EXPECT_EQ(parseBenchManifest(j.dump(), "bench.json").captureLight, "reference");
    j.erase("captureLight");
    EXPECT_EQ(parseBenchManifest(j.dump(), "bench.json").captureLight, "own");
    j["captureLight"] = "sun\nrm -rf";
    EXPECT_THROW(parseBenchManifest(j.dump(), "bench.json"), InputError);
}

TEST(BenchCollect, ManifestCannotLeadOutsideItsFolder) {
    const auto withChange = [](const std::function<void(nlohmann::json&)>& change) {
        nlohmann::json j = benchManifestJson(sampleManifest());
        change(j);
        return refusal([&] { parseBenchManifest(j.dump(), "D/bench.json"); });
    };
    using J = nlohmann::json;
    struct Case {
        const char* what;
        std::function<void(J&)> change;
        const char* expected;
    };
    const std::vector<Case> cases = {
        {"a replay name with ..", [](J& j) { j["replays"][0]["name"] = "../../../outside/r1"; },
         "not a plain file stem"},
        {"a replay name with a newline", [](J& j) { j["replays"][0]["name"] = "a\nb"; },
         "control character"},
        {"two replays of one name", [](J& j) { j["replays"][1]["name"] = "highway-drive"; },
         "named twice"},
        {"a relative replay path", [](J& j) { j["replays"][0]["path"] = "r.json"; },
         "absolute path"},
        {"a sweep outside the folder", [](J& j) { j["sweep"] = "/etc/passwd"; },
         "expected \"\" or \"sweep.json\""},
        {"a sweep one level up", [](J& j) { j["sweep"] = "../sweep.json"; },
         "expected \"\" or \"sweep.json\""},
        {"an oracle that is a number", [](J& j) { j["oracle"] = 5; },
         "'oracle': expected a string"},
        {"a run folder outside runs/", [](J& j) { j["runs"][0] = "runs/../../x"; },
         "is not a folder runs/<name>"},
        {"a run folder elsewhere", [](J& j) { j["runs"][0] = "/etc"; },
         "is not a folder runs/<name>"},
        {"a stride of zero", [](J& j) { j["stride"] = 0; }, "'stride': expected 1 to"},
        {"a huge unsigned count", [](J& j) { j["maxFrames"] = 18446744073709551615ull; },
         "'maxFrames': expected 0 to"},
        {"a missing key", [](J& j) { j.erase("backend"); }, "'backend': missing"},
        {"no replays", [](J& j) { j["replays"] = J::array(); }, "non-empty list"},
        {"a top level list", [](J& j) { j = J::array(); }, "expected a JSON object"},
    };
    for (const Case& c : cases) {
        const std::string why = withChange(c.change);
        EXPECT_NE(why.find(c.expected), std::string::npos) << c.what << ": " << why;
        EXPECT_EQ(why.rfind("D/bench.json", 0), 0u) << c.what << ": " << why;
        EXPECT_EQ(why.find('\n'), std::string::npos) << c.what << ": " << why;
    }
}

TEST(BenchCollect, PrintableShowsControlCharacters) {
    EXPECT_EQ(printable("a\nb\tc\x01"), "a\\nb\\tc\\x01");
    EXPECT_EQ(printable(std::string(300, 'x'), 10), std::string(10, 'x') + "...");
    EXPECT_TRUE(hasControlCharacter("x\x7f"));
    EXPECT_FALSE(hasControlCharacter("plain words, \"quoted\" and 'single' & $HOME"));
}

}  // namespace
}  // namespace amb
