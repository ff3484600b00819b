#version 450 core
#extension GL_GOOGLE_include_directive : require
// terrain.vert — one terrain patch (or road piece): vertices relative to the patch origin; a road
// piece also brings its ambient irradiance per vertex.
#include "common.glsl"

layout(location = 0) in vec3 aPosition;  // metres, relative to the patch origin
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aAlbedo;
layout(location = 5) in vec3 aIrradiance;  // road pieces, near terrain (uVertexIrradiance)
layout(location = 6) in vec2 aSkyDetail;  // terrain patches only (uSkyDetail): V, Vc

uniform vec3 uOrigin;     // patch origin, camera-relative [m]
uniform vec4 uPatchRect;  // xy: corner (x0, z0) relative to the origin [m]; zw: 1 / size [1/m]

out vec3 vNormal;
out vec3 vAlbedo;
out vec2 vPatchUv;  // bilinear weights of the four patch corners
out vec3 vIrradiance;
out vec2 vSkyDetail;
out vec4 vFog;
out vec3 vRelPos;  // camera-relative position [m], for the shadow lookup

void main() {
    vec3 relPos = uOrigin + aPosition;
    vNormal = aNormal;
    vAlbedo = aAlbedo;
    vIrradiance = aIrradiance;
    vSkyDetail = aSkyDetail;
    vPatchUv = clamp((aPosition.xz - uPatchRect.xy) * uPatchRect.zw, 0.0, 1.0);
    vFog = fogAt(relPos);
    vRelPos = relPos;
    gl_Position = uViewProj * vec4(relPos, 1.0);
}
