// Determinism_test.cpp — two runs of the same command, each capturing its own oracle, give the
// same figures: measure.csv byte for byte, the error and pop summaries, the anchors and bytes of
// every frame, and the ambience totals. Timing columns are the only thing allowed to differ.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "GlTestContext.h"
#include "RunAmbience.h"

namespace amb {
namespace {

namespace fs = std::filesystem;

// The named columns of a plain CSV (no quoted fields), one string per row, cells joined by ','.
std::vector<std::string> csvColumns(const fs::path& path, const std::vector<std::string>& names) {
    std::ifstream in(path);
    std::string line;
    std::vector<std::string> rows;
    if (!std::getline(in, line)) {
        ADD_FAILURE() << "empty " << path;
        return rows;
    }
    auto split = [](const std::string& s) {
        std::vector<std::string> cells;
        std::stringstream ss(s);
        std::string cell;
        while (std::getline(ss, cell, ',')) cells.push_back(cell);
        return cells;
    };
    const std::vector<std::string> header = split(line);
    std::vector<std::size_t> index;
    for (const std::string& n : names) {
        std::size_t i = 0;
        while (i < header.size() && header[i] != n) ++i;
        if (i == header.size()) {
            ADD_FAILURE() << "no column " << n << " in " << path;
            return rows;
        }
        index.push_back(i);
    }
    while (std::getline(in, line)) {
        const std::vector<std::string> cells = split(line);
        std::string row;
        for (std::size_t i : index) row += (i < cells.size() ? cells[i] : "?") + ",";
        rows.push_back(row);
    }
    return rows;
}

TEST(Determinism, TwoRunsGiveIdenticalErrorAnchorsAndPop) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    platform.reset();
    const fs::path dir = test::scratchDir("determinism");
    const std::string command = "run --replay " + test::sourcePath("replays/stress-flight.json") +
                                " --max-frames 120 --no-frames --no-video --measure-every 10";
    const auto a = test::runAmbience(command + " --out " + (dir / "a").string());
    ASSERT_EQ(a.exitCode, 0) << a.err;
    const auto b = test::runAmbience(command + " --out " + (dir / "b").string());
    ASSERT_EQ(b.exitCode, 0) << b.err;

    // measure.csv: every measured frame's error (overall and per ring), byte for byte.
    const std::string ma = test::slurp((dir / "a" / "measure.csv").string());
    const std::string mb = test::slurp((dir / "b" / "measure.csv").string());
    EXPECT_EQ(test::lineCount(ma), 1 + 12);  // frames 0, 10, ..., 110
    EXPECT_EQ(ma, mb);

    std::ifstream ina(dir / "a" / "report.json"), inb(dir / "b" / "report.json");
    const auto ja = nlohmann::json::parse(ina), jb = nlohmann::json::parse(inb);
    // Both captured their own oracle (no cache), so the capture itself is compared too.
    EXPECT_GT(ja["measurement"]["oracleCaptures"].get<int>(), 0);
    EXPECT_EQ(ja["measurement"]["oracleCaptures"], jb["measurement"]["oracleCaptures"]);
    EXPECT_EQ(ja["measurement"]["error"], jb["measurement"]["error"]);
    EXPECT_EQ(ja["measurement"]["errorByRing"], jb["measurement"]["errorByRing"]);
    EXPECT_EQ(ja["measurement"]["pop"], jb["measurement"]["pop"]);
    for (const char* key : {"anchorsMax", "anchorsEnd", "bytesMax", "bytesEnd", "facesCaptured",
                            "probesCompleted", "rejectedProbes", "teleports", "anchorsInserted",
                            "anchorsRefreshed", "anchorsExpired"}) {
        EXPECT_EQ(ja["ambience"][key], jb["ambience"][key]) << key;
    }
    // The run did something to compare: anchors were stored.
    EXPECT_GT(ja["ambience"]["anchorsMax"].get<int>(), 5);

    // Every frame's anchors and bytes (and where they sit), from report.csv.
    const std::vector<std::string> columns = {"frame",         "time_s",         "anchors",
                                              "anchorBytes",   "facesCaptured",  "finestLevel",
                                              "ambientLookups", "anchorsLevel0", "anchorsLevel1"};
    const auto ra = csvColumns(dir / "a" / "report.csv", columns);
    const auto rb = csvColumns(dir / "b" / "report.csv", columns);
    ASSERT_EQ(ra.size(), 120u);
    ASSERT_EQ(ra.size(), rb.size());
    for (std::size_t i = 0; i < ra.size(); ++i) EXPECT_EQ(ra[i], rb[i]) << "frame " << i;
}

}  // namespace
}  // namespace amb
