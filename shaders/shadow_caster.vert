#version 450 core
#extension GL_GOOGLE_include_directive : require
// shadow_caster.vert — depth of the shadow casters seen from the main light
// (app/render/ShadowMap.h): terrain patches and road pieces (uOrigin + position) or instanced
// objects placed as object.vert places them; uViewProj is the cascade's light matrix.
#include "common.glsl"

layout(location = 0) in vec3 aPosition;
layout(location = 3) in vec4 iPositionScale;  // objects: camera-relative base [m], scale
layout(location = 4) in vec2 iRotationSet;    // objects: rotation about +Y [rad]

uniform vec3 uOrigin;   // terrain: patch origin, camera-relative [m]
uniform int uInstanced; // 1: an instanced object

void main() {
    vec3 relPos = uOrigin + aPosition;
    if (uInstanced != 0) {
        float c = cos(iRotationSet.x), s = sin(iRotationSet.x);
        mat3 rot = mat3(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
        relPos = iPositionScale.xyz + rot * (aPosition * iPositionScale.w);
    }
    gl_Position = uViewProj * vec4(relPos, 1.0);
}
