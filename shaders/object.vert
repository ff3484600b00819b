#version 450 core
#extension GL_GOOGLE_include_directive : require
// object.vert — instanced static objects (trees, bushes, rocks): a unit mesh per kind, placed by
// a per-instance camera-relative position, scale and rotation about +Y.
#include "common.glsl"

layout(location = 0) in vec3 aPosition;  // metres, mesh origin at the trunk base
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aAlbedo;
layout(location = 3) in vec4 iPositionScale;  // xyz: camera-relative base [m]; w: scale
layout(location = 4) in vec2 iRotationSet;    // x: rotation about +Y [rad]; y: ambient set index
layout(location = 7) in float aOcclusion;     // the share of the ambient the plant's crown hides

out vec3 vNormal;
out vec3 vAlbedo;
out vec4 vFog;
out vec3 vRelPos;  // camera-relative position [m], for the shadow lookup
out float vAmbientShare;
flat out uint vAmbientSet;

void main() {
    float c = cos(iRotationSet.x), s = sin(iRotationSet.x);
    mat3 rot = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
    vec3 relPos = iPositionScale.xyz + rot * (aPosition * iPositionScale.w);
    vNormal = rot * aNormal;
    vAlbedo = aAlbedo;
    vAmbientSet = uint(iRotationSet.y + 0.5);
    vAmbientShare = 1.0 - aOcclusion;
    vFog = fogAt(relPos);
    vRelPos = relPos;
    gl_Position = uViewProj * vec4(relPos, 1.0);
}
