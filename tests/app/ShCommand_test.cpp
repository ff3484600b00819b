// ShCommand_test.cpp — `ambience sh project` end to end: a cube map written with writeCubeMap,
// the executable run on it, its JSON checked against closed forms; bad input exits with code 2.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "lighting/CubeMapFile.h"
#include "world/Conventions.h"

namespace amb {
namespace {

struct RunResult {
    int exitCode;
    std::string out;
};

// Runs the executable with `args` (no shell: RunAmbience.h); stdout is returned, stderr is
// written to `errPath`.
RunResult run(const std::string& args, const std::string& errPath) {
    const test::CommandResult r = test::runAmbience(args);
    std::ofstream(errPath) << r.err;
    return {r.exitCode, r.out};
}

std::string readFile(const std::string& path) {
    std::string s;
    if (FILE* f = std::fopen(path.c_str(), "r")) {
        char buf[4096];
        std::size_t got;
        while ((got = fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, got);
        std::fclose(f);
    }
    return s;
}

class ShCommand : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ =
            std::filesystem::temp_directory_path() / ("ambience_sh_" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir_);
        // Sky S = 1 (red 2) above the horizon, ground G = 0.1 below, N = 16.
        const int n = 16;
        std::vector<float> rgb(std::size_t(6) * n * n * 3);
        for (int f = 0; f < 6; ++f)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const bool sky = cubeTexelDirection(f, i, j, n).y > 0.0;
                    float* p = &rgb[3 * ((std::size_t(f) * n + j) * n + i)];
                    p[0] = sky ? 2.0f : 0.1f;
                    p[1] = p[2] = sky ? 1.0f : 0.1f;
                }
        cube_ = (dir_ / "sky.exr").string();
        writeCubeMap(cube_, n, rgb);
        err_ = (dir_ / "stderr.txt").string();
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    std::filesystem::path dir_;
    std::string cube_, err_;
};

// Coefficients and irradiance against the sky/ground closed forms: L00 = sqrt(pi) (S + G) to
// 1e-5, E(n) = pi (S (1 + n_y) + G (1 - n_y)) / 2 to 1 % (16 x 16 texels); normals are
// normalised by the command ("0,5,0" is up).
TEST_F(ShCommand, ProjectPrintsCoefficientsAndIrradiance) {
    const RunResult r =
        run("sh project --cube " + cube_ + " --normals \"0,5,0;0,-1,0;1,0,0\"", err_);
    ASSERT_EQ(r.exitCode, 0) << readFile(err_);
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("n").get<int>(), 16);
    ASSERT_EQ(j.at("coefficients").size(), 9u);
    EXPECT_NEAR(j["coefficients"][0][1].get<double>(), std::sqrt(kPi) * 1.1, 1e-5);
    EXPECT_NEAR(j["coefficients"][0][0].get<double>(), std::sqrt(kPi) * 2.1, 1e-5);
    ASSERT_EQ(j.at("irradiance").size(), 3u);
    const double ny[3] = {1.0, -1.0, 0.0};
    for (int i = 0; i < 3; ++i) {
        const double exact = kPi * ((1 + ny[i]) + 0.1 * (1 - ny[i])) / 2.0;
        EXPECT_NEAR(j["irradiance"][i][1].get<double>(), exact, 0.01 * exact) << i;
    }
}

// The reference irradiance comes straight from the texels: for this sky/ground split (on texel
// edges, N even) it is the closed form to float precision, and as that field has nothing above band 1, the
// order-2 truncation error is only the projection's texel error (under 0.2 %).
TEST_F(ShCommand, ReferenceIrradianceAndTruncationError) {
    const RunResult r =
        run("sh project --cube " + cube_ + " --normals \"0,1,0;0,-1,0;1,0,0;0.6,0.8,0\"", err_);
    ASSERT_EQ(r.exitCode, 0) << readFile(err_);
    const auto j = nlohmann::json::parse(r.out);
    const auto& ref = j.at("reference");
    ASSERT_EQ(ref.at("irradiance").size(), 4u);
    const double ny[4] = {1.0, -1.0, 0.0, 0.8};
    for (int i = 0; i < 4; ++i) {
        const double exactG = kPi * ((1 + ny[i]) + 0.1 * (1 - ny[i])) / 2.0;
        const double exactR = kPi * (2.0 * (1 + ny[i]) + 0.1 * (1 - ny[i])) / 2.0;
        // 1e-7 relative: the file stores the radiance as float (0.1 is 0.100000001...).
        EXPECT_NEAR(ref["irradiance"][i][1].get<double>(), exactG, 1e-7 * exactG) << i;
        EXPECT_NEAR(ref["irradiance"][i][0].get<double>(), exactR, 1e-7 * exactR) << i;
    }
    const double truncation = ref.at("truncationError").get<double>();
    EXPECT_GE(truncation, 0.0);
    EXPECT_LT(truncation, 0.002);
    // A sharp light (only the +Y face lit) has irradiance in band 4 and above, which order 2
    // drops: a small error (irradiance is smooth), but clearly there.
    const int n = 8;
    std::vector<float> rgb(std::size_t(6) * n * n * 3, 0.0f);
    for (std::size_t t = std::size_t(2) * n * n; t < std::size_t(3) * n * n; ++t)
        rgb[3 * t] = rgb[3 * t + 1] = rgb[3 * t + 2] = 1.0f;
    const std::string top = (dir_ / "top.exr").string();
    writeCubeMap(top, n, rgb);
    const RunResult s = run("sh project --cube " + top + " --normals 0,1,0", err_);
    ASSERT_EQ(s.exitCode, 0) << readFile(err_);
    const auto k = nlohmann::json::parse(s.out);
    // The form factor of the top face: E(up) = 2 sqrt(2) atan(1 / sqrt 2).
    EXPECT_NEAR(k["reference"]["irradiance"][0][1].get<double>(),
                2.0 * std::sqrt(2.0) * std::atan(1.0 / std::sqrt(2.0)), 1e-6);
    const double sharp = k["reference"]["truncationError"].get<double>();
    EXPECT_GT(sharp, 0.002);
    EXPECT_LT(sharp, 0.05);
    std::printf("truncation error: sky/ground %.6f, one face %.6f\n", truncation, sharp);
}

// A window changes the irradiance but not the printed (raw) coefficients; hanning:2 halves the
// band-1 part: E(up) = pi (S + G) / 2 + (pi (S - G) / 2) / 2.
TEST_F(ShCommand, WindowAppliesToIrradianceOnly) {
    const RunResult none = run("sh project --cube " + cube_ + " --normals 0,1,0", err_);
    const RunResult hann =
        run("sh project --cube " + cube_ + " --window hanning:2 --normals 0,1,0", err_);
    const RunResult autoW =
        run("sh project --cube " + cube_ + " --window auto --normals 0,1,0", err_);
    ASSERT_EQ(none.exitCode, 0);
    ASSERT_EQ(hann.exitCode, 0);
    ASSERT_EQ(autoW.exitCode, 0);
    const auto a = nlohmann::json::parse(none.out), b = nlohmann::json::parse(hann.out),
               c = nlohmann::json::parse(autoW.out);
    EXPECT_EQ(a["coefficients"], b["coefficients"]);
    const double expected = kPi * 1.1 / 2.0 + kPi * 0.9 / 4.0;
    EXPECT_NEAR(b["irradiance"][0][1].get<double>(), expected, 0.01 * expected);
    // This sky never rings, so auto is no window.
    EXPECT_EQ(a["irradiance"], c["irradiance"]);
}

// Bad input: exit code 2 and one line naming the input.
TEST_F(ShCommand, BadInputExitsWithCodeTwo) {
    const std::string missing = (dir_ / "missing.exr").string();
    RunResult r = run("sh project --cube " + missing, err_);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(readFile(err_).find(missing), std::string::npos);
    r = run("sh project --cube " + cube_ + " --window gauss:3", err_);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(readFile(err_).find("--window"), std::string::npos);
    r = run("sh project --cube " + cube_ + " --normals \"0,1,0;1,x,0\"", err_);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(readFile(err_).find("--normals item 2"), std::string::npos);
    r = run("sh project --cube " + cube_ + " --normals 0,0,0", err_);
    EXPECT_EQ(r.exitCode, 2);
}

}  // namespace
}  // namespace amb
