// Conventions_test.cpp — the shared constants of world/Conventions.h, and their GLSL twin
// shaders/conventions.glsl read as text: each number parsed out of the file equals the C++ value.
#include "world/Conventions.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/vec3.hpp>

namespace amb {
namespace {

const std::string kShaderDir = std::string(AMBIENCE_SOURCE_DIR) + "/shaders";

std::string readFile(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// The numbers of `const <type> NAME = <initialiser>;` in GLSL source (a scalar or a vecN(...)).
std::vector<double> glslConstant(const std::string& source, const std::string& name) {
    const std::regex decl("const\\s+\\w+\\s+" + name + "\\s*=\\s*([^;]*);");
    std::smatch m;
    if (!std::regex_search(source, m, decl)) return {};
    std::string init = m[1].str();
    init = std::regex_replace(init, std::regex("^\\s*\\w+\\s*\\("), "");  // vec3( ... )
    const std::regex number("[-+]?(\\d+\\.?\\d*|\\.\\d+)([eE][-+]?\\d+)?");
    std::vector<double> values;
    for (auto it = std::sregex_iterator(init.begin(), init.end(), number);
         it != std::sregex_iterator(); ++it) {
        values.push_back(std::stod(it->str()));
    }
    return values;
}

TEST(Conventions, LuminanceIsRec709) {
    EXPECT_DOUBLE_EQ(kLuminanceWeights[0] + kLuminanceWeights[1] + kLuminanceWeights[2], 1.0);
    EXPECT_DOUBLE_EQ(luminance(glm::dvec3(1.0)), 1.0);
    EXPECT_EQ(luminance(glm::dvec3(1.0, 0.0, 0.0)), 0.2126);
    EXPECT_EQ(luminance(glm::dvec3(0.0, 1.0, 0.0)), 0.7152);
    EXPECT_EQ(luminance(glm::dvec3(0.0, 0.0, 1.0)), 0.0722);
    // In float the weights are the float literals (no double rounding on the way).
    EXPECT_EQ(luminance(glm::vec3(1.0f, 0.0f, 0.0f)), 0.2126f);
    EXPECT_EQ(luminance(glm::vec3(0.0f, 1.0f, 0.0f)), 0.7152f);
    EXPECT_EQ(luminance(glm::vec3(0.0f, 0.0f, 1.0f)), 0.0722f);
}

TEST(Conventions, Constants) {
    EXPECT_DOUBLE_EQ(kPi, 4.0 * std::atan(1.0));
    EXPECT_EQ(kGroundAlbedo, 0.2f);
    EXPECT_EQ(kSunThreshold_Wpsrm2, 5000.0);
}

TEST(Conventions, GlslTwinMatches) {
    const std::string glsl = readFile(kShaderDir + "/conventions.glsl");
    ASSERT_FALSE(glsl.empty()) << "cannot read " << kShaderDir << "/conventions.glsl";

    const std::vector<double> pi = glslConstant(glsl, "PI");
    ASSERT_EQ(pi.size(), 1u);
    EXPECT_EQ(pi[0], kPi);  // written to full double precision

    const std::vector<double> w = glslConstant(glsl, "LUMINANCE_WEIGHTS");
    ASSERT_EQ(w.size(), 3u);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(w[c], kLuminanceWeights[c]) << "channel " << c;

    const std::vector<double> albedo = glslConstant(glsl, "GROUND_ALBEDO");
    ASSERT_EQ(albedo.size(), 1u);
    EXPECT_EQ(float(albedo[0]), kGroundAlbedo);

    // The GLSL luminance() uses the weights (no second copy of the numbers).
    EXPECT_TRUE(std::regex_search(glsl, std::regex("dot\\(\\s*LUMINANCE_WEIGHTS\\s*,")));
}

// The twin is the shaders' only home of these numbers: no other shader source spells pi or the
// luminance weights out.
TEST(Conventions, NoOtherShaderDefinesThem) {
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(kShaderDir)) {
        const std::string ext = entry.path().extension().string();
        if (ext != ".glsl" && ext != ".vert" && ext != ".frag" && ext != ".comp") continue;
        ++files;
        if (entry.path().filename() == "conventions.glsl") continue;
        const std::string src = readFile(entry.path().string());
        EXPECT_EQ(src.find("3.14159"), std::string::npos) << entry.path().filename();
        EXPECT_EQ(src.find("0.7152"), std::string::npos) << entry.path().filename();
        EXPECT_FALSE(std::regex_search(src, std::regex("const\\s+float\\s+PI\\b")))
            << entry.path().filename();
    }
    EXPECT_GT(files, 1);
}

}  // namespace
}  // namespace amb
