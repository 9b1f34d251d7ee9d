#version 330
// An edge's pixel over the ray-marched image: drawn unless it lies more than u_tolerance behind the marched surface
// at that pixel (the march's depth along u_forward, -1 where its ray missed).

uniform sampler2D u_depth;
uniform vec3 u_eye;
uniform vec3 u_forward;
uniform float u_tolerance;  // m: an edge's chord may sink this far under a curved surface
uniform vec3 u_color;       // linear RGB

in vec3 v_position;

layout(location = 0) out vec4 out_color;

void main() {
    float surface = texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r;
    float depth = dot(v_position - u_eye, u_forward);
    if (surface >= 0.0 && depth > surface + u_tolerance) {
        discard;
    }
    out_color = vec4(u_color, 1.0);
}
