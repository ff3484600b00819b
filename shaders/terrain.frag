#version 450 core
#extension GL_GOOGLE_include_directive : require
// terrain.frag — Lambertian terrain lit by the main light and the ambient slot of docs/ARCHITECTURE.md
// ("Terrain and objects"): one ambient irradiance per patch corner, bilinear across the patch
// (thesis 8.6); a road piece's comes per vertex instead. The main light is shadowed (shadow.glsl).
#include "common.glsl"
#include "shadow.glsl"

// Corner irradiance (rgb), corners (x0,z0), (x1,z0), (x0,z1), (x1,z1).
uniform vec4 uCornerIrradiance[4];
uniform int uVertexIrradiance;  // 1: the ambient is vIrradiance (road pieces)

in vec3 vNormal;
in vec3 vAlbedo;
in vec2 vPatchUv;
in vec3 vIrradiance;
in vec4 vFog;
in vec3 vRelPos;

layout(location = 0) out vec4 oColor;

void main() {
    vec3 e0 = mix(uCornerIrradiance[0].rgb, uCornerIrradiance[1].rgb, vPatchUv.x);
    vec3 e1 = mix(uCornerIrradiance[2].rgb, uCornerIrradiance[3].rgb, vPatchUv.x);
    vec3 ambient = uVertexIrradiance != 0 ? vIrradiance : mix(e0, e1, vPatchUv.y);
    vec3 n = normalize(vNormal);
    if (writeAov(ambient, n, vAlbedo, uVertexIrradiance != 0 ? 2.0 : 1.0, oColor)) return;
    float shadow = shadowFactor(vRelPos, n);
    oColor = vec4(applyFog(shadeLambert(vAlbedo, n, ambient, shadow), vFog), 0.0);
}
