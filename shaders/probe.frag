#version 330
// Evaluates scene_distance and scene_color at points read from a float texture, one point per pixel, so tests can
// compare the GLSL with kernels/sdf.

#include "sdf.glsl"

uniform sampler2D u_points;  // RGB32F, one world point (m) per texel

layout(location = 0) out float out_distance;
layout(location = 1) out vec4 out_color;

void main() {
    vec3 p = texelFetch(u_points, ivec2(gl_FragCoord.xy), 0).xyz;
    out_distance = scene_distance(p);
    out_color = vec4(scene_color(p), 1.0);
}
