// shadow.glsl — the main light's shadow (app/render/ShadowMap.h): cascaded depth maps seen from
// the light, one layer per cascade, each sphere-fitted and texel-snapped. A receiver takes the
// first cascade whose map covers it, looks up its position moved along its normal by the
// cascade's normal offset and nearer the light by its depth bias (against acne), and filters
// the comparison over PCF taps (each a bilinear 2 x 2 comparison). The last cascade fades to
// lit over its outer tenth, so the end of the shadows draws no line. The car, the one caster
// that moves, has its own small map, multiplied in where it covers. Mirrors
// amb::ShadowConstants; binding 2 (block) and texture unit 2.
#ifndef AMB_SHADOW_GLSL
#define AMB_SHADOW_GLSL

const int MAX_SHADOW_CASCADES = 4;
const int CAR_SHADOW_SLOT = MAX_SHADOW_CASCADES;

layout(std140, binding = 2) uniform ShadowConstants {
    mat4 uShadowMatrix[MAX_SHADOW_CASCADES + 1];  // camera-relative -> (u, v, depth, 1) in [0, 1]
    vec4 uShadowOffset[MAX_SHADOW_CASCADES + 1];  // x: normal offset [m]; y: depth bias; z: layer;
                                                  // w: share of the layer's side used
    vec4 uShadowParams;  // x: cascades (0: none); y: 1 / layer size; z: PCF taps per side;
                         // w: 1 with the car's own map (slot CAR_SHADOW_SLOT)
};

layout(binding = 2) uniform sampler2DArrayShadow uShadowMap;

// Light reaching relPos (normal n) through the map of slot k: 1 lit, 0 shadowed, -1 when the
// map does not cover it. `fade`: fade to lit over the outer tenth (the last cascade).
float shadowLookup(int k, vec3 relPos, vec3 n, bool fade) {
    vec3 p = (uShadowMatrix[k] * vec4(relPos + n * uShadowOffset[k].x, 1.0)).xyz;
    vec2 edge = min(p.xy, 1.0 - p.xy);
    float share = uShadowOffset[k].w;
    float margin = 2.0 * uShadowParams.y / share;
    if (min(edge.x, edge.y) < margin || p.z > 1.0) return -1.0;
    float ref = p.z - uShadowOffset[k].y;
    int taps = int(uShadowParams.z + 0.5);
    float lit = 0.0;
    float start = -0.5 * float(taps - 1);
    for (int j = 0; j < taps; ++j)
        for (int i = 0; i < taps; ++i) {
            vec2 uv = p.xy * share + vec2(start + float(i), start + float(j)) * uShadowParams.y;
            lit += texture(uShadowMap, vec4(uv, uShadowOffset[k].z, ref));
        }
    lit /= float(taps * taps);
    if (fade) lit = mix(1.0, lit, clamp((min(edge.x, edge.y) - margin) / 0.05, 0.0, 1.0));
    return lit;
}

// Fraction of the main light reaching camera-relative position `relPos` with unit normal `n`
// (1 lit, 0 in shadow): the first cascade that covers it, times the car's own map. Surfaces
// facing away from the light get no direct light anyway and skip the lookups. The cascades
// are tried with constant indices (a software rasteriser gathers dynamically indexed blocks).
float shadowFactor(vec3 relPos, vec3 n) {
    int count = int(uShadowParams.x + 0.5);
    if (count == 0 || dot(n, uLightDir.xyz) <= 0.0) return 1.0;
    float lit = shadowLookup(0, relPos, n, count == 1);
    if (lit < 0.0 && count > 1) lit = shadowLookup(1, relPos, n, count == 2);
    if (lit < 0.0 && count > 2) lit = shadowLookup(2, relPos, n, count == 3);
    if (lit < 0.0 && count > 3) lit = shadowLookup(3, relPos, n, true);
    if (lit < 0.0) lit = 1.0;
    if (uShadowParams.w > 0.5) {
        float car = shadowLookup(CAR_SHADOW_SLOT, relPos, n, false);
        if (car >= 0.0) lit *= car;
    }
    return lit;
}

#endif  // AMB_SHADOW_GLSL
