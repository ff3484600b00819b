// shadow.glsl — the main light's shadow (app/render/ShadowMap.h): cascaded depth maps seen from
// the light, one layer per cascade, each sphere-fitted and texel-snapped. A receiver takes the
// first cascade whose map covers it, looks up its position moved along its normal by the
// cascade's normal offset and nearer the light by its depth bias (against acne), and filters
// the comparison over PCF taps (each a bilinear 2 x 2 comparison). The last cascade fades to
// lit over its outer tenth, so the end of the shadows draws no line. Mirrors
// amb::ShadowConstants; binding 2 (block) and texture unit 2.
#ifndef AMB_SHADOW_GLSL
#define AMB_SHADOW_GLSL

const int MAX_SHADOW_CASCADES = 4;

layout(std140, binding = 2) uniform ShadowConstants {
    mat4 uShadowMatrix[MAX_SHADOW_CASCADES];  // camera-relative -> (u, v, depth, 1) in [0, 1]
    vec4 uShadowOffset[MAX_SHADOW_CASCADES];  // x: normal offset [m]; y: depth bias; z: layer
    vec4 uShadowParams;  // x: cascades (0: none); y: 1 / map size; z: PCF taps per side
};

layout(binding = 2) uniform sampler2DArrayShadow uShadowMap;

// Fraction of the main light reaching camera-relative position `relPos` with unit normal `n`
// (1 lit, 0 in shadow).
float shadowFactor(vec3 relPos, vec3 n) {
    int count = int(uShadowParams.x + 0.5);
    for (int k = 0; k < count; ++k) {
        vec3 p = (uShadowMatrix[k] * vec4(relPos + n * uShadowOffset[k].x, 1.0)).xyz;
        vec2 edge = min(p.xy, 1.0 - p.xy);
        float margin = 2.0 * uShadowParams.y;
        if (min(edge.x, edge.y) < margin || p.z > 1.0) continue;
        float ref = p.z - uShadowOffset[k].y;
        int taps = int(uShadowParams.z + 0.5);
        float lit = 0.0;
        float start = -0.5 * float(taps - 1);
        for (int j = 0; j < taps; ++j)
            for (int i = 0; i < taps; ++i) {
                vec2 uv = p.xy + vec2(start + float(i), start + float(j)) * uShadowParams.y;
                lit += texture(uShadowMap, vec4(uv, uShadowOffset[k].z, ref));
            }
        lit /= float(taps * taps);
        if (k == count - 1) {  // fade to lit over the outer tenth of the last cascade
            float fade = clamp((min(edge.x, edge.y) - margin) / 0.05, 0.0, 1.0);
            lit = mix(1.0, lit, fade);
        }
        return lit;
    }
    return 1.0;
}

#endif  // AMB_SHADOW_GLSL
