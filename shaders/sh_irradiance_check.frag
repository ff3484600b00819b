// sh_irradiance_check.frag — compiles sh_irradiance.glsl at build time (it is an include file and
// is not validated on its own). Shades a surface with the SH irradiance of its normal.
#version 450 core
#extension GL_GOOGLE_include_directive : require
#include "sh_irradiance.glsl"

layout(location = 0) in vec3 vNormal;
layout(location = 0) out vec4 fragColor;

uniform mat4 uShR;
uniform mat4 uShG;
uniform mat4 uShB;

void main() {
    fragColor = vec4(shIrradiance(uShR, uShG, uShB, normalize(vNormal)), 1.0);
}
