// SkyLighting.h — the sky model evaluated for one time of day, as the frame's draw and the
// fixed ambients read it: the sky texture (with distant ground below the horizon), the main
// light, the hemisphere means, the exposure; and the fixed ambients (--ambient constant |
// hemisphere) derived from it. No GL: the renderer uploads what it needs.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "app/frame/Draw.h"
#include "lighting/SH.h"
#include "world/SkyGround.h"

namespace amb {

class Sky;

// ---- SkyLighting -----------------------------------------------------------------------------
// The sky model evaluated for one time of day: an equirect texture of the sky and, below the
// horizon, of the flat ground of world/SkyGround.h (albedo kGroundAlbedo, lit by the sky, the
// sun and the moon), and the numbers the ambient and exposure derive from.
struct SkyLighting {
    double timeOfDay_h = -1.0;
    glm::vec3 lightDir{0, 1, 0};  // towards the main light (sun, or the moon at night)
    glm::vec3 lightIrradiance{0.0f};
    glm::vec3 sunDiscRadiance{0.0f};
    float sunCosRadius = 1.0f;
    glm::vec3 skyMean{0.0f};          // mean radiance over the upper hemisphere
    glm::vec3 groundMean{0.0f};       // mean radiance of the distant ground (lower hemisphere)
    glm::vec3 skyIrradianceUp{0.0f};  // irradiance of an upward surface from the sky alone
    glm::vec3 sunAzimuth{0, 0, 1};    // unit horizontal direction of the sun's azimuth
    glm::vec3 horizonToward{0.0f}, horizonAway{0.0f};  // sky 2 degrees up, towards / away
    std::vector<float> texture;                        // kWidth x kHeight RGB, row 0 = zenith
    static constexpr int kWidth = SkyGrid::kWidth, kHeight = SkyGrid::kHeight;
};
SkyLighting evaluateSky(const Sky& sky, double timeOfDay_h);

// Exposure for the tone mapper: a white Lambertian surface facing up maps to 0.6 before the
// curve; never brighter than 1/1000 of the noon reference, so nights stay dark.
float exposureFor(const SkyLighting& now, const SkyLighting& noon);

// ---- Ambient ---------------------------------------------------------------------------------
enum class AmbientMode { Constant, Hemisphere };
AmbientMode parseAmbientMode(const std::string& text, const std::string& where);
const char* toString(AmbientMode mode);

// The ambient before the ambience volume: the same everywhere.
//   constant:   the mean radiance of the whole sphere (sky above, distant ground below) from
//               every direction: E(n) = pi * mean.
//   hemisphere: the sky mean over the upper hemisphere, the ground mean over the lower one:
//               E(n) = pi/2 ((s + g) + (s - g) n.y) (its exact SH has bands 0 and 1 only).
class FixedAmbient final : public AmbientSource {
  public:
    FixedAmbient(AmbientMode mode, const SkyLighting& sky);
    glm::vec3 cornerIrradiance(const glm::dvec3& position_m,
                               const glm::dvec3& normal) const override;
    std::uint32_t objectSet(const glm::dvec3& position_m,
                            std::vector<AmbientSet>& sets) const override;
    const ShRgb& sh() const { return sh_; }

  private:
    ShRgb sh_;
    AmbientSet set_;
};

}  // namespace amb
