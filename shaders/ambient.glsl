// ambient.glsl — the per-instance ambient slot of the object shaders: one set of the three
// Ramamoorthi-Hanrahan irradiance matrices (red, green, blue) per object (thesis 7.7: 12 float4
// per object), evaluated per pixel with the world normal by shIrradiance (sh_irradiance.glsl).
#ifndef AMB_AMBIENT_GLSL
#define AMB_AMBIENT_GLSL

#include "sh_irradiance.glsl"

struct AmbientSet {
    mat4 r, g, b;
};

layout(std430, binding = 1) readonly buffer AmbientSets {
    AmbientSet uAmbientSets[];
};

vec3 ambientIrradiance(uint set, vec3 n) {
    AmbientSet m = uAmbientSets[set];
    return shIrradiance(m.r, m.g, m.b, n);
}

#endif  // AMB_AMBIENT_GLSL
