// BenchSweep_test.cpp — the sweep file of `ambience bench` (app/bench/BenchSweep.h): what it accepts,
// and the inputs the fuzzer (tests/fuzz/fuzz_sweep) showed must be refused.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app/bench/BenchSweep.h"
#include "world/Error.h"

namespace amb {
namespace {

const std::vector<std::string> kMethods = {"volume", "grid", "hemisphere"};

std::string refusal(const std::string& text) {
    try {
        parseSweep(text, "s.json", kMethods);
    } catch (const InputError& e) {
        return e.what();
    }
    return "accepted";
}

TEST(BenchSweep, ParsesPointsAfterTheDefault) {
    const auto points = parseSweep(
        R"({"points": [{"label": "b1", "methods": ["volume"], "volume": {"store": {"blendTime_s": 1}},
                        "facesPerFrame": 2},
                       {"label": "g24", "methods": ["grid"], "baseline": {"gridSpacing_m": 24}}]})",
        "s.json", kMethods);
    ASSERT_EQ(points.size(), 3u);
    EXPECT_EQ(points[0].label, "default");
    EXPECT_TRUE(points[0].methods.empty());
    EXPECT_EQ(points[0].facesPerFrame, 1);
    EXPECT_EQ(points[1].label, "b1");
    EXPECT_EQ(points[1].methods, std::set<std::string>{"volume"});
    EXPECT_EQ(points[1].facesPerFrame, 2);
    EXPECT_EQ(points[1].volume["store"]["blendTime_s"], 1);
    EXPECT_EQ(points[2].baseline["gridSpacing_m"], 24);
    EXPECT_EQ(readSweep("", kMethods).size(), 1u);
    // Budgets above one probe a frame (a GPU's territory) are points like any other.
    const auto big = parseSweep(R"({"points": [{"label": "f12", "facesPerFrame": 12},
                                               {"label": "f24", "facesPerFrame": 24}]})",
                                "s.json", kMethods);
    ASSERT_EQ(big.size(), 3u);
    EXPECT_EQ(big[1].facesPerFrame, 12);
    EXPECT_EQ(big[2].facesPerFrame, 24);
}

TEST(BenchSweep, RefusesBadPointsNamingWhere) {
    EXPECT_NE(refusal("{\"points\": [{\"label\": \"a\"},").find("s.json: malformed JSON"),
              std::string::npos);
    EXPECT_NE(refusal(R"({"points": {}})").find("expected {\"points\""), std::string::npos);
    EXPECT_NE(refusal(R"({"points": [{"label": "a b"}]})").find("points[0]: label"),
              std::string::npos);
    EXPECT_NE(refusal(R"({"points": [{"label": "a"}, {"label": "a"}]})").find("points[1]"),
              std::string::npos);
    EXPECT_NE(refusal(R"({"points": [{"label": "default"}]})").find("used twice"),
              std::string::npos);
    EXPECT_NE(refusal(R"({"points": [{"methods": ["nearest"]}]})").find("unknown ambience method"),
              std::string::npos);
    EXPECT_NE(refusal(R"({"points": [{"label": "a", "extra": 1}]})").find("unknown key"),
              std::string::npos);
    for (const char* faces : {"0", "25", "-1", "1.5"})
        EXPECT_NE(refusal(std::string(R"({"points": [{"label": "a", "facesPerFrame": )") + faces +
                          "}]}"),
                  "accepted")
            << faces;
    EXPECT_THROW(readSweep("/nonexistent/sweep.json", kMethods), InputError);
    EXPECT_THROW(readSweep("/dev/zero", kMethods), InputError);  // not a regular file
}

// facesPerFrame was narrowed to int before the range check, so 2^32 + 1 read as 1 and was
// accepted; so was -(2^32) + 2 (as 2).
TEST(BenchSweep, FacesPerFrameCheckedBeforeNarrowing) {
    for (const char* faces : {"4294967297", "-4294967294", "18446744073709551615",
                              "9223372036854775807"}) {
        EXPECT_NE(refusal(std::string(R"({"points": [{"label": "a", "facesPerFrame": )") + faces +
                          "}]}")
                      .find("facesPerFrame: expected 1 to 24"),
                  std::string::npos)
            << faces;
    }
}

// A settings object nested 100000 deep (600 kB, well under the size limit) parsed fine but
// overflowed the stack when the point was copied (nlohmann's copy recurses): now refused with
// the depth named, and nesting as deep as the limit still reads.
TEST(BenchSweep, DeepNestingRefusedNotACrash) {
    auto nested = [](int depth) {
        std::string v;
        for (int i = 0; i < depth; ++i) v += "{\"a\":";
        v += "1";
        v += std::string(std::size_t(depth), '}');
        return R"({"points": [{"label": "deep", "volume": )" + v + "}]}";
    };
    EXPECT_NE(refusal(nested(100000)).find("nested deeper than 32 levels"), std::string::npos);
    // {"points": [ {"volume": <29 levels>} ]} is 32 levels in all.
    EXPECT_EQ(refusal(nested(kMaxSweepJsonDepth - 3)), "accepted");
    EXPECT_NE(refusal(nested(kMaxSweepJsonDepth - 2)), "accepted");
}

TEST(BenchSweep, BudgetsAreSortedDistinctAndInRange) {
    EXPECT_EQ(parseBudgets("24,1,6,6,3", "--budgets"), (std::vector<int>{1, 3, 6, 24}));
    EXPECT_EQ(parseBudgets("24", "--budgets"), (std::vector<int>{24}));
    for (const std::string bad : {"", "0", "25", "x", "3,", ",3", "1.5", "2x", "-1",
                                  "99999999999999999999", "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17"}) {
        try {
            parseBudgets(bad, "--budgets");
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("--budgets"), std::string::npos) << e.what();
        }
    }
}

TEST(BenchSweep, EveryPointRunsAtEveryBudget) {
    const auto points = parseSweep(
        R"({"points": [{"label": "b1", "methods": ["volume"], "facesPerFrame": 2}]})", "s.json",
        kMethods);
    const auto all = withBudgets(points, {1, 6}, "--budgets");
    ASSERT_EQ(all.size(), 4u);
    EXPECT_EQ(all[0].label, "default");
    EXPECT_EQ(all[0].facesPerFrame, 1);
    EXPECT_EQ(all[1].label, "default-f6");
    EXPECT_EQ(all[1].facesPerFrame, 6);
    EXPECT_EQ(all[1].family, "default");
    EXPECT_EQ(all[2].label, "b1");
    EXPECT_EQ(all[2].facesPerFrame, 1);  // the budget overrides the point's own
    EXPECT_EQ(all[3].label, "b1-f6");
    EXPECT_EQ(all[3].family, "b1");
    EXPECT_EQ(all[3].methods, points[1].methods);
    // A point already named like a budget's label is refused, not run twice.
    const auto clash = parseSweep(R"({"points": [{"label": "default-f6"}]})", "s.json", kMethods);
    EXPECT_THROW(withBudgets(clash, {1, 6}, "--budgets"), InputError);
}

}  // namespace
}  // namespace amb
