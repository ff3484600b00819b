// ShCommand.cpp — `ambience sh project --cube FILE [--window W] [--normals "x,y,z;..."]`.
//
// Reads a vertical-strip cube map (lighting/CubeMapFile.h), projects it to order-2 SH with exact
// texel solid angles and prints JSON:
//   {"n": N, "coefficients": [[r,g,b] x 9], "irradiance": [[r,g,b] per normal]}
// "coefficients" are the raw projection (before any window); "irradiance" is evaluated from the
// windowed coefficients at the given normals (normalised here) and is not clamped.
// "reference" holds the irradiance taken straight from the texels at the same normals (no SH;
// lighting/ReferenceIrradiance.h) and "truncationError", the relative distance over the sphere
// of normals between the (windowed) order-2 SH irradiance and that reference. Windows:
// none (default), hanning:W, lanczos:W, auto (lighting/SH.h). Bad texels (NaN, Inf, negative)
// count as black, with a note on stderr.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "app/cli/Commands.h"
#include "lighting/CubeMapFile.h"
#include "lighting/CubeMapProjector.h"
#include "lighting/ReferenceIrradiance.h"
#include "lighting/SH.h"
#include "world/Error.h"

namespace amb {

namespace {

struct ProjectOptions {
    std::string cube;
    std::string window = "none";
    std::string normals;
};

// A whole-string number; throws InputError naming `where` otherwise.
double parseNumber(const std::string& text, const std::string& where) {
    std::size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size() || !std::isfinite(value)) {
        throw InputError(where, "'" + text + "' is not a finite number");
    }
    return value;
}

std::vector<std::string> split(const std::string& text, char sep) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (;;) {
        const std::size_t end = text.find(sep, start);
        parts.push_back(text.substr(start, end - start));
        if (end == std::string::npos) return parts;
        start = end + 1;
    }
}

std::string trim(const std::string& s) {
    const auto a = s.find_first_not_of(" \t");
    if (a == std::string::npos) return "";
    return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

// "none" | "auto" | "hanning:W" | "lanczos:W" with W > 0. `autoWindow` is set for "auto".
ShWindow parseWindow(const std::string& text, bool& autoWindow) {
    autoWindow = false;
    if (text == "none") return ShWindow::none();
    if (text == "auto") {
        autoWindow = true;
        return ShWindow::none();
    }
    const auto colon = text.find(':');
    const std::string kind = text.substr(0, colon);
    if (colon == std::string::npos || (kind != "hanning" && kind != "lanczos")) {
        throw InputError("--window",
                         "'" + text + "' is not one of none, hanning:W, lanczos:W, auto");
    }
    const double width = parseNumber(text.substr(colon + 1), "--window " + kind + " width");
    if (width <= 0.0) throw InputError("--window", "the width W must be > 0, got " + text);
    return kind == "hanning" ? ShWindow::hanning(width) : ShWindow::lanczos(width);
}

// "x,y,z;x,y,z;..." -> unit normals (empty text -> none; an empty trailing item is allowed).
std::vector<glm::dvec3> parseNormals(const std::string& text) {
    std::vector<glm::dvec3> normals;
    if (trim(text).empty()) return normals;
    const auto items = split(text, ';');
    for (std::size_t i = 0; i < items.size(); ++i) {
        if (trim(items[i]).empty() && i + 1 == items.size() && i > 0) break;
        const std::string where = "--normals item " + std::to_string(i + 1);
        const auto parts = split(items[i], ',');
        if (parts.size() != 3) {
            throw InputError(where, "'" + items[i] + "' is not three numbers x,y,z");
        }
        glm::dvec3 n;
        for (int c = 0; c < 3; ++c) n[c] = parseNumber(trim(parts[c]), where);
        const double len = glm::length(n);
        if (!(len > 1e-12) || !std::isfinite(len)) {
            throw InputError(where, "'" + items[i] + "' has no direction (zero length)");
        }
        normals.push_back(n / len);
    }
    return normals;
}

nlohmann::ordered_json rgbArray(const glm::dvec3& v) {
    return {v.x, v.y, v.z};
}

void runProject(const ProjectOptions& o) {
    bool autoWindow = false;
    ShWindow window = parseWindow(o.window, autoWindow);
    const std::vector<glm::dvec3> normals = parseNormals(o.normals);
    const CubeMapImage image = readCubeMap(o.cube);

    const CubeMapProjection projection = projectCubeMap(image.n, image.rgb);
    if (projection.badTexels > 0) {
        std::fprintf(stderr,
                     "ambience: note: %s: %lld texel(s) with NaN, Inf or negative radiance "
                     "counted as black\n",
                     o.cube.c_str(), static_cast<long long>(projection.badTexels));
    }
    if (autoWindow) window = shAutoWindow(projection.sh);
    const ShRgbD windowed = shApplyWindow(projection.sh, window);

    nlohmann::ordered_json out;
    out["n"] = image.n;
    out["coefficients"] = nlohmann::ordered_json::array();
    for (const glm::dvec3& c : projection.sh.c) out["coefficients"].push_back(rgbArray(c));
    out["irradiance"] = nlohmann::ordered_json::array();
    for (const glm::dvec3& n : normals) {
        out["irradiance"].push_back(rgbArray(shIrradiance(windowed, n)));
    }
    // The reference: irradiance straight from the texels (no SH), and the error the order-2
    // truncation (and the window) makes against it over the sphere of normals.
    std::vector<float> clean = image.rgb;
    for (float& v : clean)
        if (!std::isfinite(v) || v < 0.0f) v = 0.0f;
    const CubeIrradiance direct(image.n, clean);
    const IrradianceField directField = [&direct](const glm::dvec3& n) { return direct.at(n); };
    const IrradianceField shFieldD = [&windowed](const glm::dvec3& n) {
        return shIrradiance(windowed, n);
    };
    const SphereRule rule = sphereProductRule();
    const double norm = irradianceNorm(directField, rule);
    nlohmann::ordered_json reference;
    reference["irradiance"] = nlohmann::ordered_json::array();
    for (const glm::dvec3& n : normals) reference["irradiance"].push_back(rgbArray(direct.at(n)));
    reference["quadratureNormals"] = rule.directions.size();
    reference["truncationError"] =
        norm > 0.0 ? irradianceDistance(shFieldD, directField, rule) / norm : 0.0;
    out["reference"] = reference;
    std::printf("%s\n", out.dump(2).c_str());
}

}  // namespace

void addShCommand(CLI::App& app) {
    auto* sh = app.add_subcommand("sh", "Spherical-harmonics tools");
    sh->require_subcommand(1);

    auto options = std::make_shared<ProjectOptions>();
    auto* project = sh->add_subcommand(
        "project", "Project a vertical-strip cube map (N x 6N image) to order-2 SH; print JSON");
    project->add_option("--cube", options->cube, "Cube-map image (EXR for HDR)")->required();
    project
        ->add_option("--window", options->window,
                     "none | hanning:W | lanczos:W | auto (weakest window with E >= 0)")
        ->capture_default_str();
    project->add_option("--normals", options->normals,
                        "Normals for the irradiance output: \"x,y,z;x,y,z;...\" (normalised)");
    project->callback([options] { runProject(*options); });
}

}  // namespace amb
