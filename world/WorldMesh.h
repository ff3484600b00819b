// WorldMesh.h — a triangle mesh as plain arrays, the form in which world/ hands geometry to the
// renderer and to the probe capture (no GL types here).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace amb {

struct WorldMesh {
    std::vector<float> positions;        // xyz per vertex [m], relative to the mesh's origin
    std::vector<float> normals;          // xyz per vertex, unit
    std::vector<float> albedo;           // rgb per vertex, linear [0, 1]
    // Terrain only, else empty: the terrain's own sky visibility at a vertex and at its patch's
    // corners, two a vertex (TerrainPatch::skyDetail).
    std::vector<float> skyDetail;
    // Plants only, else empty: the share of the ambient a vertex's own crown hides from it, one
    // a vertex (a trunk under its crown; Vegetation::crownSkyShare). The draw scales the
    // ambient it applies there by 1 - this.
    std::vector<float> occlusion;
    std::vector<std::uint32_t> indices;  // three per triangle, counter-clockwise seen from outside

    std::size_t vertexCount() const { return positions.size() / 3; }
    std::size_t triangleCount() const { return indices.size() / 3; }
};

}  // namespace amb
