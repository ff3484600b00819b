// DebugOverlay.cpp — anchor markers drawn on the CPU into the read-back frame.
#include "app/render/DebugOverlay.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "lighting/AmbienceVolume.h"

namespace amb {

namespace {

constexpr std::array<glm::vec3, 7> kLevelColours = {{{1.0f, 0.15f, 0.1f},
                                                      {1.0f, 0.55f, 0.0f},
                                                      {1.0f, 0.95f, 0.1f},
                                                      {0.2f, 0.9f, 0.2f},
                                                      {0.1f, 0.9f, 0.9f},
                                                      {0.2f, 0.4f, 1.0f},
                                                      {0.7f, 0.3f, 1.0f}}};

struct Projected {
    bool visible = false;
    int x = 0, y = 0;
    double distance_m = 0.0;
};

Projected project(const glm::mat4& viewProj, const glm::dvec3& eye_m, const glm::dvec3& p_m,
                  int width, int height) {
    Projected out;
    const glm::dvec3 rel = p_m - eye_m;
    const glm::vec4 clip = viewProj * glm::vec4(glm::vec3(rel), 1.0f);
    if (clip.w <= 1e-3f) return out;  // behind the camera
    const float nx = clip.x / clip.w, ny = clip.y / clip.w;
    if (std::fabs(nx) > 1.05f || std::fabs(ny) > 1.05f) return out;
    out.visible = true;
    out.x = int(std::lround((nx * 0.5f + 0.5f) * width));
    out.y = int(std::lround((0.5f - ny * 0.5f) * height));  // row 0 is the top
    out.distance_m = glm::length(rel);
    return out;
}

void fillBox(std::vector<unsigned char>& rgb, int width, int height, int x0, int y0, int x1, int y1,
             const glm::vec3& colour, bool hollow) {
    for (int y = std::max(0, y0); y <= std::min(height - 1, y1); ++y) {
        for (int x = std::max(0, x0); x <= std::min(width - 1, x1); ++x) {
            if (hollow && x != x0 && x != x1 && y != y0 && y != y1) continue;
            unsigned char* px = &rgb[(std::size_t(y) * width + x) * 3];
            for (int c = 0; c < 3; ++c) px[c] = (unsigned char)std::lround(255.0f * colour[c]);
        }
    }
}

}  // namespace

int drawAnchorOverlay(std::vector<unsigned char>& rgb, int width, int height,
                      const glm::mat4& viewProj, const glm::dvec3& eye_m,
                      const AmbienceVolume& volume) {
    const double now = volume.simulationTime_s();
    int drawn = 0;
    volume.store().forEach([&](const Anchor& a) {
        const Projected p = project(viewProj, eye_m, a.capturedPosition_m, width, height);
        if (!p.visible) return;
        const double ageFraction =
            a.lifetime_s > 0.0 ? std::clamp(a.age_s(now) / a.lifetime_s, 0.0, 1.0) : 1.0;
        const glm::vec3 colour = kLevelColours[std::size_t(a.key.level) % kLevelColours.size()] *
                                 float(1.0 - 0.67 * ageFraction);
        // Nearer anchors get larger markers: 2 px far away, up to 5 px close by.
        const int r = int(std::clamp(300.0 / std::max(p.distance_m, 1.0), 1.0, 4.0));
        fillBox(rgb, width, height, p.x - r - 1, p.y - r - 1, p.x + r + 1, p.y + r + 1,
                glm::vec3(0.0f), false);
        fillBox(rgb, width, height, p.x - r, p.y - r, p.x + r, p.y + r, colour, false);
        ++drawn;
    });
    if (const auto probe = volume.probeInProgress()) {
        const Projected p = project(viewProj, eye_m, probe->position_m, width, height);
        if (p.visible) {
            fillBox(rgb, width, height, p.x - 7, p.y - 7, p.x + 7, p.y + 7, glm::vec3(1.0f), true);
            fillBox(rgb, width, height, p.x - 8, p.y - 8, p.x + 8, p.y + 8, glm::vec3(1.0f), true);
        }
    }
    return drawn;
}

}  // namespace amb
