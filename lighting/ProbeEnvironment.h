// ProbeEnvironment.h — what the ambience volume needs to know about the world, apart from the
// captures themselves: where a probe may sit, how fast the sun moves, and the radiance used where
// no anchor is in reach. WorldProbeEnvironment answers from the generated World; tests may answer
// analytically.
//
// [SECTION] Probe placement (docs/DESIGN.md "Capture": never inside terrain or a tree)
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
#pragma once

#include <memory>
#include <vector>

#include <glm/vec3.hpp>

namespace amb {

class World;

class ProbeEnvironment {
  public:
    virtual ~ProbeEnvironment() = default;
    // Where to capture the probe of lattice point (x, z) [m]; maxAside_m bounds the sideways move.
    virtual glm::dvec3 placeProbe(double x_m, double z_m, double maxAside_m) const = 0;
    // The sun's angular speed across the sky [rad per hour of day].
    virtual double sunAngularSpeed_radPerHour() const = 0;
    // Fallback radiance as a cube map: 6 n^2 texels x RGB, face-major, row-major
    // (world/Conventions.h).
    virtual void fallbackCubeMap(double timeOfDay_h, int n, std::vector<float>& rgb) const = 0;
};

struct WorldProbeEnvironmentSettings {
    double probeHeight_m = 2.0;  // above terrain or water
    double clearance_m = 0.5;    // kept from plant footprints and tops
};

class WorldProbeEnvironment : public ProbeEnvironment {
  public:
    // `world` must outlive this object.
    explicit WorldProbeEnvironment(const World& world, const WorldProbeEnvironmentSettings& s = {});
    glm::dvec3 placeProbe(double x_m, double z_m, double maxAside_m) const override;
    double sunAngularSpeed_radPerHour() const override;
    void fallbackCubeMap(double timeOfDay_h, int n, std::vector<float>& rgb) const override;

  private:
    const World& world_;
    WorldProbeEnvironmentSettings settings_;
};

}  // namespace amb
