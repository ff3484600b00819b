// NearField.h — the two-scale ambience: probes capture the far field, and the occluders near a
// shading point are applied to it there, in closed form (docs/ARCHITECTURE.md "Two scales").
//
// [SECTION] Why
//   A probe 27 m away cannot know that a point sits under a canopy or beside a trunk, and the
//   interpolation smears whatever its corners saw over the whole cell. The world knows every
//   plant exactly, so the plants within radius_m of a probe are left out of its capture (the far
//   field, smooth enough to interpolate) and the plants within radius_m of each shading point are
//   put back at that point.
// [SECTION] Radii
//   A probe leaves out the plants within captureRadius_m of it; a point puts back those within
//   radius_m of it. The point reads probes up to a cell away, so a plant a little farther than
//   captureRadius_m from the point may be missing from a nearby probe's capture: putting back
//   about half as much again as the probes leave out measures best. A plant put back is seen
//   from the surface's own height, a plant left in a capture from the probe's 2 m, where a crown
//   stands lower in the sky and hides less of it: so the more of the wood is put back, the less
//   of the probes' brightness is left. 40 / 60 m against the earlier 12 / 20 m: the error at the
//   drawn normal on the highway, the mountain road and the low flight 13, 10 and 3 % lower, for
//   about a fifth more frame time (each point's caps grow with the square of radius_m; 60 / 90 m
//   gains 19, 16 and 4 % for a third more; docs/TUNING.md "Near field"). Bushes and rocks are
//   never in a capture, so they are near out to smallRadius_m. A plant's weight fades from 1 to 0
//   over the last kNearFade of its radius (smoothstep), so a moving point (the car) gains and
//   loses plants without a step.
// [SECTION] Surface height
//   Terrain corners and road vertices are asked at kShadingHeight_m above the ground, the probes'
//   height, whose far field the near field completes. A surface's own irradiance is taken at the
//   surface, so its plants, terrain walls and ground can be put back as seen from
//   surfaceHeight_m instead (the far field stays the probes'). Measured against the bounce-lit
//   reference with the terrain near the eye lit per vertex and the plants' shadows, 0.5 m took
//   the error at the drawn normal on the tuning replays from 0.175 / 0.283 / 0.052 to 0.148 /
//   0.191 / 0.048 (2 m before; docs/TUNING.md "Near field", surfaceHeight_m). Lower still gains
//   on the mountain road and loses on the other two.
// [SECTION] Range
//   The near field is put back where the picture can show it. Objects farther than
//   objectRange_m from the camera (plants a few pixels tall) and terrain corners and road
//   vertices farther than cornerRange_m (where a terrain patch is hundreds of metres across, so
//   one corner's plants would colour the whole patch, and a road is a few pixels wide) take the
//   far field alone. The near field fades out over the last kNearFade of each range
//   (rangeWeight), so a point the camera leaves behind loses it without a step. Most of a
//   frame's road vertices lie kilometres away: on the highway the range takes the near field's
//   builds from about 5 to 1 a frame.
// [SECTION] Patch mean
//   The draw evaluates the terrain's ambience at patch corners only and blends it bilinearly
//   across the patch (world/TerrainPatch.h): a patch is 32 m across next to the camera and
//   256 m half a kilometre away. A corner's value is therefore read over the tent
//   (1 - |dx| / P)(1 - |dz| / P) of its patch size P, and the near field at the corner point
//   alone (one tree's canopy, a rock beside it) would colour that whole area. So, given the
//   corner's patch size, its near field is the mean over the tent: patchSamples^2 points on
//   the ground at offsets spaced 2P / (patchSamples + 1), weighted by the tent, each the
//   near field of its own point through its own normal, on the corner's far field:
//       E = a(n) . L + sum_s w_s ((h_s + s_s) . L + light_s)
//   (what the near field changes, averaged; a(n) the corner's own normal). With 3 a side the
//   points lie on the lattice of P / 2, so neighbouring corners, of one patch size or of two,
//   share most of them: a cache of the samples builds about 4 points a corner, not 9. The
//   guard reads the mean hide (exact for each sample, close for the mean). The ground terms'
//   light is not linear in the light's direction, so each sample's is kept with the mean
//   (NormalTransfer::groundParts) to be remade when the light moves.
// [SECTION] Caps
//   An occluder is a sphere (world/Vegetation.h: crowns, trunks, rocks as spheres). Seen from a
//   point p it is a cap of half-angle theta (sin theta = r / |c - p|) around d = (c - p) / |c - p|.
//   The cap's indicator projects onto a zonal function about d (Sloan, "Stupid SH tricks"):
//       z_0 = sqrt(pi) (1 - cos t),  z_1 = sqrt(3 pi) / 2 sin^2 t,  z_2 = sqrt(5 pi) / 2 cos t sin^2 t
//   and, turned to d, C_k = sqrt(4 pi / (2l + 1)) z_l Y_k(d). Its solid angle is
//   Omega = 2 pi (1 - cos t) = sqrt(4 pi) z_0.
// [SECTION] What a cap does to the far field F (order-2 SH L)
//   It hides the far radiance behind it and shows its own:  L' = L + sum_i w_i (R_i - A_i) C_i,
//     A_i = (C_i . L) / Omega_i    the far field's mean over the cap (exact for the order-2 part);
//     R_i = rho_i / pi (E_amb,i + 2/3 Phi(alpha_i) E_sun)   the sphere's mean outgoing radiance
//                                  towards p: a Lambertian sphere of albedo rho_i;
//     E_amb,i = sum_k Ahat_l f_l L_k Y_k(-d_i), f = (1, 2/3, 1/4): the far field's irradiance
//                                  averaged over the sphere's visible disc (projected-area weights
//                                  of the normals n . (-d) = mu: integral 2 mu P_l(mu) over [0, 1]);
//     Phi(a) = (sin a + (pi - a) cos a) / pi: the Lambert sphere's phase law, alpha_i the angle
//                                  between the main light and -d_i, 2/3 its disc mean at full
//                                  phase. The main light is the one the renderer draws apart.
//   So L' = (I + T) L + S E_sun with T (9 x 9 per channel) fixed by the geometry. The light is a
//   delta in the far field, so its term uses the same map: S_c = (T_c - hide) Y(l), exactly the
//   order-2 projection in l of the phase law (within 0.8 % of its peak) and, for terrain bands,
//   of a wall's cosine (within 9 %, as order-2 irradiance always is). T is cached per point (the
//   points the draw asks for do not move), 2.5 kB with the ground's terms, whatever the number of
//   occluders.
// [SECTION] Plants' shadows
//   The phase law lights a sphere as if nothing stood between it and the light, but in a wood a
//   crown stands in its neighbours' shadows and a hill's, as the reference's and the main
//   view's shadowed crowns do. So each plant sphere carries the share of the light that reaches
//   its lit side (SphereOccluder::sunVisibility): five points on it (the point facing the light
//   and four 60 degrees from it, weighted by their cosine), each lit as far as the terrain
//   (terrainLightVisibility) and the other plants' spheres along the light leave it. A sphere's
//   share depends on the light alone, so the scene's answer is kept per sphere until the light
//   moves (NearField::sunVisibilities). A point's caps take one share for their light term S:
//   the mean of theirs weighted by what each shows of the light (w_i Omega_i rho_i Phi(alpha_i);
//   terrain bands count as lit), kept with the transfer when the light moves on, as the
//   ground's own visibilities are (NearFieldTransfer::capSun). Off (plantShadows), every share
//   is 1.
// [SECTION] Plants' sky
//   A cap's ambient E_amb,i is the far field's irradiance at the point, and the far field holds
//   no plant within captureRadius_m of its probes: each plant put back is lit as if it stood
//   alone in the open. In a wood its neighbours (and its own upper crown, over a trunk) hide
//   much of its sky, as they do in the reference, whose leaves take the light of the full scene.
//   So each sphere also carries the share of the sky its surface sees past the other plants'
//   spheres (SphereOccluder::skyVisibility): nine points on it (its top, four 30 degrees above
//   its equator, four 30 degrees below), each over 24 directions of the upper hemisphere
//   weighted by their cosine to the point's normal, the directions blocked as sphereBlock
//   blocks them (points inside another sphere of the plant are not surface and are skipped).
//   The sky is most of a crown's ambient, so the cap's ambient is scaled by that share: its
//   row of T_c shows rho_i V_i. Its light term is kept: the caps' one share of the light
//   becomes sum f_i s_i / sum f_i V_i (f_i as in Plants' shadows), which makes the light
//   S = (T_c - hide) Y(l) capSun what it was. The share depends on the scene alone: kept per
//   sphere for the run (NearField::skyVisibilities). Measured, lighting crowns as if alone was
//   most of the model's brightness on the drives (docs/HISTORY.md "Plants' sky"). Off
//   (plantSky), every share is 1.
// [SECTION] Terrain
//   The terrain cannot be left out of a capture (it would leave a hole), so the anchors hold the
//   terrain their probes saw. What they cannot hold is terrain near a point that rises above the
//   ground's broad slope there: a gully's walls, a valley floor's rim, a hollow. Around the point
//   (kShadingHeight_m up) the horizon is searched in 8 wedges out to terrainRadius_m; in each, the
//   band between the broad slope's elevation (the plane of the heights terrainRadius_m away) and
//   the nearest terrain's highest elevation is a wall of the terrain's albedo there, lit like a
//   cap (what it hides, what it shows, the light's cosine on a wall facing the point). Its SH is
//   closed form: over azimuth phi0..phi1 and elevation e1..e2 every basis function is a sum of
//   products of cos/sin powers, integrated exactly. A plant seen against a band hides the band.
// [SECTION] Ground
//   Below a point the far field holds the ground its probes stood over: grass where the point is
//   on asphalt, sunlit turf where it is in a tree's shadow, another patch of the albedo's noise.
//   That ground fills most of a low point's lower hemisphere (the ground within R of the foot of
//   a point h up holds R^2 / (R^2 + h^2) of a downward normal's irradiance: 98 % at R = 16 m,
//   h = 2 m), and measured against the reference it was the largest part of the error near the
//   camera. So the ground within groundRadius_m of the foot (the plane through the foot with the
//   ground's normal there) is put in the far field's place. Over 32 directions d_k of that
//   region (4 rings of equal solid angle w about -n, 8 azimuths) each ray that no plant stops
//   meets the ground at x_k, of albedo rho_k (the terrain's as the patches draw it) and lit
//   with visibility V_k (the sun blocked by the point's plants or by terrain):
//     L' = L - sum_k w Y(d_k) (Y(d_k) . L)                     what the probes saw there
//            + g_c E_amb,c(n) + lit_c E_light max(0, n . l)
//     g_c = sum_k w rho_k,c / pi Y(d_k),  lit_c = sum_k w rho_k,c / pi V_k Y(d_k),
//   the ground's radiance rho / pi (E_amb + E_light V cos). It is lit as the captures and the
//   reference light every surface they draw, by the main light and by the sky's hemisphere
//   ambient A (world/SkyGround.h HemisphereAmbient; the first bounce), here as the point's caps
//   leave it at the ground's normal n: E_amb,c = ((I + T_c)^T a(n)) . A_c, T_c the caps' (a
//   canopy over the ground darkens its sky and shows it its leaves). Only A's two coefficients
//   (band 0 and the vertical band 1) are non-zero, so a ground keeps two weights a channel
//   (GroundAmbient). Against the reference this measured better than lighting the ground by the
//   far field through the caps (what the probes' own sky held, about 10 % too bright on the
//   drives, and in a dense forest far too dark) and than the ambient without the caps
//   (docs/TUNING.md "Near field"). The first term is part of T (the hide is the same for every
//   channel); the other two are remade when the light moves (the ambient with it), with the
//   visibility of the light the point was built in. With no caps, a white ground under a far
//   field of the ambient's sky radiance all round changes nothing.
//   The car moves: 32 directions swept over a tree's shadow or the albedo's noise would make
//   the term jitter by a few per cent a frame. So an object first built within latticeRange_m
//   of the camera takes the quadratic B-spline blend (C1 in the position) of the terms at the
//   3 x 3 nearest points of a lattice of groundCell_m, each built once at the object's lift
//   above the ground (no plant stopping its rays: the object's own caps hide what stands in
//   front) and cached. Plants, first built as they enter objectRange_m, and terrain corners and
//   road vertices never move: they take their own (a plant's with its own spheres left out of
//   what stops the rays).
// [SECTION] Overlap (occluders must not darken twice)
//   Caps are taken largest first; cap i keeps the weight w_i = f_i prod_{j<i} (1 - f_j O_ij /
//   Omega_i), f its fade (see Radii), O_ij the solid angle it shares with an earlier cap j (the
//   smoothstep approximation of two caps' intersection of Oat and Sander, "Ambient aperture
//   lighting", 2007). A cap inside an earlier one gets weight 0; caps apart keep f.
// [SECTION] Guard
//   What the caps hide must not take the irradiance below zero for any normal (below the far
//   field's own minimum if that is negative). The ground's hide is not the caps': it takes the
//   lower hemisphere's far radiance out only to put the ground's (never negative) in its place,
//   and the far field's upper half alone sits at zero irradiance for a downward normal, so
//   guarding it would switch on and off with rounding. The guard looks at the caps' part only. A sampled lower bound of the minimum of the far
//   field less what is hidden comes first: the minimum over 160 normals less half a bound of the
//   second derivative along great circles times the squared covering radius (at the true
//   minimum the gradient vanishes). Only if it is negative is the exact minimum
//   (shMinIrradiance) taken and the hidden part scaled down until it holds. A point keeps its
//   scale while its far field stays within 25 % of the one it was checked for (far fields change
//   slowly: blends, the sun), so checks are rare. What the caps show is radiance >= 0 added, as a
//   capture of a lit object adds it. Caps narrower than asin(0.015) (a trunk 20 m away) are left
//   out.
// [SECTION] Through one normal
//   The draw needs the SH at terrain corners and road vertices only through their own normal n
//   (it interpolates the irradiance, not the SH). There E(n) = a(n) . L' with a_k = Ahat_l
//   Y_k(n), so the 9 x 9 maps collapse to vectors: E_c = a . L_c + g_c (h . L_c) + s_c . L_c +
//   (s_c . Y(l)) E_light,c, h = hide^T a, s_c = (T_c - hide)^T a: 66 floats a point with the
//   ground's light term (NormalTransfer), not 500, and no matrix product per frame. The guard is
//   then exact for that normal: what is hidden never takes E(n) below min(0, a . L), g_c < 1
//   only where it would. The draw reads 48 of them a frame (NormalApply: w_c = a + h + s_c in
//   four lanes a coefficient, and a + h, whose sign says whether the guard can act at all).
//   Those points lie on the ground with its normal (a terrain corner, a road vertex, a patch
//   mean's sample): the ground term's region lies below their own tangent plane, where the
//   exact irradiance sees none of it and order-2 SH only rings (through the normal it moved
//   the drives' corners by 1.1-1.5 % on average, 5.4 % at most). So a point asked through a
//   normal within kOwnGroundDeg of the ground's at its foot is built without it, which
//   takes a fifth off the build.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>
#include <tsl/hopscotch_map.h>

#include "lighting/AmbienceMethod.h"
#include "lighting/SH.h"
#include "world/DirectionalLight.h"
#include "world/SkyGround.h"
#include "world/TerrainPatch.h"

namespace amb {

class World;

inline constexpr double kNearFade = 0.25;  // see Radii

struct NearFieldSettings {
    bool enabled = true;     // apply the near field at shading points (a method's switch)
    double radius_m = 60.0;  // r_near: occluders this close (horizontally) to a point are near
    // Probes leave out the plants this close to them (see Radii).
    double captureRadius_m = 40.0;
    bool plants = true;      // trees, bushes and rocks as spheres
    // Their spheres lit by the light only where other plants and the terrain leave it (see
    // Plants' shadows); off, as if nothing shaded them.
    bool plantShadows = true;
    // Their spheres' ambient scaled by the share of the sky the other plants leave them (see
    // Plants' sky); off, each is lit as if it stood alone in the open.
    bool plantSky = true;
    // Bushes and rocks, which probe captures never draw (only trees are in the capture scene),
    // are near out to this radius: the near field is all the ambience knows of them.
    double smallRadius_m = 48.0;
    bool terrain = true;     // the terrain's near horizon (see Terrain)
    double terrainRadius_m = 32.0;  // how far the near horizon is searched
    bool ground = true;             // the ground below the point (see Ground)
    double groundRadius_m = 16.0;   // how far from the point's foot the ground is its own
    double groundCell_m = 6.0;      // the lattice whose ground terms objects blend (see Ground)
    // Objects first built this close to the camera (the car, which moves) blend the lattice's
    // terms; those first built farther (plants entering objectRange_m, which stand still, and
    // a flight's ground point 60 m below it: the distance is in three dimensions) take their
    // own, as corners do (see Ground).
    double latticeRange_m = 16.0;
    // Terrain corners and road vertices (points asked with their normal) are shaded at a
    // surface: the near field puts its plants, terrain walls and ground back as seen from this
    // height above the ground, not from the probes' kShadingHeight_m, whose far field it
    // completes (see Surface height).
    double surfaceHeight_m = 0.5;
    // Points the draw asks for (terrain corners, objects) are cached with their transfer; when a
    // cache holds this many, the half of it used least recently is dropped (the view's points,
    // asked every frame, stay).
    int cacheEntries = 16384;  // about 2.5 kB each (objects), 0.5 kB (corners)
    // Objects (shAt: plants, the car) farther than this from the camera take the far field
    // alone: a few pixels tall, they show no near field, and they are most of the draw's
    // lookups (4 600 of 7 500 a frame on the highway).
    double objectRange_m = 64.0;
    // Terrain corners and road vertices farther than this take the far field alone (see
    // Range): there a patch is hundreds of metres across and a road a few pixels wide. (why
    // this value: docs/TUNING.md "Near field")
    double cornerRange_m = 500.0;
    // A terrain corner's colour is blended across every patch that has it as a corner, so it
    // stands for the tent of the patch's size about it, not for the corner alone (see Patch
    // mean): the near field there is the tent-weighted mean of patchSamples x patchSamples points
    // of the ground. Off, a corner takes the near field at its own point.
    bool patchMean = true;
    int patchSamples = 3;  // per axis
    // The draw scales the terrain's ambient at each vertex of its finest patches by the
    // terrain's own sky visibility there against the patch's corners (world/TerrainPatch.h
    // skyDetail): the gullies that fall between corners. Needs `terrain`.
    bool vertexDetail = true;
    // Terrain patches whose nearest point (horizontally) lies closer than this to the eye take
    // the ambient at each mesh vertex, each at its own point and through its own normal, instead of blending the corners across the patch (docs/ARCHITECTURE.md
    // "Terrain and objects"). 0: off, every patch blends its corners. (why this value:
    // docs/TUNING.md "Near field")
    double vertexAmbient_m = 320.0;
    // The draw lights at most this many new mesh vertices a frame per vertex (nearest patches
    // first, at least one patch); a patch entering the range whose turn has not come blends its
    // corners meanwhile, so a frame's near-field builds stay bounded (docs/ARCHITECTURE.md
    // "Terrain and objects"). 0: no bound, every patch in range at once.
    int vertexPointsPerFrame = 600;
    // The surfaces the method's captures draw (lit by the hemisphere, or with ownLight by the
    // method's own field) within this range of the camera take the near field's change of that
    // light, as the draw's terrain corners do (NearFieldMethod.cpp "Captures' light"): without
    // it a forest floor under its canopy is lit as if it stood in the open. 0: off. (why these
    // values: docs/TUNING.md "Near field")
    double captureLightRange_m = 400.0;
    // The lattice on which that near field is taken and blended bilinearly.
    double captureLightCell_m = 32.0;
    // At most this many new lattice points a frame, nearest the camera first (0: no bound).
    int captureLightPointsPerFrame = 32;
};
// The near field's weight at distance_m (horizontal) from the camera for a range: 1 out to
// (1 - kNearFade) range, 0 from range on, smoothstep between (see Range).
double rangeWeight(double distance_m, double range_m);

struct SphereOccluder {
    glm::dvec3 centre_m{0.0};
    double radius_m = 0.0;
    glm::dvec3 albedo{0.0};
    double weight = 1.0;  // in [0, 1]: faded near the edge of the near radius (see Radii)
    double sunVisibility = 1.0;  // the light's share on its lit side (see Plants' shadows)
    double skyVisibility = 1.0;  // the sky's share its surface sees (see Plants' sky)
};

// ---- Closed forms ------------------------------------------------------------------------------
// Zonal coefficients z_l of a cap of half-angle t (given cos t) about +Y.
std::array<double, 3> capZonal(double cosHalfAngle);
// The cap's SH about unit direction d: C_k = sqrt(4 pi / (2l + 1)) z_l Y_k(d).
std::array<double, kShCoefficients> capSh(const glm::dvec3& direction, double cosHalfAngle);
// Solid angle shared by two caps (half-angles a, b, centres `separation` apart) [sr].
double capOverlap(double halfAngleA, double halfAngleB, double separation_rad);
// Lambert sphere phase law Phi(alpha), 1 at full phase, 0 at new.
double lambertSpherePhase(double alpha_rad);

// A wedge of the horizon where near terrain rises between two elevations [rad] (see Terrain);
// azimuth phi about +Y, direction (cos e cos phi, sin e, cos e sin phi).
struct HorizonWedge {
    double azimuth0 = 0.0, azimuth1 = 0.0;
    double lower = 0.0, upper = 0.0;
    glm::dvec3 albedo{0.0};
};

// The ground at one place as the scene knows it.
struct GroundPoint {
    double height_m = 0.0;
    glm::dvec3 normal{0.0, 1.0, 0.0};
    glm::dvec3 albedo{0.0};
    // In a plane given to groundAt: false when the caller knows no road reaches the point (the
    // scene may skip its road lookup; NearFieldScene::roadNear).
    bool roadNear = true;
};

// The ground's ambient as its point's caps leave it (see Ground): per channel, the weights of
// the hemisphere ambient's two SH coefficients (band 0 and the vertical band 1) in the
// irradiance at the ground's normal with the caps applied; E_amb,c = w0 A_0 + w1 A_1.
using GroundAmbient = std::array<std::array<float, 2>, 3>;

// What the ground near a point puts in place of the far field's (see Ground).
struct GroundTerm {
    std::array<float, kShCoefficients * kShCoefficients> hide{};  // -sum w Y Y^T, row-major
    std::array<std::array<float, kShCoefficients>, 3> show{};      // g_c (sigma not applied)
    std::array<std::array<float, kShCoefficients>, 3> lit{};       // lit_c
    glm::dvec3 normal{0.0, 1.0, 0.0};                              // the ground's at the foot
    int samples = 0;  // directions that met the ground (no plant in front)
    bool any = false;
};

// One occluder as seen from a point: a plant's cap or a terrain band.
struct OccluderCap {
    glm::dvec3 direction{0.0, 1.0, 0.0};  // centre
    double cosHalfAngle = 1.0;            // caps
    double weight = 1.0;                  // after overlap (see above)
    glm::dvec3 albedo{0.0};
    bool band = false;  // a terrain band: lit as a wall facing the point
    double azimuth0 = 0.0, azimuth1 = 0.0, lower = 0.0, upper = 0.0;  // bands
    std::array<double, kShCoefficients> sh{};  // the region's SH
    double solidAngle = 0.0;
    int behind = -1;  // the band a cap is seen against: it hides that band, not the far field
    double sunVisibility = 1.0;  // its sphere's (see Plants' shadows); bands 1
    double skyVisibility = 1.0;  // its sphere's (see Plants' sky); bands 1
};
// The caps of `occluders` seen from `point`, with their overlap weights (largest first).
// An occluder that holds the point is a cap wider than a hemisphere: 90 degrees at its surface,
// the whole sphere at its centre.
std::vector<OccluderCap> occluderCaps(const glm::dvec3& point_m,
                                      const std::vector<SphereOccluder>& occluders);

// The SH of the band azimuth0..azimuth1 x lower..upper (closed form, see Terrain).
std::array<double, kShCoefficients> bandSh(double azimuth0, double azimuth1, double lower,
                                           double upper);
// The wedges as bands (thinner than about a degree: none).
std::vector<OccluderCap> terrainBands(const std::vector<HorizonWedge>& wedges);
// Everything near a point: the terrain's bands, then the plants' caps, each cap seen against a
// band marked as in front of it.
std::vector<OccluderCap> nearOccluders(const glm::dvec3& point_m,
                                       const std::vector<SphereOccluder>& occluders,
                                       const std::vector<HorizonWedge>& horizon);

// L' = (I + T) L + S E_light, per channel (see above), T split into what the caps hide (the same
// for every channel) and what they show.
struct NearFieldTransfer {
    std::array<float, kShCoefficients * kShCoefficients> hide{};  // row-major
    // T_c = hide + what the caps show, by column for the apply, the channels in four lanes:
    // columns[(k * 9 + j) * 4 + ch] = T_c[j][k], columns[(k * 9 + j) * 4 + 3] = 0.
    alignas(16) std::array<float, 4 * kShCoefficients * kShCoefficients> columns{};
    std::array<std::array<float, kShCoefficients>, 3> s{};  // S_c for lightDirection
    glm::dvec3 lightDirection{0.0};
    float capSun = 1.0f;  // the caps' share of the light, kept as the light moves (see Plants' shadows)
    // The ground's light terms (see Ground): g_c, lit_c, the ground's normal and ambient, and
    // E_amb,c at lightDirection's time (what g_c is lit by) [W m^-2].
    std::array<std::array<float, kShCoefficients>, 3> groundShow{}, groundLit{};
    GroundAmbient groundAmbient{};
    glm::vec3 groundAmbientE{0.0f};
    // The ground's part of hide: the guard leaves it out (see Guard).
    std::array<float, kShCoefficients * kShCoefficients> groundHide{};
    glm::vec3 groundNormal{0.0f, 1.0f, 0.0f};
    bool ground = false;
    bool any = false;  // some occluder is near
    // The guard's last scale per channel and the far field it was found for (see Guard).
    mutable bool guardValid = false;
    mutable glm::dvec3 guardScale{1.0};
    mutable ShRgb guardFar;
    bool empty() const { return !any; }
};
NearFieldTransfer nearFieldTransfer(const std::vector<OccluderCap>& caps,
                                    const GroundTerm* ground = nullptr);
// The caps' one share of the light towards `lightDirection` (see Plants' shadows): their
// sunVisibility weighted by what each shows of the light, over the same weights scaled by their
// skyVisibility (see Plants' sky); 1 when none shows any.
double capSunVisibility(const std::vector<OccluderCap>& caps, const glm::dvec3& lightDirection);

// One sample's ground light term in a patch mean (see Patch mean), its weight folded in.
struct GroundLightPart {
    glm::vec3 show{0.0f}, lit{0.0f};  // w a(n) . g_c and w a(n) . lit_c
    glm::vec3 normal{0.0f, 1.0f, 0.0f};
    GroundAmbient ambient{};
};

// The transfer seen through one normal (see Through one normal).
struct NormalTransfer {
    std::array<float, kShCoefficients> hide{};      // h = hide^T a(n), the caps' hide only
    std::array<float, 3 * kShCoefficients> show{};  // s_c = (T_c - hide)^T a(n), [c * 9 + k]
                                                    // (the ground's hide included)
    std::array<float, kShCoefficients> groundHide{};  // the ground's hide^T a(n)
    glm::vec3 light{0.0f};                          // s_c . Y(l), for lightEpoch's light
    float capSun = 1.0f;  // the transfer's (see Plants' shadows): scales the caps' part of light
    glm::vec3 sky{0.0f};  // the ground's a(n) . g_c E_amb,c(n_ground), for its ambient [W m^-2]
    // The ground's part through this normal: a(n) . g_c and a(n) . lit_c (see Ground).
    glm::vec3 groundShow{0.0f}, groundLit{0.0f};
    glm::vec3 groundNormal{0.0f, 1.0f, 0.0f};
    GroundAmbient groundAmbient{};
    bool ground = false;
    // A patch mean's samples' ground light terms, remade with the rest when the light moves
    // (ground is then false; see Patch mean).
    std::shared_ptr<const std::vector<GroundLightPart>> groundParts;
    std::uint32_t lightEpoch = 0;
    bool any = false;
};
// The weighted mean of samples' transfers (weights summing to 1), each made through its own
// normal and brought to one light (see Patch mean); any if one of them is.
NormalTransfer meanNormalTransfer(const NormalTransfer* const* samples, const double* weights,
                                  std::size_t count);
// `transfer` through `normal` (unit); with no transfer, nothing near.
NormalTransfer normalTransfer(const NearFieldTransfer* transfer, const glm::dvec3& normal);
void updateLightTerm(NormalTransfer& transfer, const glm::dvec3& lightDirection,
                     const HemisphereAmbient& ambient, std::uint32_t epoch);
// What the draw reads of a NormalTransfer every frame, in the order ShRgb holds the far field:
// E_c = w_c . L_c + light_c E_light,c + sky_c, w_c = a + h + s_c, wherever (a + h) . L_c >= 0
// (then the guard cannot act); elsewhere the guarded sum, from a (the normal's) and
// h = (a + h) - a.
struct NormalApply {
    // w_c[k] at [k * 4 + c], [k * 4 + 3] = 0: four lanes a coefficient, so the sum vectorises.
    alignas(16) std::array<float, 4 * kShCoefficients> whole{};
    std::array<float, kShCoefficients> aHide{};      // a + h
    glm::vec3 light{0.0f}, sky{0.0f};                // the NormalTransfer's
    std::uint32_t lightEpoch = 0;  // its too, kept here so the check reads only this entry
    bool any = false;
};
NormalApply normalApply(const NormalTransfer& transfer, const glm::dvec3& normal);
// The irradiance at `normal` (the one the transfer was made for) of the far field with the near
// field applied, guarded for that normal, clamped at 0 (as the draw clamps).
glm::vec3 applyNormalTransfer(const NormalApply& transfer, const ShRgb& far,
                              const glm::vec3& normal, const DirectionalLight& light);
// Remakes S for the light direction, and the ground's sky term for the ambient.
void updateLightTerm(NearFieldTransfer& transfer, const glm::dvec3& lightDirection,
                     const HemisphereAmbient& ambient);
// The far field with the near field applied, guarded (see above).
ShRgb applyTransfer(const NearFieldTransfer& transfer, const ShRgb& far,
                    const DirectionalLight& light);
// Everything at once, uncached: the caps of `occluders`, the bands of `horizon` and the
// ground (if given, lit by `light` and `ambient`) at `point` applied to `far`.
ShRgbD applyNearField(const ShRgbD& far, const glm::dvec3& point_m,
                      const std::vector<SphereOccluder>& occluders, const DirectionalLight& light,
                      const std::vector<HorizonWedge>& horizon = {},
                      const GroundTerm* ground = nullptr, const HemisphereAmbient& ambient = {});

// ---- The scene's occluders ---------------------------------------------------------------------
class NearFieldScene {
  public:
    virtual ~NearFieldScene() = default;
    // Occluders whose base lies within radius_m (horizontally) of `point_m`, and those the
    // captures never draw within smallRadius_m, appended to `out`.
    virtual void occludersNear(const glm::dvec3& point_m, double radius_m, double smallRadius_m,
                               std::vector<SphereOccluder>& out) const = 0;
    // The light drawn apart from the ambience at a time of day (the sun, the moon at night).
    virtual DirectionalLight mainLight(double timeOfDay_h) const = 0;
    // The ambient the captures light their surfaces with at a time of day (see Ground).
    virtual HemisphereAmbient ambient(double timeOfDay_h) const = 0;
    // The terrain's height at (x, z) [m] (where a ground point's shading point sits).
    virtual double groundHeight(double x_m, double z_m) const = 0;
    // The wedges of the horizon where terrain within radius_m rises above what the far field
    // holds (see Terrain), appended to `out`; none by default.
    virtual void terrainNear(const glm::dvec3& point_m, double radius_m,
                             std::vector<HorizonWedge>& out) const {
        (void)point_m, (void)radius_m, (void)out;
    }
    // The ground at (x, z); false if the scene has none to offer (then no ground term). With
    // `plane` given (the ground term's samples, on the tangent plane through a foot), the ground
    // is taken to lie there, with the plane's normal, and only its albedo is looked up.
    virtual bool groundAt(double x_m, double z_m, GroundPoint& out,
                          const GroundPoint* plane = nullptr) const {
        (void)x_m, (void)z_m, (void)out, (void)plane;
        return false;
    }
    // Whether a road may reach within radius_m of (x, z) (heights and albedos there depend on
    // it); true unless the scene knows there is none.
    virtual bool roadNear(double x_m, double z_m, double radius_m) const {
        (void)x_m, (void)z_m, (void)radius_m;
        return true;
    }
    // Whether terrain leaves the light (unit direction towards it) visible from `from`, in [0, 1].
    virtual double terrainLightVisibility(const glm::dvec3& from_m, const glm::dvec3& toLight) const {
        (void)from_m, (void)toLight;
        return 1.0;
    }
    // The share of the light (unit direction towards it) that reaches the lit side of a plant's
    // sphere, in [0, 1] (see Plants' shadows); 1 by default.
    virtual double sphereLightVisibility(const glm::dvec3& centre_m, double radius_m,
                                         const glm::dvec3& toLight) const {
        (void)centre_m, (void)radius_m, (void)toLight;
        return 1.0;
    }
    // The share of the sky that a plant's sphere sees past the other plants' spheres, in [0, 1]
    // (see Plants' sky); 1 by default.
    virtual double sphereSkyVisibility(const glm::dvec3& centre_m, double radius_m) const {
        (void)centre_m, (void)radius_m;
        return 1.0;
    }
};

// The ground term at `point_m` (see Ground): the ground within radius_m of its foot, lit by the
// light towards `lightDirection`; `seen` stop the rays from the point (an object's own spheres
// are not among them), `shading` the light on the ground. Nothing (any = false) where the scene
// has no ground or the point is not above it, and for a point seen only through `drawnNormal`
// when that is within kOwnGroundDeg of the ground's normal at the foot (see Through one normal).
GroundTerm groundTerm(const glm::dvec3& point_m, const NearFieldScene& scene,
                      const std::vector<SphereOccluder>& seen,
                      const std::vector<SphereOccluder>& shading, double radius_m,
                      const glm::dvec3& lightDirection, const glm::dvec3* drawnNormal = nullptr);
inline constexpr double kOwnGroundDeg = 10.0;
// For a point seen only through `drawnNormal` (upward): each band keeps only what rises above
// the point's own tangent plane in its wedge's middle azimuth (what lies below it is outside
// the normal's hemisphere, where order-2 SH would only ring: the uphill side of a gully's wall).
void belowTangentPlaneOut(const glm::dvec3& drawnNormal, std::vector<HorizonWedge>& horizon);
// sum_i w_i terms_i (the normal renormalised); any if one of them is.
GroundTerm blendGroundTerms(const GroundTerm* const* terms, const double* weights, int count);

// The generated world's plants (Vegetation::spheres, scaled and placed).
class WorldNearFieldScene final : public NearFieldScene {
  public:
    explicit WorldNearFieldScene(const World& world) : world_(world), albedo_(world) {}
    void occludersNear(const glm::dvec3& point_m, double radius_m, double smallRadius_m,
                       std::vector<SphereOccluder>& out) const override;
    DirectionalLight mainLight(double timeOfDay_h) const override;
    HemisphereAmbient ambient(double timeOfDay_h) const override;
    double groundHeight(double x_m, double z_m) const override;
    void terrainNear(const glm::dvec3& point_m, double radius_m,
                     std::vector<HorizonWedge>& out) const override;
    // The terrain's height, normal and albedo as the patches draw them near the camera.
    bool groundAt(double x_m, double z_m, GroundPoint& out,
                  const GroundPoint* plane = nullptr) const override;
    bool roadNear(double x_m, double z_m, double radius_m) const override;
    // Marched along the light out to kShadowReach_m, as far as the main view's shadows reach.
    double terrainLightVisibility(const glm::dvec3& from_m,
                                  const glm::dvec3& toLight) const override;
    // The terrain and the other plants' spheres along the light (out to where the light's line
    // is kPlantTop_m above the ground) at five points of the lit side.
    double sphereLightVisibility(const glm::dvec3& centre_m, double radius_m,
                                 const glm::dvec3& toLight) const override;
    // The other plants' spheres within kSkyReach_m, at nine points of the sphere.
    double sphereSkyVisibility(const glm::dvec3& centre_m, double radius_m) const override;
    static constexpr double kSkyReach_m = 16.0;  // plants farther are in the far field's sky
    static constexpr double kMinSkyVisibility = 0.02;  // keeps a cap's light term well defined
    static constexpr double kPlantTop_m = 20.0;  // no plant of the world is taller
    static constexpr double kMaxCasterReach_m = 64.0;  // plants farther along the light are left out
    static constexpr int kWedges = 8;
    static constexpr double kShadowReach_m = 200.0;

  private:
    const World& world_;
    TerrainAlbedo albedo_;
};

// The near field at points, with the per-point cache: what a method's decorator asks.
class NearField {
  public:
    NearField(const NearFieldScene& scene, const NearFieldSettings& settings);
    const NearFieldSettings& settings() const { return settings_; }
    void setTimeOfDay(double timeOfDay_h);
    // Where the camera is (see NearFieldSettings::latticeRange_m); until told, every object
    // blends the lattice.
    void setViewer(const glm::dvec3& camera_m);
    // The far field at `point_m` with the near field applied, cached by the point. With
    // selfRadius_m > 0 an object's own spheres (on its axis: centres within selfRadius_m
    // horizontally of the point) are left out.
    ShRgb apply(const ShRgb& far, const glm::dvec3& point_m, double selfRadius_m = 0.0) const;
    // The same at height_m above the ground at (x, z), cached by (x, z): the ground's height is
    // looked up only the first time (so every call on one NearField passes the same height_m).
    ShRgb applyAbove(const ShRgb& far, double x_m, double z_m, double height_m,
                     double selfRadius_m = 0.0) const;
    // The same for many points at once (corners: no self radius), in place.
    void applyMany(std::size_t count, ShRgb* inOut, const glm::dvec3* points_m) const;
    void applyAboveMany(std::size_t count, ShRgb* inOut, const double* x_m, const double* z_m,
                        double height_m, double selfRadius_m = 0.0) const;
    // The irradiance at fixed points for their normals (corners, road vertices: a point always
    // comes with the same normal), clamped at 0, from the far field there (see Through one
    // normal); cached by the point.
    // With `weights`, each point's near field is faded in by its weight (0: the far field's
    // irradiance, and the point is not asked of the cache). With `patch_m`, a point of
    // patch_m[i] > 0 is a terrain corner of that patch size and takes the patch mean (see Patch
    // mean) if the settings ask for it.
    void irradianceMany(std::size_t count, const ShRgb* far, const glm::dvec3* points_m,
                        const glm::dvec3* normals, glm::vec3* out,
                        const double* weights = nullptr, const double* patch_m = nullptr) const;
    std::size_t cachedPoints() const;
    std::size_t cacheBytes() const;
    // Wall time spent in apply and the points it answered since the last resetCounters.
    double seconds() const;
    std::size_t points() const;
    // Of those, the points whose transfer was built (not in the cache) and the time it took.
    std::size_t builds() const;
    double buildSeconds() const;
    void resetCounters();

  private:
    // Null when nothing is near the point. With `drawnNormal`, the point is seen through that
    // normal alone (see groundTerm).
    std::unique_ptr<NearFieldTransfer> build(const glm::dvec3& point_m, double selfRadius_m,
                                             const GroundTerm* objectGroundTerm = nullptr,
                                             const glm::dvec3* drawnNormal = nullptr) const;
    // The batch's points not in the object cache, built on every thread and put in (a lone
    // one is left to applyLocked).
    void buildObjects(std::size_t count, const std::array<float, 4>* keys,
                      const glm::dvec3* points_m, double selfRadius_m) const;
    ShRgb applyKeyed(const ShRgb& far, const std::array<float, 4>& key,
                     const std::function<glm::dvec3()>& point, double selfRadius_m) const;
    // The same with the lock held and without timing.
    ShRgb applyLocked(const ShRgb& far, const std::array<float, 4>& key,
                      const std::function<glm::dvec3()>& point, double selfRadius_m) const;
    // The plants near a point (all of them: build leaves an object's own out of its caps), each
    // with its share of the light.
    std::vector<SphereOccluder> occluders(const glm::dvec3& point_m) const;
    // Fills the spheres' sunVisibility from the scene, kept per sphere for the light's epoch.
    void sunVisibilities(std::vector<SphereOccluder>& spheres) const;
    // Fills the spheres' skyVisibility from the scene, kept per sphere (see Plants' sky).
    void skyVisibilities(std::vector<SphereOccluder>& spheres) const;
    // An object's ground term: the B-spline blend of the lattice's (see Ground), cached.
    GroundTerm objectGround(const glm::dvec3& point_m) const;
    // The nine lattice points an object's ground term blends: their keys, weights and
    // (x, lift above the ground, z).
    void latticeOf(const glm::dvec3& point_m, std::array<float, 4> keys[9], double weights[9],
                   glm::dvec3 points[9]) const;
    GroundTerm latticeTerm(const glm::dvec3& latticePoint) const;
    // A ground sample of a patch mean at (x, z): the near field kShadingHeight_m above the
    // ground there through the ground's normal, brought to the current light.
    NormalTransfer groundSample(double x_m, double z_m) const;

    const NearFieldScene& scene_;
    NearFieldSettings settings_;
    DirectionalLight light_;
    HemisphereAmbient ambient_;  // the scene's, for the light of lightEpoch_
    using Key = std::array<float, 4>;  // point, self radius
    struct KeyHash {
        std::size_t operator()(const Key& k) const;
    };
    mutable std::mutex mutex_;
    // Every entry carries the use clock's reading when it was last asked (see cacheEntries).
    mutable std::uint64_t uses_ = 0;
    struct Cached {
        std::unique_ptr<NearFieldTransfer> transfer;  // null: nothing near
        std::uint64_t used = 0;
    };
    struct CachedGround {
        GroundTerm term;
        std::uint64_t used = 0;
    };
    mutable tsl::hopscotch_map<Key, Cached, KeyHash> cache_;
    mutable tsl::hopscotch_map<Key, CachedGround, KeyHash> groundCache_;  // the objects' lattice
    // The patch means' ground samples (see Patch mean), emptied when it holds cacheEntries.
    mutable tsl::hopscotch_map<Key, NormalTransfer, KeyHash> sampleCache_;
    // Through one normal: the point's index in the vectors below. Small slots keep the map in
    // cache; the transfers follow in the order the draw first asked.
    mutable tsl::hopscotch_map<Key, std::uint32_t, KeyHash> normalCache_;
    mutable std::vector<NormalTransfer> normalTransfers_;  // read when the light moves
    mutable std::vector<NormalApply> normalApplies_;       // read every frame
    mutable std::vector<std::uint64_t> normalUsed_;
    // Each drops the half of its cache used least recently (all of it if no use is older).
    void evictObjects() const;
    void evictGround() const;
    void evictNormals() const;
    mutable std::vector<Key> batchKeys_;                   // the batch's, then a sequence's
    mutable std::vector<std::uint32_t> batchIndex_;
    mutable std::vector<std::uint32_t> batchAt_;  // each point's entry in the batch
    mutable std::vector<std::size_t> batchMissing_, batchUnique_;  // the points to build
    // The draw asks its batches (corners, road vertices) in nearly the same order every frame:
    // the last few batches' keys and indices are walked alongside, and the map is asked only
    // where the order changed (a random probe of the map misses the processor's caches).
    struct Sequence {
        Key first{};  // the batch's first point (asked of the cache or not)
        std::vector<Key> keys;
        std::vector<std::uint32_t> index;
        std::uint64_t used = 0;  // the use clock when this batch was last asked
        std::uint32_t lightEpoch = 0;  // the light its entries' light terms were brought to
    };
    static constexpr int kSequences = 4;
    mutable std::array<Sequence, kSequences> sequences_;
    // A new entry of the through-one-normal cache, marked used now; its index.
    std::uint32_t addNormalEntry(const Key& key, const NormalTransfer& transfer,
                                 const NormalApply& apply) const;
    std::uint32_t lightEpoch_ = 1;  // counts the light's moves of more than 0.5 degrees
    // A per-sphere share (of the light or of the sky) by centre and radius: emptied when its
    // epoch moves on or when it holds kShareEntries.
    struct ShareCache {
        std::mutex mutex;
        tsl::hopscotch_map<Key, float, KeyHash> shares;
        std::uint32_t epoch = 0;
    };
    static constexpr std::size_t kShareEntries = 1u << 17;
    // Fills each sphere's `share` member from the cache, asking `compute(centre, radius)` for the
    // spheres it lacks; a share not finite counts as 1. Entries are kept for `epoch`.
    void fillShares(ShareCache& cache, std::uint32_t epoch, std::vector<SphereOccluder>& spheres,
                    double SphereOccluder::*share,
                    const std::function<double(const glm::dvec3&, double)>& compute) const;
    // The light's shares for lightEpoch_ (see Plants' shadows); the sky's, kept for the run
    // (see Plants' sky).
    mutable ShareCache sunShares_, skyShares_;
    glm::dvec3 viewer_{0.0};
    bool viewerKnown_ = false;
    // Whether an object built at `point_m` now blends the lattice (see latticeRange_m).
    bool blendsLattice(const glm::dvec3& point_m) const;
    glm::dvec3 epochLight_{0.0};
    mutable double seconds_ = 0.0, buildSeconds_ = 0.0;
    mutable std::size_t points_ = 0, builds_ = 0;
    mutable std::size_t bytes_ = 0, normalBytes_ = 0, groundBytes_ = 0;  // the caches', structure included
};

// A capturing method with the near field: its captures leave the near plants out
// (CaptureSettings::nearField, CubeCapture::captureFar) and every shading point gets them back.
// Objects (shAt) within objectRange_m of the camera take theirs at kShadingHeight_m above their
// ground point without their own spheres; terrain corners (cornerShAt) within cornerRange_m at
// kShadingHeight_m above the corner. Both fade out over the last kNearFade of their range.
class NearFieldMethod final : public AmbienceMethod {
  public:
    NearFieldMethod(std::unique_ptr<AmbienceMethod> far, std::unique_ptr<NearFieldScene> scene,
                    const NearFieldSettings& settings);
    ~NearFieldMethod() override;

    // The method whose far field this one completes.
    AmbienceMethod& far() { return *far_; }
    const AmbienceMethod& far() const { return *far_; }

    std::string methodName() const override { return far_->methodName(); }
    void predictStage(const glm::dvec3& cameraPosition_m, const glm::dvec3& cameraVelocity_mps,
                      double timeOfDay_h, double dt_s) override;
    // The captures' light's lattice for this frame (see Captures' light), then the far method's.
    void captureStage() override;
    void storeStage() override { far_->storeStage(); }
    ShRgb shAt(double x_m, double z_m) const override;
    // A frame's objects at once: one lock and one timing for the lot.
    void shAt(std::size_t count, const double* x_m, const double* z_m, ShRgb* out) const override;
    ShRgb cornerShAt(double x_m, double z_m) const override;
    void cornerShAt(std::size_t count, const double* x_m, const double* z_m,
                    ShRgb* out) const override;
    ShRgb cornerShAtPoint(const glm::dvec3& point_m) const override;
    void cornerShAtPoints(std::size_t count, const glm::dvec3* points_m, ShRgb* out) const override;
    void cornerIrradianceAtPoints(std::size_t count, const glm::dvec3* points_m,
                                  const glm::dvec3* normals, glm::vec3* out,
                                  const double* patch_m = nullptr) const override;
    void irradianceFromFar(std::size_t count, const glm::dvec3* points_m,
                           const glm::dvec3* normals, const ShRgb* far, glm::vec3* out,
                           const double* patch_m = nullptr) const override;
    double farCaptureRadius_m() const override;
    const SurfaceLight* captureSurfaceLight() const override {
        return far_->captureSurfaceLight();
    }
    // An empty override gives the captures the light they had (see Captures' light).
    void overrideCaptureLight(CaptureLightOverride light) override;
    void noteLookups(std::size_t count, const double* x_m, const double* z_m) override {
        far_->noteLookups(count, x_m, z_m);
    }
    bool wantsLookups() const override { return far_->wantsLookups(); }
    bool terrainSkyDetail() const override { return skyDetail_; }
    // The setting vertexAmbient_m while the near field is enabled, else 0.
    double terrainVertexRange_m() const override;
    // The setting vertexPointsPerFrame.
    int terrainVertexPointsPerFrame() const override;
    MethodStatistics methodStatistics() const override;
    // None: the error budget's ideal volume (fresh full captures at the lattice points) is not
    // what this method interpolates (far captures and the near field at the point), so its
    // spacing and schedule terms are reported as one (lighting/ReferenceOracle.h).
    IdealSupport idealSupport(double x_m, double z_m) const override {
        (void)x_m, (void)z_m;
        return {};
    }
    // An object's own spheres sit on its axis, at its ground point: those within this
    // (horizontally) are its own.
    static constexpr double kSelfRadius_m = 0.05;

  private:
    std::unique_ptr<AmbienceMethod> far_;
    std::unique_ptr<NearFieldScene> scene_;
    std::unique_ptr<NearField> near_;
    // The captures' light with the near field (when captureLightRange_m > 0), installed as the
    // far method's capture-light override (see Captures' light).
    class CaptureLight;
    std::unique_ptr<CaptureLight> captureLight_;
    double timeOfDay_h_ = 12.0;  // of the latest predictStage
    glm::dvec3 camera_m_{0.0};  // of the latest predictStage
    bool skyDetail_ = false;    // settings: terrain and vertexDetail
    // The near field's weight at (x, z) for a range (objectRange_m, cornerRange_m; see Range).
    double weight(double x_m, double z_m, double range_m) const;
    // The batches' points of weight > 0 with their far SH, into the scratch below; then the
    // near field's answers faded into `out` at their indices.
    void gather(std::size_t count, const double* x_m, const double* z_m, const ShRgb* far,
                double range_m) const;
    void scatter(ShRgb* out) const;
    mutable std::vector<std::size_t> nearIndex_;
    mutable std::vector<double> nearX_, nearZ_, nearWeight_, nearPatch_;
    mutable std::vector<ShRgb> nearSh_;
};

}  // namespace amb
