#version 450 core
#extension GL_GOOGLE_include_directive : require
// sky.frag — the world's sky model (baked into the equirect texture each time the time of day
// changes) and the sun disc, drawn behind everything. In a capture the disc is off (its energy
// is added to the texel holding the sun direction on the CPU, so a 16-texel face keeps it) and
// alpha = 1 marks sky texels.
#include "common.glsl"

in vec2 vNdc;
layout(location = 0) out vec4 oColor;

void main() {
    if (uFog.z > 0.5 && uFog.z < 3.5) {  // screen witness outputs: alpha 0 marks the sky
        oColor = vec4(0.0);
        return;
    }
    // Two points on the pixel's ray (reversed Z: depth 1 = near plane; depth 0 is at infinity).
    vec4 mid = uInvViewProj * vec4(vNdc, 0.5, 1.0);
    vec4 near = uInvViewProj * vec4(vNdc, 1.0, 1.0);
    vec3 dir = normalize(mid.xyz / mid.w - near.xyz / near.w);
    vec3 radiance = skyRadiance(dir);
    if (dot(dir, normalize(uLightDir.xyz)) > uSunDisc.w) radiance += uSunDisc.rgb;
    oColor = vec4(radiance, uFog.y);
}
