#version 330
// Samples the editor's `float sdf(vec3 p)` (and `vec3 color(vec3 p)`), which the renderer appends after this file.
// u_sample_points 0: one grid sample per pixel, for marching cubes: pixel (i, j) of a draw is sample
// (i, j mod ny, z0 + j div ny) at u_origin + u_spacing·index. 1: the points of a float texture, one per pixel
// (vertex colours, and the tests' numpy comparisons).

#include "sdf.glsl"

float sdf(vec3 p);
vec3 color(vec3 p);

uniform int u_sample_points; // 0: the grid, 1: the points of u_points
uniform vec3 u_origin;      // grid sample (0, 0, 0) (m)
uniform float u_spacing;    // between samples (m)
uniform int u_ny;           // samples along y
uniform int u_z0;           // first z slice of this draw
uniform sampler2D u_points; // RGB32F, one point (m) per texel

layout(location = 0) out float out_distance;
layout(location = 1) out vec4 out_color;

void main() {
    ivec2 ij = ivec2(gl_FragCoord.xy);
    // One program for both passes (a uniform, not a define): llvmpipe compiles a program at its first draw, which
    // costs more than the draw, and the editor pays for every program a new source needs.
    vec3 grid_point = u_origin + u_spacing * vec3(float(ij.x), float(ij.y % u_ny), float(u_z0 + ij.y / u_ny));
    vec3 p = u_sample_points == 1 ? texelFetch(u_points, ij, 0).xyz : grid_point;
    out_distance = sdf(p);
    out_color = vec4(color(p), 1.0);
}
