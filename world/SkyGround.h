// SkyGround.h — what a viewer over open, flat land sees: the sky model (world/Sky.h, no sun or
// moon disc) above the horizon and, below it, a flat Lambertian ground of albedo kGroundAlbedo
// (world/Conventions.h) lit by that sky and by the sun and the moon:
//   L_ground = kGroundAlbedo / pi x (E_sky(up) + E_sun max(0, sun.y) + E_moon max(0, moon.y)),
//   E_sky(up) = integral over the upper hemisphere of L_sky(w) w.y dw,
// the integral taken with the caller's quadrature (its directions and their solid angles). A
// direction with y >= 0 sees the sky, y < 0 the ground.
//
// The one implementation behind the fallback scene (lighting/ProbeEnvironment.h, a cube map) and
// the renderer's sky texture and fixed ambients (app/frame/SkyLighting.h, an equirect texture).
#pragma once

#include <vector>

#include <glm/vec3.hpp>

namespace amb {

class Sky;

struct SkyGround {
    glm::dvec3 skyIrradianceUp{0.0};   // E_sky(up): on an upward surface, from the sky alone
    glm::dvec3 groundIrradiance{0.0};  // E_sky(up) + sun + moon: the light on the ground
    glm::dvec3 ground{0.0};            // radiance of the ground: kGroundAlbedo / pi x the above
    glm::dvec3 skyMean{0.0};  // solid-angle weighted mean sky radiance over the sky directions
};

// The sky-and-ground radiance at unit directions `dirs` (world axes), each standing for the solid
// angle solidAngles_sr[i] [sr]: `rgb` gets 3 floats per direction, in the order given.
SkyGround evaluateSkyGround(const Sky& sky, double timeOfDay_h, const std::vector<glm::dvec3>& dirs,
                            const std::vector<double>& solidAngles_sr, std::vector<float>& rgb);

// The ground's light and radiance for a given E_sky(up) (the second half of the above).
SkyGround groundUnder(const Sky& sky, double timeOfDay_h, const glm::dvec3& skyIrradianceUp);

// The equirect grid of the renderer's sky texture: kWidth x kHeight texels, row 0 at the zenith,
// column 0 at azimuth -pi; each texel's centre direction and solid angle (sin theta dtheta dphi).
struct SkyGrid {
    static constexpr int kWidth = 64, kHeight = 32;
    std::vector<glm::dvec3> directions;
    std::vector<double> solidAngles_sr;
};
const SkyGrid& skyGrid();

// The ambient the captures and the reference light their surfaces with (the first bounce, before
// any ambience; app/frame/SkyLighting.h "hemisphere"): the sky's mean radiance s over the upper
// hemisphere and the distant ground's g over the lower one, on the sky grid. Its SH has two
// coefficients only (world/Conventions.h basis), so its irradiance is E(n) = pi / 2 ((s + g) +
// (s - g) n.y).
struct HemisphereAmbient {
    glm::dvec3 sky{0.0}, ground{0.0};  // mean radiances [W m^-2 sr^-1]
    // L_0 = Y00 4 pi (s + g) / 2 and the vertical band-1 coefficient L_1 = Y1 (s - g) / 2 x
    // 2 integral over y > 0 of y dw = Y1 pi (s - g).
    glm::dvec3 shBand0() const;
    glm::dvec3 shVertical() const;
};
HemisphereAmbient hemisphereAmbient(const Sky& sky, double timeOfDay_h);

}  // namespace amb
