#version 330
// A mesh's edges (GL_LINES) from the same pinhole camera as raymarch.frag, for the wireframe over a ray-march.

uniform mat4 u_view_projection;

in vec3 in_position;  // world (m)

out vec3 v_position;

void main() {
    v_position = in_position;
    gl_Position = u_view_projection * vec4(in_position, 1.0);
}
