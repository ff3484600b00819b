// ProbeEnvironment.h — what the ambience volume needs to know about the world, apart from the
// captures themselves: where a probe may sit, how fast the sun moves, and the radiance used where
// no anchor is in reach. WorldProbeEnvironment answers from the generated World; tests may answer
// analytically.
//
// [SECTION] Probe placement (docs/ARCHITECTURE.md "Capture": never inside terrain or a tree)
//   The probe goes probeHeight_m above the terrain (or the water surface) at the lattice point.
//   If that point lies within a plant's footprint (crown or rock radius x scale + clearance_m),
//   it is moved aside to the nearest free spot on rings of up to maxAside_m; if none is free it
//   is lifted above the plant's top (proxy mesh height x scale + clearance_m). The caller
//   records the returned position as the anchor's captured position.
// [SECTION] Fallback radiance (AnchorStore::setFallback)
//   A cube map of the sky model (Preetham by day, twilight, moonlit night; no sun or moon disc)
//   over the upper hemisphere and, below the horizon, a flat Lambertian ground of albedo
//   kGroundAlbedo lit by that sky and the sun and moon: L_ground = albedo / pi x
//   (E_sky(up) + E_sun max(0, sun.y) + E_moon max(0, moon.y)), evaluated by world/SkyGround.h.
//   Its SH is the "no anchor" ambience: what a probe over open flat ground would see.
// [SECTION] Object witnesses (lighting/ReferenceOracle.h: error where users look)
//   The car: carHeight_m above the camera's ground point. Trees: `trees` of those between near_m
//   and far_m from the camera, chosen by a hash of (tree, measuredIndex) so that every tree in
//   range is as likely; each gives a base witness (1 m up, half its crown radius out from the
//   trunk, towards the camera: the lit trunk) and a crown witness (at 60 % of its height, just
//   outside its crown towards the camera). An object's ambience is read at its ground point.
//   Each also carries the normal of the surface it stands for as the camera sees it, at which
//   the error at the drawn normal is taken: a tree's trunk and crown face the camera
//   (horizontally), the car's roof faces up. A tree whose base or crown witness would stand
//   inside another plant or among any tree's leaves, its own too (inTheOpen), or less than
//   0.25 m above the terrain is passed over for the next: such a point shows nothing the
//   camera sees.
#pragma once

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

namespace amb {

class World;

enum class ObjectKind { Car, TreeBase, TreeCrown };
inline constexpr int kObjectKinds = 3;
const char* toString(ObjectKind kind);

struct ObjectWitness {
    ObjectKind kind = ObjectKind::Car;
    glm::dvec3 position_m{0.0};        // where the reference looks from
    double groundX_m = 0.0, groundZ_m = 0.0;  // where the draw reads the object's ambience
    glm::dvec3 normal{0.0, 1.0, 0.0};         // the drawn surface's normal there (unit)
    // The share of the object's ambient the draw gives that surface: a trunk's under its own
    // crown (world/Vegetation.h crownSkyShare), else 1.
    double ambientShare = 1.0;
};

// The terrain patch the main view draws around a ground point for a camera (world/TerrainPatch.h
// selectPatches: the quadtree leaf holding the point), as the draw shades it: the ambient is
// looked up at the leaf's four corners with their normals, and interpolated bilinearly across
// it. `size_m` 0: no patch known (the point's own value stands for it).
// What stands on a ground point: nothing, a tree's crown above it (the ground there is seen
// under the crown), or a bush, a rock or a trunk on it (the ground there is not seen at all).
enum class GroundCover { Open, UnderCrown, Hidden };

// How placeProbe placed the probe of a lattice point: at the point, moved aside out of a plant's
// footprint, or lifted above the plant (no free spot within maxAside_m).
enum class ProbePlacement { AtPoint, MovedAside, Lifted };
const char* toString(ProbePlacement placement);

struct DrawnPatch {
    double x0_m = 0.0, z0_m = 0.0, size_m = 0.0;  // the leaf covers [x0, x0 + size) x [z0, ...)
    // Its vertex grid: quads x quads cells of size_m / quads (TerrainPatch::kPatchQuads); 0:
    // not known (a draw lighting it per vertex cannot be graded).
    int quads = 0;
    std::array<glm::dvec3, 4> corner_m{};        // ground points (x0,z0), (x1,z0), (x0,z1), (x1,z1)
    std::array<glm::dvec3, 4> cornerNormal{};    // unit, World::normal there
    glm::dvec3 surface_m{0.0};                   // the ground at the point itself
    glm::dvec3 surfaceNormal{0.0, 1.0, 0.0};     // unit, World::normal there
    GroundCover cover = GroundCover::Open;         // at the point itself
};

// The grid cell of a drawn patch that holds a ground point, as the draw meshes it: what a patch
// lit per vertex (the ambient's terrainVertexRange_m) shows there is the cell's vertex values
// interpolated as its triangles interpolate them. Its four vertices (a, b), (a + 1, b),
// (a, b + 1), (a + 1, b + 1) as rendered (heights stitched across LOD boundaries) with the
// mesh's normals, and the weights of the triangle holding the point (world/TerrainPatch.h
// quadTriangleWeights: one is 0). `known` false: none.
struct DrawnCell {
    bool known = false;
    double spacing_m = 0.0;  // the patch's vertex spacing
    std::array<glm::dvec3, 4> vertex_m{};
    std::array<glm::dvec3, 4> normal{};
    std::array<double, 4> weight{};
};

class ProbeEnvironment {
  public:
    virtual ~ProbeEnvironment() = default;
    // Where to capture the probe of lattice point (x, z) [m]; maxAside_m bounds the sideways move.
    virtual glm::dvec3 placeProbe(double x_m, double z_m, double maxAside_m) const = 0;
    // How placeProbe places it. By default from its position alone: moved aside when it left the
    // point, never lifted.
    virtual ProbePlacement placement(double x_m, double z_m, double maxAside_m) const;
    // The sun's angular speed across the sky [rad per hour of day].
    virtual double sunAngularSpeed_radPerHour() const = 0;
    // Fallback radiance as a cube map: 6 n^2 texels x RGB, face-major, row-major
    // (world/Conventions.h).
    virtual void fallbackCubeMap(double timeOfDay_h, int n, std::vector<float>& rgb) const = 0;
    // Witnesses on objects near a camera at (x, z) (see above); none by default.
    virtual std::vector<ObjectWitness> objectWitnesses(double cameraX_m, double cameraZ_m,
                                                       int trees, double near_m, double far_m,
                                                       double carHeight_m,
                                                       int measuredIndex) const {
        (void)cameraX_m, (void)cameraZ_m, (void)trees, (void)near_m, (void)far_m;
        (void)carHeight_m, (void)measuredIndex;
        return {};
    }
    // Whether a reference may stand at `point_m`: at least clearance_m above the terrain, not
    // among any tree's leaves (Vegetation::amongLeaves: the full crowns' bumps reach past their
    // spheres), and outside every plant (a tree's spheres, world/Vegetation.h; a bush's or
    // rock's footprint up to its top) but the one standing at ownBase_m, if given (see Object
    // witnesses). Everywhere by default.
    virtual bool inTheOpen(const glm::dvec3& point_m, double clearance_m,
                           const glm::dvec3* ownBase_m = nullptr) const {
        (void)point_m, (void)clearance_m, (void)ownBase_m;
        return true;
    }
    // The patch drawn around ground point (x, z) for a camera at `camera_m` (see DrawnPatch);
    // none by default.
    virtual DrawnPatch drawnPatch(double x_m, double z_m, const glm::dvec3& camera_m) const {
        (void)x_m, (void)z_m, (void)camera_m;
        return {};
    }
    // The cell of that patch holding (x, z) (see DrawnCell); none by default.
    virtual DrawnCell drawnCell(double x_m, double z_m, const glm::dvec3& camera_m) const {
        (void)x_m, (void)z_m, (void)camera_m;
        return {};
    }
};

struct WorldProbeEnvironmentSettings {
    // Above terrain or water. At the near field's eye height (0.5 m) the terrain's error at the
    // drawn normal fell by 17-20 % on the drives but the road's on the screen rose by 70-80 %
    // on the highway and the dusk road (docs/HISTORY.md "Probes at the surfaces' eye height
    // (not kept)"), so it stays 2 m.
    double probeHeight_m = 2.0;
    double clearance_m = 0.5;    // kept from plant footprints and tops
};

class WorldProbeEnvironment : public ProbeEnvironment {
  public:
    // `world` must outlive this object.
    explicit WorldProbeEnvironment(const World& world, const WorldProbeEnvironmentSettings& s = {});
    glm::dvec3 placeProbe(double x_m, double z_m, double maxAside_m) const override;
    ProbePlacement placement(double x_m, double z_m, double maxAside_m) const override;
    double sunAngularSpeed_radPerHour() const override;
    void fallbackCubeMap(double timeOfDay_h, int n, std::vector<float>& rgb) const override;
    bool inTheOpen(const glm::dvec3& point_m, double clearance_m,
                   const glm::dvec3* ownBase_m = nullptr) const override;
    std::vector<ObjectWitness> objectWitnesses(double cameraX_m, double cameraZ_m, int trees,
                                               double near_m, double far_m, double carHeight_m,
                                               int measuredIndex) const override;
    DrawnPatch drawnPatch(double x_m, double z_m, const glm::dvec3& camera_m) const override;
    // From the terrain mesh the main view builds for those leaves (TerrainPatchCache::build,
    // stitched), built once per camera asked.
    DrawnCell drawnCell(double x_m, double z_m, const glm::dvec3& camera_m) const override;
    ~WorldProbeEnvironment() override;

  private:
    const World& world_;
    WorldProbeEnvironmentSettings settings_;
    // The leaves of the last camera drawnPatch was asked for (a reference frame asks once per
    // terrain witness, all for one camera).
    mutable glm::dvec3 leavesCamera_{std::nan("")};
    mutable std::vector<std::array<double, 3>> leaves_;  // x0, z0, size
    // drawnCell's: the patches (cached across cameras), the mesh of the last camera asked.
    struct Mesh;
    mutable std::unique_ptr<Mesh> mesh_;
};

}  // namespace amb
