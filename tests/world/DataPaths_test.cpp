// DataPaths_test.cpp — the data-folder lookup over the two layouts it serves: an installed
// prefix (P/bin, P/share/ambience) and a build tree (build/bin, build/shaders, the source's
// replays two levels up), built here as scratch folders.
#include "world/DataPaths.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

namespace amb {
namespace {

namespace fs = std::filesystem;

// A fresh scratch folder for one test, removed at the end.
class DataPathsTest : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() /
                ("ambience-datapaths-" + std::to_string(getpid()) + "-" +
                 ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(root_);
        fs::create_directories(root_);
    }
    void TearDown() override { fs::remove_all(root_); }

    // Creates the file `relative` under the scratch root (and its folders).
    fs::path touch(const std::string& relative) {
        const fs::path p = root_ / relative;
        fs::create_directories(p.parent_path());
        std::ofstream(p) << "x\n";
        return p;
    }

    fs::path root_;
};

// The installed data folder of a prefix under the scratch root, as CMake configured it
// (prefix/share/ambience by default).
std::string installedData(const std::string& prefix) {
    return prefix + "/bin/" + installedDataFromBin();
}

TEST(DataPaths, DefaultInstallLayoutIsShareAmbience) {
    // GNUInstallDirs' defaults (bin, share) unless the build was configured otherwise.
    if (std::string(AMBIENCE_INSTALL_BINDIR) != "bin" ||
        std::string(AMBIENCE_INSTALL_DATADIR) != "share")
        GTEST_SKIP() << "configured with other install folders";
    EXPECT_EQ(installedDataFromBin(), "../share/ambience");
}

TEST_F(DataPathsTest, InstalledPrefixFindsItsDataFolder) {
    touch("prefix/bin/ambience");
    const std::string data = installedData("prefix");
    const fs::path shader = touch(data + "/shaders/terrain.frag");
    const fs::path replay = touch(data + "/replays/highway-drive.json");
    const fs::path plots = touch(data + "/bench-plots.py");
    const std::string exe = (root_ / "prefix/bin").string();

    const auto normal = [](const fs::path& p) { return p.lexically_normal().string(); };
    EXPECT_EQ(findDataFileFrom(exe, "shaders"), normal(shader.parent_path()));
    EXPECT_EQ(findDataFileFrom(exe, "shaders/terrain.frag"), normal(shader));
    EXPECT_EQ(findDataFileFrom(exe, "replays/highway-drive.json"), normal(replay));
    EXPECT_EQ(findDataFileFrom(exe, "bench-plots.py"), normal(plots));
}

TEST_F(DataPathsTest, BuildTreeInsideSourceTreeFindsEachInItsPlace) {
    // source/build/bin/ambience, source/build/bin/bench-plots.py, source/build/shaders,
    // source/replays (the source's own shaders/ must lose to the validated copy in build/).
    touch("source/build/bin/ambience");
    const fs::path plots = touch("source/build/bin/bench-plots.py");
    const fs::path built = touch("source/build/shaders/terrain.frag");
    touch("source/shaders/terrain.frag");
    const fs::path replay = touch("source/replays/highway-drive.json");
    const std::string exe = (root_ / "source/build/bin").string();

    EXPECT_EQ(findDataFileFrom(exe, "bench-plots.py"), plots.string());
    EXPECT_EQ(findDataFileFrom(exe, "shaders"), built.parent_path().string());
    EXPECT_EQ(findDataFileFrom(exe, "replays/highway-drive.json"), replay.string());
}

TEST_F(DataPathsTest, InstalledDataWinsOverABuildTreeLayoutAroundIt) {
    // A prefix that also has a shaders/ beside bin/ (as a build tree would): the installed
    // folder is searched first.
    const fs::path installed = touch(installedData("p") + "/shaders/sky.frag");
    touch("p/shaders/sky.frag");
    EXPECT_EQ(findDataFileFrom((root_ / "p/bin").string(), "shaders"),
              installed.parent_path().lexically_normal().string());
}

TEST_F(DataPathsTest, MissingDataIsEmptyNotAGuess) {
    touch("prefix/bin/ambience");
    EXPECT_EQ(findDataFileFrom((root_ / "prefix/bin").string(), "shaders"), "");
    EXPECT_EQ(findDataFileFrom("", "shaders"), "");
    EXPECT_TRUE(dataFolders("").empty());
}

TEST(DataPaths, FoldersAreNormalisedAndInOrder) {
    const auto folders = dataFolders("/opt/amb/bin");
    ASSERT_EQ(folders.size(), 4u);
    EXPECT_EQ(folders[0],
              (fs::path("/opt/amb/bin") / installedDataFromBin()).lexically_normal().string());
    EXPECT_EQ(folders[0].find(".."), std::string::npos);
    EXPECT_NE(folders[0].back(), '/');
    EXPECT_EQ(folders[1], "/opt/amb/bin");
    EXPECT_EQ(folders[2], "/opt/amb");
    EXPECT_EQ(folders[3], "/opt");
}

TEST(DataPaths, ExecutableDirectoryIsTheBuildsBinFolder) {
    // CMake puts every executable, this test binary included, in <build>/bin.
    const std::string dir = executableDirectory();
    ASSERT_FALSE(dir.empty());
    EXPECT_TRUE(fs::path(dir).is_absolute());
    EXPECT_TRUE(fs::equivalent(dir, fs::path(AMBIENCE_BINARY_DIR) / "bin"));
}

TEST(DataPaths, ThisBuildTreeFindsItsShadersAndPlotScript) {
    // The real build tree: the validated shaders in <build>/shaders, the plot script in
    // <build>/bin (app/CMakeLists.txt, shaders/CMakeLists.txt).
    const fs::path build(AMBIENCE_BINARY_DIR);
    if (!fs::exists(build / "shaders/conventions.glsl")) GTEST_SKIP() << "no shaders built";
    EXPECT_TRUE(fs::equivalent(findDataFile("shaders/conventions.glsl"),
                               build / "shaders/conventions.glsl"));
    if (fs::exists(build / "bin/bench-plots.py"))
        EXPECT_TRUE(fs::equivalent(findDataFile("bench-plots.py"), build / "bin/bench-plots.py"));
}

}  // namespace
}  // namespace amb
