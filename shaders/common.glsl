// common.glsl — frame constants shared by every program, and the small functions they share.
// Positions reaching the GPU are camera-relative (world - camera, float), see Conventions.h.
#ifndef AMB_COMMON_GLSL
#define AMB_COMMON_GLSL

#include "conventions.glsl"  // PI, LUMINANCE_WEIGHTS, GROUND_ALBEDO

// One block per frame (or per capture face), std140, binding 0. Mirrors amb::FrameConstants.
layout(std140, binding = 0) uniform FrameConstants {
    mat4 uViewProj;          // camera-relative world -> clip (reversed Z, depth 1 at near)
    mat4 uInvViewProj;       // clip -> camera-relative world
    vec4 uLightDir;          // xyz: unit direction towards the main light (sun by day, moon)
    vec4 uLightIrradiance;   // rgb: irradiance on a surface facing the light
    vec4 uSunDisc;           // rgb: radiance of the sun disc; w: cos(angular radius), > 1 = off
    vec4 uFog;               // x: extinction per metre; y: 1 when capturing (alpha marks sky);
                             // z: output (0 shaded; 1 ambient irradiance, 2 world normal, 3 albedo:
                             // the screen witnesses' AOVs, alpha = surface kind, 0 = sky;
                             // 4 the ambient view)
    vec4 uSunAzimuth;        // xz: unit horizontal direction of the sun's azimuth
    vec4 uFogToward;         // rgb: horizon sky radiance towards the sun's azimuth
    vec4 uFogAway;           // rgb: horizon sky radiance away from it
};

layout(binding = 0) uniform sampler2D uSkyTexture;  // equirect sky radiance, row 0 = zenith

// Equirectangular lookup: u = azimuth from -Z (north) through +X (east), v = polar angle / pi.
vec2 skyUv(vec3 d) {
    float u = atan(d.x, -d.z) / (2.0 * PI) + 0.5;
    float v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2(u, v);
}

vec3 skyRadiance(vec3 d) { return textureLod(uSkyTexture, skyUv(d), 0.0).rgb; }

// Aerial perspective, evaluated per vertex: the surface radiance fades with distance
// (Beer-Lambert, one extinction coefficient) towards the horizon sky radiance in the vertex's
// azimuth, taken as a blend of the horizon towards and away from the sun (uSunAzimuth.xyz: unit
// horizontal direction of the sun's azimuth; uFogToward/uFogAway set on the CPU from the sky model,
// so no per-vertex trigonometry). It also hides the far edge of the terrain LOD. Returns the
// in-scattered radiance in rgb and the transmittance in a.
vec4 fogAt(vec3 relPos) {
    float dist = length(relPos);
    vec2 dirXZ = relPos.xz / max(length(relPos.xz), 1e-6);
    float towardSun = 0.5 + 0.5 * dot(dirXZ, uSunAzimuth.xz);
    vec3 horizon = mix(uFogAway.rgb, uFogToward.rgb, towardSun * towardSun);
    return vec4(horizon, exp(-uFog.x * dist));
}

vec3 applyFog(vec3 radiance, vec4 fog) { return mix(fog.rgb, radiance, fog.a); }

// Lambertian surface: radiance = albedo / pi * (ambient irradiance + direct irradiance), the
// direct term times `shadow`, the fraction of the main light that reaches the surface
// (shadow.glsl); the ambient lights what the main light does not.
vec3 shadeLambert(vec3 albedo, vec3 n, vec3 ambientIrradiance, float shadow) {
    vec3 direct = uLightIrradiance.rgb * (max(dot(n, uLightDir.xyz), 0.0) * shadow);
    return albedo / PI * (max(ambientIrradiance, vec3(0.0)) + direct);
}

// The screen witnesses' outputs (app/render/Renderer.h, RenderOutput): instead of the shaded colour,
// the ambient irradiance as the draw applies it, the world normal or the albedo; alpha names
// the surface (1 terrain, 2 road, 3 object, 4 object drawn with a simplified mesh). Returns false
// for the shaded colour. Output 4 (the ambient view) is the ambient term alone, as the radiance
// of a white surface: ambient irradiance / pi, tone mapped like the shaded view.
bool writeAov(vec3 ambientIrradiance, vec3 n, vec3 albedo, float kind, out vec4 color) {
    if (uFog.z < 0.5) return false;
    if (uFog.z > 3.5) {  // the ambient view: a white Lambertian surface lit by the ambient alone
        color = vec4(max(ambientIrradiance, vec3(0.0)) / PI, 0.0);
        return true;
    }
    color = vec4(uFog.z < 1.5 ? ambientIrradiance : (uFog.z < 2.5 ? n : albedo), kind);
    return true;
}

#endif  // AMB_COMMON_GLSL
