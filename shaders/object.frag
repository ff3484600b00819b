#version 450 core
#extension GL_GOOGLE_include_directive : require
// object.frag — per-pixel SH ambient with the world normal (thesis 7.7, 9.4) plus the main light, shadowed
// (shadow.glsl).
#include "common.glsl"
#include "ambient.glsl"
#include "shadow.glsl"

in vec3 vNormal;
in vec3 vAlbedo;
in vec4 vFog;
in vec3 vRelPos;
in float vAmbientShare;  // a trunk under its crown: what the crown leaves of the ambient
flat in uint vAmbientSet;
uniform int uSimplified;  // 1: a proxy or far mesh (surface kind 4 in the witnesses' outputs)

layout(location = 0) out vec4 oColor;

void main() {
    vec3 n = normalize(vNormal);
    if (!gl_FrontFacing) n = -n;  // thin crowns and leaves are seen from both sides
    vec3 ambient = ambientIrradiance(vAmbientSet, n) * vAmbientShare;
    if (writeAov(ambient, n, vAlbedo, uSimplified != 0 ? 4.0 : 3.0, oColor)) return;
    float shadow = shadowFactor(vRelPos, n);
    oColor = vec4(applyFog(shadeLambert(vAlbedo, n, ambient, shadow), vFog), 0.0);
}
