#version 330
// Rasterises the marching-cubes mesh from the same pinhole camera as raymarch.frag.

uniform mat4 u_view_projection;

in vec3 in_position;  // world (m)
in vec3 in_normal;    // world, unit
in vec3 in_color;     // linear RGB

out vec3 v_position;
out vec3 v_normal;
out vec3 v_color;

void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_color = in_color;
    gl_Position = u_view_projection * vec4(in_position, 1.0);
}
