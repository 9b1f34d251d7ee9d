#version 330
// Phong-shaded mesh with the same lighting terms as raymarch.frag (no shadows or AO) and the same depth output.

#include "shading.glsl"

uniform vec3 u_eye;
uniform vec3 u_forward;

in vec3 v_position;
in vec3 v_normal;
in vec3 v_color;

layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;  // along u_forward (m)

void main() {
    vec3 n = normalize(v_normal);
    vec3 view_dir = normalize(u_eye - v_position);
    out_color = vec4(clamp(phong(v_color, n, view_dir, 1.0, 1.0), 0.0, 1.0), 1.0);
    out_depth = dot(v_position - u_eye, u_forward);
}
