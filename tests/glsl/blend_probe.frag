#version 330
// Test harness for tests/shaders/test_edges_shaders.py: evaluates sdf.glsl's blend functions themselves (not a scene) at
// inputs read from a float texture, one (a, b, k, sharpness) per texel: a and b distances (m), k a blend width (m),
// sharpness the exponential blend's (1/m, possibly +inf).

#include "sdf.glsl"

uniform sampler2D u_inputs;  // RGBA32F

layout(location = 0) out vec4 out_poly;  // smin_poly, smooth_union, smooth_subtract, smooth_intersect (poly)
layout(location = 1) out vec4 out_exp;   // smin_exp, smooth_union, smooth_subtract, smooth_intersect (exp)

void main() {
    vec4 abks = texelFetch(u_inputs, ivec2(gl_FragCoord.xy), 0);
    float a = abks.x;
    float b = abks.y;
    float k = abks.z;
    out_poly = vec4(smin_poly(a, b, k), smooth_union(a, b, k, BLEND_POLY), smooth_subtract(a, b, k, BLEND_POLY),
                    smooth_intersect(a, b, k, BLEND_POLY));
    out_exp = vec4(smin_exp(a, b, abks.w), smooth_union(a, b, k, BLEND_EXP), smooth_subtract(a, b, k, BLEND_EXP),
                   smooth_intersect(a, b, k, BLEND_EXP));
}
