// TextFile_test.cpp — the bounded readers and the link-replacing writer (world/TextFile.h), and
// the JSON text checks every reader of user files goes through (world/JsonText.h).
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>

#include <gtest/gtest.h>

#include "world/Error.h"
#include "world/JsonText.h"
#include "world/TextFile.h"

namespace amb {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() /
                         ("ambience-textfile-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string refusal(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "accepted";
}

std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(TextFile, RefusesWhatIsNotARegularFileWithoutBlocking) {
    const fs::path dir = scratch("kinds");
    ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0644), 0);
    const auto t0 = std::chrono::steady_clock::now();
    // No writer ever opens the FIFO: a blocking open would never return.
    EXPECT_NE(refusal([&] {
                  readTextFile((dir / "fifo").string(), "f", 100);
              }).find("not a regular file"),
              std::string::npos);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
    EXPECT_NE(refusal([&] { readTextFile("/dev/zero", "f", 100); }).find("not a regular file"),
              std::string::npos);
    EXPECT_NE(refusal([&] { readTextFile(dir.string(), "f", 100); }).find("not a regular file"),
              std::string::npos);
    EXPECT_NE(refusal([&] { readTextFile((dir / "none").string(), "f", 100); }).find("cannot open"),
              std::string::npos);
    std::ofstream(dir / "big") << std::string(101, 'x');
    EXPECT_NE(refusal([&] { readTextFile((dir / "big").string(), "f", 100); }).find("too large"),
              std::string::npos);
    EXPECT_EQ(readTextFile((dir / "big").string(), "f", 101), std::string(101, 'x'));
}

TEST(TextFile, LinksAreFollowedOnlyWhenAllowed) {
    const fs::path dir = scratch("links");
    std::ofstream(dir / "target") << "outside";
    fs::create_symlink(dir / "target", dir / "link");
    EXPECT_EQ(readTextFile((dir / "link").string(), "f", 100), "outside");
    EXPECT_NE(refusal([&] {
                  readTextFile((dir / "link").string(), "f", 100, Links::Refuse);
              }).find("symbolic link"),
              std::string::npos);
    EXPECT_NE(refusal([&] {
                  readTextFileTail((dir / "link").string(), "f", 4, Links::Refuse);
              }).find("symbolic link"),
              std::string::npos);
}

TEST(TextFile, TailReadsTheEndOnly) {
    const fs::path dir = scratch("tail");
    std::ofstream(dir / "log") << "first line\nsecond\nlast line\n";
    EXPECT_EQ(readTextFileTail((dir / "log").string(), "log", 10), "last line\n");
    EXPECT_EQ(readTextFileTail((dir / "log").string(), "log", 1000),
              "first line\nsecond\nlast line\n");
}

TEST(TextFile, WriteReplacesALinkInsteadOfWritingThroughIt) {
    const fs::path dir = scratch("write");
    std::ofstream(dir / "victim") << "precious";
    fs::create_symlink(dir / "victim", dir / "out.csv");
    writeTextFile((dir / "out.csv").string(), "results\n", "results");
    EXPECT_EQ(slurp(dir / "victim"), "precious");
    EXPECT_FALSE(fs::is_symlink(dir / "out.csv"));
    EXPECT_EQ(slurp(dir / "out.csv"), "results\n");
    writeTextFile((dir / "script.sh").string(), "#!/bin/sh\n", "script", 0755);
    EXPECT_NE(fs::status(dir / "script.sh").permissions() & fs::perms::owner_exec, fs::perms::none);
    fs::create_directory(dir / "folder");
    EXPECT_NE(refusal([&] {
                  writeTextFile((dir / "folder").string(), "x", "results");
              }).find("cannot replace the results"),
              std::string::npos);
    EXPECT_NE(refusal([&] {
                  writeTextFile((dir / "no" / "such").string(), "x", "results");
              }).find("cannot write the results"),
              std::string::npos);
    // Nothing is left beside the files.
    int entries = 0;
    for (const auto& e : fs::directory_iterator(dir)) entries += !e.path().empty();
    EXPECT_EQ(entries, 4);  // victim, out.csv, script.sh, folder
}

TEST(JsonText, NulBytesAndDeepNestingAreRefused) {
    EXPECT_EQ(parseJsonText(R"({"a": [1, {"b": 2}]})", "f").at("a").at(1).at("b"), 2);
    // nlohmann's parser stops at a NUL as at the end of its input: "{}" would pass.
    EXPECT_NE(refusal([] {
                  parseJsonText(std::string("{}\0junk", 7), "f.json");
              }).find("f.json: a NUL byte at offset 2"),
              std::string::npos);
    const auto nested = [](int levels) {
        return std::string(std::size_t(levels), '[') + "1" + std::string(std::size_t(levels), ']');
    };
    EXPECT_EQ(refusal([&] { parseJsonText(nested(kMaxJsonDepth), "f"); }), "accepted");
    EXPECT_NE(refusal([&] {
                  parseJsonText(nested(kMaxJsonDepth + 1), "f");
              }).find("nested deeper than 64"),
              std::string::npos);
    EXPECT_THROW(parseJsonText("{", "f"), nlohmann::json::exception);  // worded by each reader
}

}  // namespace
}  // namespace amb
