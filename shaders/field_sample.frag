#version 330
// Samples the editor's `float sdf(vec3 p)` (and `vec3 color(vec3 p)`), which the renderer appends after this file.
// SAMPLE_POINTS 0: one grid sample per pixel, for marching cubes: pixel (i, j) of a draw is sample
// (i, j mod ny, z0 + j div ny) at u_origin + u_spacing·index. SAMPLE_POINTS 1: the points of a float texture, one
// per pixel (vertex colours, and the tests' numpy comparisons).

#include "sdf.glsl"

float sdf(vec3 p);
vec3 color(vec3 p);

#ifndef SAMPLE_POINTS
#define SAMPLE_POINTS 0
#endif

uniform vec3 u_origin;      // grid sample (0, 0, 0) (m)
uniform float u_spacing;    // between samples (m)
uniform int u_ny;           // samples along y
uniform int u_z0;           // first z slice of this draw
uniform sampler2D u_points; // RGB32F, one point (m) per texel

layout(location = 0) out float out_distance;
layout(location = 1) out vec4 out_color;

void main() {
    ivec2 ij = ivec2(gl_FragCoord.xy);
#if SAMPLE_POINTS
    vec3 p = texelFetch(u_points, ij, 0).xyz;
    out_color = vec4(color(p), 1.0);
#else
    vec3 p = u_origin + u_spacing * vec3(float(ij.x), float(ij.y % u_ny), float(u_z0 + ij.y / u_ny));
    out_color = vec4(0.0);
#endif
    out_distance = sdf(p);
}
