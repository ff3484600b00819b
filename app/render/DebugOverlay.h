// DebugOverlay.h — draws the ambience volume's anchors over a finished 8-bit frame: one marker
// per anchor at its captured position, coloured by lattice level (coarsest red, then orange,
// yellow, green, cyan, blue, violet) and darkened with age (fresh = full colour, at the end of
// its lifetime a third of it); the probe being captured as a white frame.
#pragma once

#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace amb {

class AmbienceVolume;

// `rgb` is top row first, 3 bytes per pixel; `viewProj` maps positions relative to `eye_m` to
// clip space (Renderer::viewProjection). Returns the number of anchors drawn.
int drawAnchorOverlay(std::vector<unsigned char>& rgb, int width, int height,
                      const glm::mat4& viewProj, const glm::dvec3& eye_m,
                      const AmbienceVolume& volume);

}  // namespace amb
