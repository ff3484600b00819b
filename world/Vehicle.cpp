// Vehicle.cpp — the car body: a chassis box, a bonnet box ahead of the driver and a cabin box
// around and behind the eye (open towards the front, so it never covers the view).
#include "world/Vehicle.h"

#include <array>

namespace amb {

namespace {

// Appends an axis-aligned box [lo, hi] with outward normals; `skipFront` leaves out the +Z face.
void addBox(WorldMesh& m, std::array<float, 3> lo, std::array<float, 3> hi,
            std::array<float, 3> albedo, bool skipFront = false) {
    // Per face: normal, then the four corners counter-clockwise seen from outside.
    struct Face {
        std::array<float, 3> n;
        std::array<std::array<int, 3>, 4> c;  // 0 = lo, 1 = hi per axis
    };
    static const Face faces[6] = {
        {{1, 0, 0}, {{{1, 0, 1}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}}}},
        {{-1, 0, 0}, {{{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}}},
        {{0, 1, 0}, {{{0, 1, 1}, {1, 1, 1}, {1, 1, 0}, {0, 1, 0}}}},
        {{0, -1, 0}, {{{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}}},
        {{0, 0, 1}, {{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}}},
        {{0, 0, -1}, {{{1, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 1, 0}}}},
    };
    for (int f = 0; f < 6; ++f) {
        if (skipFront && f == 4) continue;
        const auto base = std::uint32_t(m.vertexCount());
        for (const auto& c : faces[f].c) {
            for (int a = 0; a < 3; ++a) m.positions.push_back(c[a] ? hi[a] : lo[a]);
            m.normals.insert(m.normals.end(), faces[f].n.begin(), faces[f].n.end());
            m.albedo.insert(m.albedo.end(), albedo.begin(), albedo.end());
        }
        for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
    }
}

}  // namespace

WorldMesh makeVehicleMesh() {
    WorldMesh m;
    const std::array<float, 3> paint{0.55f, 0.06f, 0.05f}, dark{0.04f, 0.04f, 0.045f};
    addBox(m, {-0.9f, 0.25f, -2.6f}, {0.9f, 0.8f, 2.3f}, paint);   // chassis
    addBox(m, {-0.85f, 0.8f, 0.4f}, {0.85f, 1.05f, 2.2f}, paint);  // bonnet, ahead of the eye
    addBox(m, {-0.8f, 0.8f, -2.2f}, {0.8f, 1.75f, 0.35f}, dark, true);  // cabin, open in front
    return m;
}

}  // namespace amb
