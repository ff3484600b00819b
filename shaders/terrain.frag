#version 450 core
#extension GL_GOOGLE_include_directive : require
// terrain.frag — Lambertian terrain lit by the main light and the ambient slot of docs/ARCHITECTURE.md
// ("Terrain and objects"): one ambient irradiance per patch corner, bilinear across the patch
// (thesis 8.6); a road piece's comes per vertex instead, and so does a near patch's when the
// ambient asks for it (nearField.vertexAmbient_m). The main light is shadowed (shadow.glsl).
#include "common.glsl"
#include "shadow.glsl"

// Corner irradiance (rgb), corners (x0,z0), (x1,z0), (x0,z1), (x1,z1).
uniform vec4 uCornerIrradiance[4];
uniform int uVertexIrradiance;  // 1: the ambient is vIrradiance (road pieces, near terrain)
uniform int uRoad;              // 1: a road piece (surface kind 2), else terrain (kind 1)
// 1: the corners' ambient is scaled by the vertex's sky detail (world/TerrainPatch.h skyDetail:
// the terrain's own visibility V between corners, gullies, against Vc of the corners); the main
// view with the near field. What the walls hide comes back as their light: albedo times the
// ambient and the main light on open ground.
uniform int uSkyDetail;

in vec3 vNormal;
in vec3 vAlbedo;
in vec2 vPatchUv;
in vec3 vIrradiance;
in vec2 vSkyDetail;
in vec4 vFog;
in vec3 vRelPos;

layout(location = 0) out vec4 oColor;

void main() {
    vec3 e0 = mix(uCornerIrradiance[0].rgb, uCornerIrradiance[1].rgb, vPatchUv.x);
    vec3 e1 = mix(uCornerIrradiance[2].rgb, uCornerIrradiance[3].rgb, vPatchUv.x);
    vec3 ambient = uVertexIrradiance != 0 ? vIrradiance : mix(e0, e1, vPatchUv.y);
    if (uVertexIrradiance == 0 && uSkyDetail != 0) {
        vec3 open = uLightIrradiance.rgb * max(uLightDir.y, 0.0);
        vec3 b = vAlbedo * (ambient + open) / max(ambient, vec3(1e-6));
        vec2 v = clamp(vSkyDetail, 0.0, 1.0);
        ambient *= (v.x + (1.0 - v.x) * b) / max(v.y + (1.0 - v.y) * b, vec3(1e-6));
    }
    vec3 n = normalize(vNormal);
    if (writeAov(ambient, n, vAlbedo, uRoad != 0 ? 2.0 : 1.0, oColor)) return;
    float shadow = shadowFactor(vRelPos, n);
    oColor = vec4(applyFog(shadeLambert(vAlbedo, n, ambient, shadow), vFog), 0.0);
}
