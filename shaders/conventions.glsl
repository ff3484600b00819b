// conventions.glsl — the GLSL twin of world/Conventions.h: pi, the Rec. 709 luminance weights
// and the albedo of the distant ground. tests/world/Conventions_test.cpp reads this file and
// checks each number against the C++ constant (kPi, kLuminanceWeights, kGroundAlbedo); change
// both together. Included by common.glsl.
#ifndef AMB_CONVENTIONS_GLSL
#define AMB_CONVENTIONS_GLSL

const float PI = 3.14159265358979323846;
const vec3 LUMINANCE_WEIGHTS = vec3(0.2126, 0.7152, 0.0722);  // Rec. 709, linear RGB
const float GROUND_ALBEDO = 0.2;  // flat Lambertian ground below the horizon

float luminance(vec3 rgb) { return dot(LUMINANCE_WEIGHTS, rgb); }

#endif  // AMB_CONVENTIONS_GLSL
