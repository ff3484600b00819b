#version 450 core
// tonemap.frag — HDR to display: exposure, then the ACES filmic curve fitted by Narkowicz (2015,
// "ACES Filmic Tone Mapping Curve"), then the sRGB transfer function (IEC 61966-2-1).
layout(binding = 0) uniform sampler2D uHdr;
uniform float uExposure;

in vec2 vNdc;
layout(location = 0) out vec4 oColor;

vec3 acesFilm(vec3 x) {
    const float a = 2.51, b = 0.03, c = 2.43, d = 0.59, e = 0.14;
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), 0.0, 1.0);
}

vec3 srgbEncode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}

void main() {
    vec3 hdr = texelFetch(uHdr, ivec2(gl_FragCoord.xy), 0).rgb;
    oColor = vec4(srgbEncode(acesFilm(hdr * uExposure)), 1.0);
}
