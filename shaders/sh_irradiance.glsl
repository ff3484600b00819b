// sh_irradiance.glsl — irradiance from order-2 SH (Ramamoorthi & Hanrahan 2001; thesis 7.7, 9.4).
//
//   vec3 shIrradiance(mat4 Mr, mat4 Mg, mat4 Mb, vec3 n)
//     Mr, Mg, Mb: the symmetric 4x4 irradiance matrices of the red, green and blue channels, as
//                 made by amb::shIrradianceMatrices (lighting/SH.h); column-major, as uploaded
//                 with glUniformMatrix4fv(..., GL_FALSE, ...) from a glm::mat4.
//     n:          unit world-space normal.
//     returns     E(n) = (n,1)^T M (n,1) per channel, in the radiance units of the coefficients
//                 times steradians. Not clamped: the caller decides what to do with ringing.
//
// Include it with `#extension GL_GOOGLE_include_directive : require` and `#include
// "sh_irradiance.glsl"` (resolved by the shader loader or glslangValidator -I). This file is
// written in the common subset of GLSL and C++ with GLM: the C++ tests include it with GLM's
// vec3, vec4, mat4 and dot in scope and compare it with amb::shIrradiance.
#ifndef AMB_SH_IRRADIANCE_GLSL
#define AMB_SH_IRRADIANCE_GLSL

vec3 shIrradiance(mat4 Mr, mat4 Mg, mat4 Mb, vec3 n) {
    vec4 n4 = vec4(n, 1.0);
    return vec3(dot(n4, Mr * n4), dot(n4, Mg * n4), dot(n4, Mb * n4));
}

#endif  // AMB_SH_IRRADIANCE_GLSL
