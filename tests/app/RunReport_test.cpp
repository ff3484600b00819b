// RunReport_test.cpp — the progress of long commands (ProgressBar): a bar redrawn in place on a
// terminal, plain lines at the set interval elsewhere, lines a log reader can tell apart, the
// interval setting, and `ambience run` with stderr in a file.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "RunAmbience.h"
#include "app/cli/RunReport.h"
#include "world/Error.h"

namespace amb {
namespace {

// Everything written to `f` so far.
std::string contents(std::FILE* f) {
    std::fflush(f);
    std::rewind(f);
    std::string s;
    char buffer[4096];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof(buffer), f)) > 0;) s.append(buffer, n);
    return s;
}

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::size_t start = 0;
    for (std::size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1)
        out.push_back(text.substr(start, end - start));
    if (start < text.size()) out.push_back(text.substr(start));
    return out;
}

// The count before "/<total>" in a progress line ("run: frame 12/60 (20 %) ...").
int doneOf(const std::string& line, const std::string& unit) {
    const std::size_t at = line.find(unit + " ");
    return at == std::string::npos ? -1 : std::atoi(line.c_str() + at + unit.size() + 1);
}

// Off a terminal: no bar and no carriage return, a line when an interval has passed since the
// last (so at most elapsed / interval of them while updating), and one at the end.
TEST(ProgressBar, OffATerminalALineEveryIntervalAndOneAtTheEnd) {
    std::FILE* f = std::tmpfile();
    ASSERT_NE(f, nullptr);
    const double interval_s = 0.1;
    ProgressBar bar(40, "test", "frame", f, false, interval_s);
    const auto start = std::chrono::steady_clock::now();
    for (int i = 1; i <= 40; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        bar.update(i, 5.0);
    }
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto updating = lines(contents(f));
    const int whileUpdating = int(updating.size());
    // The end is drawn by finish() unless the last update already drew it.
    const bool endShown = !updating.empty() && doneOf(updating.back(), "frame") == 40;
    bar.finish();
    const std::string text = contents(f);
    std::fclose(f);
    EXPECT_EQ(text.find('\r'), std::string::npos);
    EXPECT_EQ(text.find('['), std::string::npos);
    EXPECT_GE(whileUpdating, 1);  // elapsed_s >= 0.4 s, four intervals
    EXPECT_LE(whileUpdating, int(elapsed_s / interval_s)) << text;
    const auto all = lines(text);
    ASSERT_EQ(int(all.size()), whileUpdating + (endShown ? 0 : 1)) << text;
    int previous = 0;
    for (const std::string& line : all) {
        EXPECT_TRUE(isProgressLine(line)) << line;
        EXPECT_EQ(line.rfind("test: frame ", 0), 0u) << line;
        const int done = doneOf(line, "frame");
        EXPECT_GT(done, previous) << text;
        previous = done;
    }
    EXPECT_EQ(all.back().rfind("test: frame 40/40 (100 %), ", 0), 0u) << all.back();
    EXPECT_NE(all.back().find("fps"), std::string::npos);
    EXPECT_NE(all.back().find("0:00 left"), std::string::npos);
}

// A long interval: nothing while updating, the one line at the end.
TEST(ProgressBar, OffATerminalALongIntervalLeavesTheLastLineOnly) {
    std::FILE* f = std::tmpfile();
    ASSERT_NE(f, nullptr);
    ProgressBar bar(3, "bench", "run", f, false, 3600.0);
    for (int i = 1; i <= 3; ++i) bar.update(i, "last x");
    EXPECT_EQ(contents(f), "");
    bar.finish();
    bar.finish();  // once only
    const auto all = lines(contents(f));
    std::fclose(f);
    ASSERT_EQ(all.size(), 1u);
    EXPECT_EQ(all[0].rfind("bench: run 3/3 (100 %), ", 0), 0u) << all[0];
    EXPECT_NE(all[0].find(", last x"), std::string::npos) << all[0];
}

// On a terminal: one line redrawn after a carriage return, ended by finish(); a note clears
// the bar, takes a line of its own and the bar comes back below it.
TEST(ProgressBar, OnATerminalABarRedrawnInPlace) {
    std::FILE* f = std::tmpfile();
    ASSERT_NE(f, nullptr);
    ProgressBar bar(10, "run", "frame", f, true, 3600.0);
    bar.update(5, 1.0);  // the first draw waits a tenth of a second; the last is always drawn
    std::this_thread::sleep_for(std::chrono::milliseconds(120));
    bar.update(5, 1.0);
    bar.note("run failed: x");
    bar.update(10, 1.0);
    bar.finish();
    const std::string text = contents(f);
    std::fclose(f);
    EXPECT_EQ(text.rfind("\r\033[K[###############...............] frame 5/10 (50 %)", 0), 0u)
        << text;
    EXPECT_NE(text.find("\r\033[Krun failed: x\n\r\033[K[####"), std::string::npos) << text;
    EXPECT_NE(text.find("[##############################] frame 10/10 (100 %)"), std::string::npos)
        << text;
    EXPECT_EQ(text.back(), '\n');
    EXPECT_EQ(test::lineCount(text), 2);  // the note's and the bar's end
}

TEST(ProgressBar, ProgressLinesAreToldApartFromOtherLines) {
    EXPECT_TRUE(isProgressLine("run: frame 1200/2701 (44 %), 31.0 fps, 0:38 elapsed, 0:49 left"));
    EXPECT_TRUE(isProgressLine("tune t3: run 2/4 (50 %), 12 s/run, 0:24 elapsed, 0:24 left"));
    EXPECT_FALSE(isProgressLine("run: highway-drive, 60 frames at 640x360 on egl (llvmpipe)"));
    EXPECT_FALSE(isProgressLine("ambience: error: volume.json: unknown key 'x'"));
    EXPECT_FALSE(isProgressLine("bench: 3 runs on 2 job(s)"));
    EXPECT_FALSE(isProgressLine("frame 3/4 (75 %)"));
    EXPECT_FALSE(isProgressLine(""));
}

TEST(ProgressBar, IntervalFromTheEnvironment) {
    unsetenv("AMBIENCE_PROGRESS_S");
    EXPECT_EQ(progressInterval_s(), 5.0);
    setenv("AMBIENCE_PROGRESS_S", "0.25", 1);
    EXPECT_EQ(progressInterval_s(), 0.25);
    for (const char* bad : {"0", "-1", "x", "1s", "nan", "1e9"}) {
        setenv("AMBIENCE_PROGRESS_S", bad, 1);
        EXPECT_THROW(progressInterval_s(), InputError) << bad;
    }
    unsetenv("AMBIENCE_PROGRESS_S");
}

// `ambience run` with stderr in a file (not a terminal): progress lines at the interval set,
// the frame count rising to the total; with a long interval the last line alone.
TEST(ProgressBar, RunWithStderrInAFileWritesProgressLines) {
    const auto dir = test::scratchDir("run-progress");
    auto progressLines = [&](const char* interval) {
        setenv("AMBIENCE_PROGRESS_S", interval, 1);
        const auto r = test::runAmbience(
            "run --no-frames --ambient constant --max-frames 60 --measure-every 10 --out " +
            (dir / interval).string());
        unsetenv("AMBIENCE_PROGRESS_S");
        EXPECT_EQ(r.exitCode, 0) << r.err;
        std::vector<std::string> out;
        for (const std::string& line : lines(r.err))
            if (isProgressLine(line)) out.push_back(line);
        EXPECT_EQ(r.err.find('\r'), std::string::npos);
        return out;
    };
    const auto often = progressLines("0.05");
    ASSERT_GE(often.size(), 3u);  // 60 frames measured on every 10th take a second or more
    int previous = 0;
    for (const std::string& line : often) {
        EXPECT_EQ(line.rfind("run: frame ", 0), 0u) << line;
        const int done = doneOf(line, "frame");
        EXPECT_GT(done, previous) << line;
        previous = done;
    }
    EXPECT_EQ(often.back().rfind("run: frame 60/60 (100 %)", 0), 0u) << often.back();
    const auto rarely = progressLines("3600");
    ASSERT_EQ(rarely.size(), 1u);
    EXPECT_EQ(rarely[0].rfind("run: frame 60/60 (100 %)", 0), 0u) << rarely[0];
    setenv("AMBIENCE_PROGRESS_S", "soon", 1);
    const auto bad =
        test::runAmbience("run --no-frames --max-frames 2 --out " + (dir / "bad").string());
    unsetenv("AMBIENCE_PROGRESS_S");
    EXPECT_EQ(bad.exitCode, 2);
    EXPECT_NE(bad.err.find("AMBIENCE_PROGRESS_S"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace amb
