// shadow.glsl — the main light's shadow (app/render/ShadowMap.h): cascaded depth maps seen from
// the light, one layer per cascade, each sphere-fitted and texel-snapped. Each receiver reads
// one map, picked before any texture is read (a software rasteriser runs every branch of a
// shader for the whole block of pixels, so each lookup tried costs every pixel its sample): the
// car's own map where it covers the receiver (it holds the static casters around the car too),
// else the first cascade whose map covers it, else the far terrain cascade. The receiver's
// position moves along its normal by the map's normal offset and nearer the light by its depth
// bias (against acne), and the comparison is filtered over PCF taps (each a bilinear 2 x 2
// comparison). Without the far cascade the last cascade fades to lit over its outer tenth; with
// it, that band hands over to the far cascade in a fixed dither, and the far cascade fades to
// lit at its own edge. Mirrors amb::ShadowConstants; binding 2 (block) and texture unit 2.
#ifndef AMB_SHADOW_GLSL
#define AMB_SHADOW_GLSL

const int MAX_SHADOW_CASCADES = 4;
const int CAR_SHADOW_SLOT = MAX_SHADOW_CASCADES;
const int FAR_SHADOW_SLOT = MAX_SHADOW_CASCADES + 1;

layout(std140, binding = 2) uniform ShadowConstants {
    mat4 uShadowMatrix[MAX_SHADOW_CASCADES + 2];  // camera-relative -> (u, v, depth, 1) in [0, 1]
    vec4 uShadowOffset[MAX_SHADOW_CASCADES + 2];  // x: normal offset [m]; y: depth bias; z: layer;
                                                  // w: share of the layer's side used
    vec4 uShadowParams;  // x: cascades (0: none); y: 1 / layer size; z: PCF taps per side;
                         // w: 1 with the car's own map (slot CAR_SHADOW_SLOT)
    vec4 uShadowFar;     // x: 1 with the far terrain cascade (slot FAR_SHADOW_SLOT)
};

layout(binding = 2) uniform sampler2DArrayShadow uShadowMap;

// Where slot k's map puts relPos (normal n): (u, v, depth) over the part of the layer the map
// uses, and in w how far inside the map's margin it lies, in u (< 0: the map does not cover it).
vec4 shadowCoord(int k, vec3 relPos, vec3 n) {
    vec3 p = (uShadowMatrix[k] * vec4(relPos + n * uShadowOffset[k].x, 1.0)).xyz;
    vec2 edge = min(p.xy, 1.0 - p.xy);
    float inside = min(edge.x, edge.y) - 2.0 * uShadowParams.y / uShadowOffset[k].w;
    return vec4(p, p.z > 1.0 ? -1.0 : inside);
}

// Light reaching the point at `c` (shadowCoord) of the map with offsets `o`: 1 lit, 0 shadowed.
float shadowTaps(vec4 c, vec4 o) {
    float ref = c.z - o.y;
    int taps = int(uShadowParams.z + 0.5);
    float lit = 0.0;
    float start = -0.5 * float(taps - 1);
    for (int j = 0; j < taps; ++j)
        for (int i = 0; i < taps; ++i) {
            vec2 uv = c.xy * o.w + vec2(start + float(i), start + float(j)) * uShadowParams.y;
            lit += texture(uShadowMap, vec4(uv, o.z, ref));
        }
    return lit / float(taps * taps);
}

// Fraction of the main light reaching camera-relative position `relPos` with unit normal `n`
// (1 lit, 0 in shadow), from the one map picked as above. Surfaces facing away from the light
// get no direct light anyway. The slots are tried with constant indices (a software rasteriser
// gathers dynamically indexed blocks).
float shadowFactor(vec3 relPos, vec3 n) {
    int count = int(uShadowParams.x + 0.5);
    if (count == 0 || dot(n, uLightDir.xyz) <= 0.0) return 1.0;
    bool far = uShadowFar.x > 0.5;
    vec4 c = vec4(-1.0), o = vec4(0.0);
    float fade = 0.0;  // > 0: the fade band of the last cascade (or the far one), its width
    if (uShadowParams.w > 0.5) {
        c = shadowCoord(CAR_SHADOW_SLOT, relPos, n);
        o = uShadowOffset[CAR_SHADOW_SLOT];
    }
    if (c.w < 0.0) {
        c = shadowCoord(0, relPos, n);
        o = uShadowOffset[0];
        fade = count == 1 ? 0.05 : 0.0;
    }
    if (c.w < 0.0 && count > 1) {
        c = shadowCoord(1, relPos, n);
        o = uShadowOffset[1];
        fade = count == 2 ? 0.05 : 0.0;
    }
    if (c.w < 0.0 && count > 2) {
        c = shadowCoord(2, relPos, n);
        o = uShadowOffset[2];
        fade = count == 3 ? 0.05 : 0.0;
    }
    if (c.w < 0.0 && count > 3) {
        c = shadowCoord(3, relPos, n);
        o = uShadowOffset[3];
        fade = 0.05;
    }
    // The last cascade's outer band: handed over to the far cascade in a fixed dither (one
    // sample a pixel still), or faded to lit.
    if (far && fade > 0.0 && c.w >= 0.0) {
        vec2 q = floor(gl_FragCoord.xy);
        float h = fract(52.9829189 * fract(dot(q, vec2(0.06711056, 0.00583715))));
        if (h >= c.w / fade) c = vec4(-1.0);
        fade = 0.0;
    }
    if (c.w < 0.0 && far) {
        c = shadowCoord(FAR_SHADOW_SLOT, relPos, n);
        o = uShadowOffset[FAR_SHADOW_SLOT];
        fade = 0.05;
    }
    if (c.w < 0.0) return 1.0;
    float lit = shadowTaps(c, o);
    if (fade > 0.0) lit = mix(1.0, lit, clamp(c.w / fade, 0.0, 1.0));
    return lit;
}

#endif  // AMB_SHADOW_GLSL
